//! Instanced scenes for hrtao: glTF/OBJ loading, procedural CAD-like generators and
//! scene edits that bump the animation frame identifier `F`.
//!
//! Loaded scenes keep the file's own units and up-axis (no conversion). Generated scenes
//! are in metres, Z-up.

mod aabb;
pub mod cad;
// Built without `occt` too: the IFC worker shares the worker process and the scene building.
#[cfg_attr(not(feature = "occt"), allow(dead_code))]
mod cad_header;
#[cfg_attr(not(feature = "occt"), allow(dead_code))]
mod cad_load;
mod error;
mod generate;
mod gltf_compressed;
mod gltf_load;
mod guard;
#[cfg(feature = "hostile-corpus")]
pub mod hostile;
mod ifc_load;
pub mod normals;
mod obj_groups;
mod obj_load;
mod ply_load;
mod scene;
mod stl_load;
mod threemf_colors;
mod threemf_load;
mod tree;
mod up;

use std::path::Path;

pub use glam;

pub use aabb::Aabb;
pub use error::SceneError;
pub use generate::{box_corners, box_triangles, BOX_FACES, MAX_INSTANCES, MAX_MESH_TRIANGLES};
pub use guard::{default_max_memory, CadFormat, CadOptions, CadTessellation, LoadOptions};
pub use ifc_load::{default_venv, ifc_python, install_command as ifc_install_command, IFCOPENSHELL_VERSION};
pub use scene::{
    Instance, LoadProgress, Mesh, Primitive, Scene, Storey, DEFAULT_BASE_COLOR, EXACT_BOUNDS_VERTEX_BUDGET,
};
pub use tree::{Node, NodeTree};
pub use up::UpAxis;

/// Loads a glTF 2.0 file (`.gltf` or `.glb`), validated and non-empty, with the default [`LoadOptions`].
pub fn load_gltf(path: &Path, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    finish(
        gltf_load::load_gltf(path, &LoadOptions::default(), progress)?,
        &path.display().to_string(),
    )
}

/// Loads a Wavefront OBJ file (materials from its `.mtl` if present), validated and non-empty, with
/// the default [`LoadOptions`].
pub fn load_obj(path: &Path, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    finish(
        obj_load::load_obj(path, &LoadOptions::default(), progress)?,
        &path.display().to_string(),
    )
}

/// Builds a procedural scene from a `gen:NAME?key=value&...` spec; validated and non-empty.
///
/// All generators are in metres, **Z-up**, ground at z = 0:
///
/// | spec | parameters (default) |
/// |---|---|
/// | `gen:racks` | `rows` (25), `cols` (100), `units` (40), `detail` (2000 = triangles per server mesh) |
/// | `gen:city` | `blocks` (8, per side), `per_block` (3, buildings per side), `variants` (6), `floors` (30), `seed` (1) |
/// | `gen:box` | `size` (2): closed-top box open towards −Y |
/// | `gen:plane` | `size` (100): one quad |
/// | `gen:slab` | `h` (1), `size` (10), `ground` (100): ground quad plus a 0.1 m slab at height `h` |
///
/// Unknown/repeated keys, non-numeric, negative or out-of-range values, more than
/// [`MAX_INSTANCES`] instances or more than [`MAX_MESH_TRIANGLES`] triangles in a mesh are
/// [`SceneError::BadGeneratorParam`]; unknown names are [`SceneError::UnknownGenerator`].
pub fn generate(spec: &str, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    finish(generate::generate(spec, progress)?, spec)
}

/// The extensions [`load_with`] reads (lower case; any case is accepted).
pub const SUPPORTED_EXTENSIONS: [&str; 11] = [
    "gltf", "glb", "obj", "stl", "ply", "3mf", "step", "stp", "iges", "igs", "ifc",
];

static DEFAULT_CAD_TESSELLATION: std::sync::RwLock<Option<CadTessellation>> = std::sync::RwLock::new(None);
static DEFAULT_CAD_WORKER: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();

/// Sets the binary whose `occt-worker` subcommand reads STEP/IGES for loads whose [`LoadOptions`] name none:
/// `hrtao` passes its own executable. The first call wins.
pub fn set_default_cad_worker(path: std::path::PathBuf) {
    let _ = DEFAULT_CAD_WORKER.set(path);
}

pub(crate) fn default_cad_worker() -> Option<std::path::PathBuf> {
    DEFAULT_CAD_WORKER.get().cloned()
}

/// Sets the STEP/IGES tessellation of loads made from now on with default [`LoadOptions`] (the command line's
/// `--deflection`/`--angular-deflection`).
pub fn set_default_cad_tessellation(t: CadTessellation) {
    *DEFAULT_CAD_TESSELLATION
        .write()
        .unwrap_or_else(|e| e.into_inner()) = Some(t);
}

/// The tessellation [`set_default_cad_tessellation`] set, if it was called.
pub fn command_line_cad_tessellation() -> Option<CadTessellation> {
    *DEFAULT_CAD_TESSELLATION.read().unwrap_or_else(|e| e.into_inner())
}

pub(crate) fn default_cad_tessellation() -> CadTessellation {
    DEFAULT_CAD_TESSELLATION
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .unwrap_or_default()
}

/// Loads a scene from `gen:...`, `*.gltf`, `*.glb` or `*.obj` with the default [`LoadOptions`].
pub fn load(path_or_spec: &str, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    load_with(path_or_spec, &LoadOptions::default(), progress)
}

/// Loads a scene from `gen:...`, `*.gltf`, `*.glb`, `*.obj`, `*.stl`, `*.ply`, `*.3mf`, `*.step`/`*.stp`,
/// `*.iges`/`*.igs` or `*.ifc` (any case; STEP and IGES through OpenCASCADE in a worker process, with the `occt`
/// feature; IFC through IfcOpenShell in a Python worker process);
/// `opts` can cancel the load from another
/// thread and bounds its memory. Files and their references are read through a guard: references stay
/// inside the model's folder, only regular files of the declared size are read (never devices, FIFOs,
/// directories or sockets), and every read is bounded (see docs/reliability.md).
pub fn load_with(
    path_or_spec: &str,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    if path_or_spec.starts_with("gen:") {
        return generate(path_or_spec, progress);
    }
    let path = Path::new(path_or_spec);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let scene = match ext.as_str() {
        "gltf" | "glb" => gltf_load::load_gltf(path, opts, progress)?,
        "obj" => obj_load::load_obj(path, opts, progress)?,
        "stl" => stl_load::load_stl(path, opts, progress)?,
        "ply" => ply_load::load_ply(path, opts, progress)?,
        "3mf" => threemf_load::load_3mf(path, opts, progress)?,
        "step" | "stp" | "iges" | "igs" => {
            let format = if ext.starts_with('s') {
                CadFormat::Step
            } else {
                CadFormat::Iges
            };
            load_cad(path, format, opts, progress)?
        }
        "ifc" => ifc_load::load_ifc(path, opts, progress)?,
        _ => {
            return Err(SceneError::UnsupportedFormat(format!(
                "{path_or_spec}: expected .gltf, .glb, .obj, .stl, .ply, .3mf, .step, .stp, .iges, .igs, .ifc or gen:..."
            )))
        }
    };
    finish(scene, path_or_spec)
}

#[cfg(feature = "occt")]
fn load_cad(
    path: &Path,
    format: CadFormat,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    cad_load::load_cad(path, format, opts, progress)
}

#[cfg(not(feature = "occt"))]
fn load_cad(
    path: &Path,
    format: CadFormat,
    _opts: &LoadOptions,
    _progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    Err(SceneError::UnsupportedFormat(format!(
        "{}: {} files are read through OpenCASCADE, which this build leaves out: rebuild with the `occt` \
         feature (on by default: `cargo build --release`, or `--features occt`) after scripts/install-deps.sh",
        path.display(),
        format.name()
    )))
}

/// Validates and rejects scenes without any triangle; errors name the source.
fn finish(mut scene: Scene, source: &str) -> Result<Scene, SceneError> {
    // Unusable shading normals fall back to face normals, with one warning per load.
    let mut bad = 0usize;
    let mut first = None;
    for (mi, mesh) in scene.meshes.iter_mut().enumerate() {
        for (pi, prim) in mesh.primitives.iter_mut().enumerate() {
            if let Some(why) = prim.check_normals() {
                bad += 1;
                first.get_or_insert(format!("mesh {mi} ({}) primitive {pi}: {why}", mesh.name));
            }
        }
    }
    if let Some(first) = first {
        log::warn!("{source}: {bad} primitive(s) shade flat, their normals are unusable (first: {first})");
    }
    scene.validate().map_err(|e| match e {
        SceneError::Invalid(m) => SceneError::Invalid(format!("{source}: {m}")),
        other => other,
    })?;
    if scene.tree.is_empty() {
        scene.tree = NodeTree::single(scene.name.clone(), scene.instances.len());
    }
    if scene.unique_triangle_count() == 0 {
        return Err(SceneError::Empty(format!("scene {source} has no triangles")));
    }
    if scene.instances.is_empty() {
        return Err(SceneError::Empty(format!(
            "scene {source} places no mesh: it has no node with a mesh (or only nodes with singular transforms)"
        )));
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without the `occt` feature a STEP file is an error saying how to enable it; with it and no worker to run,
    /// an error saying so (never a panic).
    #[test]
    fn step_without_the_kernel_is_a_clear_error() {
        let dir = std::env::temp_dir().join(format!("hrtao-scene-step-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("part.STP");
        std::fs::write(
            &p,
            "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A();\nENDSEC;\nEND-ISO-10303-21;\n",
        )
        .unwrap();
        let mut opts = LoadOptions::default();
        opts.cad.worker = None;
        let e = load_with(p.to_str().unwrap(), &opts, &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("part.STP"), "{e}");
        if cfg!(feature = "occt") {
            assert!(e.contains("no OpenCASCADE worker"), "{e}");
        } else {
            assert!(e.contains("`occt` feature"), "{e}");
        }
        let _ = std::fs::remove_dir_all(dir);
    }
}
