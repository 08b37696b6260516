//! Wavefront OBJ loader (via tobj). Each OBJ model becomes one mesh with one primitive and
//! one identity instance; the colour is the `.mtl` diffuse colour if available.
//!
//! Shading normals: a model whose every face corner has a `vn` keeps them (tobj's `single_index` gives one
//! normal per vertex, lined up with the positions); a model without `vn` gets smooth normals by the load's crease
//! angle ([`crate::normals::smooth`]). tobj drops the missing normals of a model whose faces mix corners with and
//! without `vn` (what is left no longer lines up with the positions): such a model is smoothed whole, with a
//! warning.

use std::cell::RefCell;
use std::path::Path;

use glam::{DVec3, Mat4};

use crate::error::SceneError;
use crate::guard::{read_model, resolve_reference, Budget, Fetch, LoadOptions, Target};
use crate::obj_groups::TaggedObj;
use crate::scene::{recentre_origin, Instance, LoadProgress, Mesh, Primitive, Scene, DEFAULT_BASE_COLOR};

pub fn load_obj(
    path: &Path,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    let (text, mut budget) = read_model(path, opts, progress)?;
    budget.reserve(declared_bytes(&text), "the declared geometry (v and f lines)")?;
    budget.reserve(
        text.len() as u64,
        "the object and group names (a tagged copy of the file)",
    )?;
    opts.check_cancel(path)?;
    let mut tagged = TaggedObj::new(&text);
    drop(text);
    // `..Default::default()` keeps this compiling if tobj's optional features add fields.
    #[allow(clippy::needless_update)]
    let load_opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // tobj's material loader is `Fn` and its error type has no message: keep ours aside.
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
    let budget = RefCell::new(budget);
    let load_mtl = |name: &Path| -> tobj::MTLLoadResult {
        match read_mtl(path, name, opts, &mut budget.borrow_mut()) {
            Ok(r) => r,
            Err(MtlError::Missing(message)) => {
                log::warn!("{}: {message}; using the default colour", path.display());
                Err(tobj::LoadError::OpenFileFailed)
            }
            Err(MtlError::Refused(e)) => {
                mtl_error.borrow_mut().get_or_insert(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    let parsed = tobj::load_obj_buf(&mut tagged.text.as_slice(), &load_opts, load_mtl);
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, materials) = parsed.map_err(|e| SceneError::Obj {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    tagged.text = Vec::new();
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
        opts.check_cancel(path)?;
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
        let mut prim = Primitive::new(positions, m.indices, base_color);
        if !m.normals.is_empty() && m.normals.len() != m.positions.len() {
            log::warn!(
                "{}: model {mi} ({}): {} of its {} vertices have a `vn`; smoothing the whole model instead",
                path.display(),
                model.name,
                m.normals.len() / 3,
                m.positions.len() / 3
            );
        }
        if m.normals.len() == m.positions.len() {
            prim.normals = m
                .normals
                .chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                .collect();
        } else {
            if opts.crease_deg.is_some() {
                budget.borrow_mut().reserve(
                    prim.triangle_count()
                        .saturating_mul(crate::normals::SMOOTH_BYTES_PER_TRIANGLE),
                    "smoothing the normals",
                )?;
            }
            crate::normals::smooth_primitive(&mut prim, opts.crease_deg, path)?;
        }
        let mesh_id = scene.meshes.len() as u32;
        let (node, name) = tagged.node_of(&model.name);
        tagged.tree.nodes[node as usize]
            .instances
            .push(scene.instances.len() as u32);
        scene.meshes.push(Mesh {
            name: name.clone(),
            primitives: vec![prim],
        });
        scene.instances.push(Instance {
            mesh: mesh_id,
            transform: Mat4::IDENTITY,
            name,
            visible: true,
        });
        progress(LoadProgress {
            stage: "meshes",
            done: mi as u64 + 1,
            total,
        });
    }
    scene.tree = tagged.tree;
    scene.tree.prune_empty();
    Ok(scene)
}

enum MtlError {
    /// The `.mtl` does not exist: a warning, the model loads with the default colour.
    Missing(String),
    /// The `mtllib` points outside the folder, at a device, FIFO, directory, ...: an error.
    Refused(SceneError),
}

/// Reads an `mtllib` through the guard (inside the OBJ's folder, a regular file, within the budget).
fn read_mtl(
    obj: &Path,
    name: &Path,
    opts: &LoadOptions,
    budget: &mut Budget,
) -> Result<tobj::MTLLoadResult, MtlError> {
    let uri = name.to_string_lossy();
    let file = resolve_reference(obj, name, &uri).map_err(MtlError::Refused)?;
    if std::fs::symlink_metadata(&file).is_err() {
        return Err(MtlError::Missing(format!("mtllib `{uri}` does not exist")));
    }
    let bytes = Fetch {
        model: obj,
        target: Target::Reference(&uri),
        declared: None,
    }
    .read(&file, opts, budget, &mut |_| {})
    .map_err(MtlError::Refused)?;
    Ok(tobj::load_mtl_buf(&mut bytes.as_slice()))
}

/// Memory of one object/group header: its model tree node and name lookup entry (obj_groups.rs).
const HEADER_BYTES: u64 = std::mem::size_of::<crate::tree::Node>() as u64 * 2 + 64;

/// Memory tobj and this loader will take for the OBJ, from the counts its lines declare: `v`/`vn`/`vt`
/// arrays, and per face corner an output vertex (position, normal, texcoord, our copy) plus the
/// triangulated indices (face lists and the final list), and per `o`/`g` line a model tree node.
fn declared_bytes(text: &[u8]) -> u64 {
    let (mut v, mut vn, mut vt, mut corners, mut tri, mut headers) = (0u64, 0u64, 0u64, 0u64, 0u64, 0u64);
    for line in text.split(|&b| b == b'\n') {
        let mut words = line.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => v += 1,
            Some(b"vn") => vn += 1,
            Some(b"vt") => vt += 1,
            Some(b"o" | b"g") => headers += 1,
            Some(b"f") => {
                let k = words.count() as u64;
                corners += k;
                tri += k.saturating_sub(2) * 3;
            }
            _ => {}
        }
    }
    v * 12 + vn * 12 + vt * 8 + corners * (12 + 12 + 8 + 12) + tri * 4 * 2 + headers * HEADER_BYTES
}
