//! Wavefront OBJ loader (via tobj). Each OBJ model becomes one mesh with one primitive and
//! one identity instance; the colour is the `.mtl` diffuse colour if available.

use std::path::Path;

use glam::{DVec3, Mat4};

use crate::error::SceneError;
use crate::scene::{recentre_origin, Instance, LoadProgress, Mesh, Primitive, Scene, DEFAULT_BASE_COLOR};

pub fn load_obj(path: &Path, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    // tobj reports a missing file only as "open file failed"; give the real io error.
    if let Err(source) = std::fs::metadata(path) {
        return Err(SceneError::Io {
            path: path.to_path_buf(),
            source,
        });
    }
    // `..Default::default()` keeps this compiling if tobj's optional features add fields.
    #[allow(clippy::needless_update)]
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, materials) = tobj::load_obj(path, &opts).map_err(|e| SceneError::Obj {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let materials = match materials {
        Ok(m) => m,
        Err(e) => {
            log::warn!(
                "{}: materials unavailable ({e}); using default colour",
                path.display()
            );
            Vec::new()
        }
    };
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut scene = Scene::new(name);
    // Positions are parsed in f64 (tobj's use_f64); far from the file's origin they are re-centred.
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for m in &models {
        for c in m.mesh.positions.chunks_exact(3) {
            let p = DVec3::new(c[0], c[1], c[2]);
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    let origin = if lo.x <= hi.x {
        recentre_origin((lo + hi) * 0.5)
    } else {
        DVec3::ZERO
    };
    scene.origin = origin.to_array();
    let total = models.len() as u64;
    for (mi, model) in models.into_iter().enumerate() {
        let m = model.mesh;
        if m.positions.len() % 3 != 0 {
            return Err(SceneError::Obj {
                path: path.to_path_buf(),
                message: format!("model {mi} ({}): position array is not xyz triples", model.name),
            });
        }
        let positions: Vec<[f32; 3]> = m
            .positions
            .chunks_exact(3)
            .map(|c| (DVec3::new(c[0], c[1], c[2]) - origin).as_vec3().to_array())
            .collect();
        let base_color = m
            .material_id
            .and_then(|id| materials.get(id))
            .and_then(|mat| mat.diffuse)
            .map(|d| [d[0] as f32, d[1] as f32, d[2] as f32, 1.0])
            .unwrap_or(DEFAULT_BASE_COLOR);
        let mesh_id = scene.meshes.len() as u32;
        scene.meshes.push(Mesh {
            name: model.name.clone(),
            primitives: vec![Primitive {
                positions,
                indices: m.indices,
                base_color,
            }],
        });
        scene.instances.push(Instance {
            mesh: mesh_id,
            transform: Mat4::IDENTITY,
            name: model.name,
            visible: true,
        });
        progress(LoadProgress {
            stage: "meshes",
            done: mi as u64 + 1,
            total,
        });
    }
    Ok(scene)
}
