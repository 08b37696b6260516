//! STEP and IGES through OpenCASCADE (OCCT), the B-rep kernel FreeCAD, KiCad, gmsh and F3D use.
//!
//! The binding is a small C++ bridge of our own (`src/bridge.cpp`, the only C++ in the project) compiled
//! with `cc` and called through a plain C ABI (`src/bridge.h`). Why `cc` and not `cxx` or an existing crate:
//! - the bridge needs four entry points with plain data (paths, float/index arrays, callbacks), so `cxx`'s
//!   generated glue and its extra build-time crates buy nothing, and a C ABI keeps the C++ side a single
//!   translation unit that compiles once against the heavy OCCT headers;
//! - the crates that wrap OCCT (`opencascade-sys`) build OCCT from source (not an option on 2 cores) and do
//!   not expose XCAF (assembly structure, names, colours), which is the point here;
//! - the bridge catches every C++ exception and returns it as an error string, so no exception crosses
//!   into Rust.
//!
//! The kernel is run only in a worker process (see the viewer's `occt-worker` subcommand): a crash or
//! endless loop inside OCCT must not take the viewer down.
//!
//! [`read`] returns each unique part tessellated once ([`Part`]) and the product structure in pre-order
//! ([`Node`]): every occurrence of a part is a node referring to the same part. In IGES an occurrence is shared
//! when the file says so with subfigures (a definition, entity 308, placed by instances, 408); a file without them
//! (OCCT's own IGES writer and many exporters write every occurrence as a copy) has nothing to share.

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::Path;

mod ffi {
    use super::*;

    #[repr(C)]
    pub struct Callbacks {
        pub ctx: *mut c_void,
        pub progress: extern "C" fn(*mut c_void, f64, *const c_char) -> c_int,
        pub part: extern "C" fn(*mut c_void, i32, *const c_char),
        pub primitive: extern "C" fn(
            *mut c_void,
            i32,
            *const f32,
            *const f32,
            usize,
            *const u32,
            usize,
            *const f32,
            i32,
        ),
        pub node: extern "C" fn(*mut c_void, i32, *const c_char, i32, *const f64, *const f32, i32) -> i32,
    }

    #[repr(C)]
    pub struct Tessellation {
        pub relative: f64,
        pub absolute: f64,
        pub angular: f64,
    }

    #[repr(C)]
    #[derive(Default)]
    pub struct Units {
        pub model_m: f64,
        pub file_m: f64,
    }

    extern "C" {
        pub fn hr_read(
            path: *const c_char,
            format: i32,
            tess: *const Tessellation,
            cb: *const Callbacks,
            units: *mut Units,
            err: *mut c_char,
            err_len: usize,
        ) -> c_int;
        pub fn hr_write_test(
            path: *const c_char,
            format: i32,
            kind: i32,
            count: i32,
            err: *mut c_char,
            err_len: usize,
        ) -> c_int;
    }
}

/// The exchange format of a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Step,
    Iges,
}

impl Format {
    /// By extension (`.step`, `.stp`, `.iges`, `.igs`, any case).
    pub fn of_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
        match ext.as_str() {
            "step" | "stp" => Some(Format::Step),
            "iges" | "igs" => Some(Format::Iges),
            _ => None,
        }
    }
}

/// How finely parts are tessellated (`BRepMesh_IncrementalMesh`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tessellation {
    /// Linear deflection as a fraction of each part's bounding-box diagonal; 0 uses `absolute`.
    pub relative: f64,
    /// Linear deflection in millimetres, used when `relative` is 0 (F3D's way).
    pub absolute: f64,
    /// Angular deflection in radians.
    pub angular: f64,
}

impl Default for Tessellation {
    /// 0.5 % of each part's size and 35°, the loader's default (`hrtao_scene::CadTessellation`): the surface
    /// normals handed back with the nodes shade curved faces smoothly, so the triangles need only keep
    /// silhouettes and AO true.
    fn default() -> Self {
        Tessellation {
            relative: 5e-3,
            absolute: 0.0,
            angular: 35f64.to_radians(),
        }
    }
}

pub use hrtao_scene::cad::{CadModel as Model, CadNode as Node, CadPart as Part, CadPrimitive as Primitive};

/// Why a read failed.
#[derive(thiserror::Error, Debug)]
pub enum Error {
    #[error("{0}")]
    Kernel(String),
    #[error("stopped")]
    Stopped,
}

struct Ctx<'a> {
    model: Model,
    progress: &'a mut dyn FnMut(&str, f64) -> bool,
    bad: Option<String>,
}

fn cstr(p: *const c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    // SAFETY: the bridge passes NUL-terminated strings valid for the call.
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

fn rgba(p: *const f32) -> Option<[f32; 4]> {
    // SAFETY: non-null colour pointers point at 4 floats.
    (!p.is_null()).then(|| unsafe { *(p as *const [f32; 4]) })
}

extern "C" fn on_progress(ctx: *mut c_void, f: f64, stage: *const c_char) -> c_int {
    // SAFETY: ctx is the &mut Ctx passed to hr_read, alive for the call.
    let ctx = unsafe { &mut *(ctx as *mut Ctx) };
    let stage = cstr(stage);
    c_int::from((ctx.progress)(&stage, f))
}

extern "C" fn on_part(ctx: *mut c_void, id: i32, name: *const c_char) {
    // SAFETY: as above.
    let ctx = unsafe { &mut *(ctx as *mut Ctx) };
    if id as usize != ctx.model.parts.len() {
        ctx.bad = Some(format!("part {id} out of order"));
    }
    ctx.model.parts.push(Part {
        name: cstr(name),
        primitives: Vec::new(),
    });
}

/// The `n` items at `p` (none when `n` is 0, where an empty C++ vector's pointer may be null).
///
/// # Safety
/// `p` points at `n` valid items when `n` > 0.
unsafe fn copied<T: Copy>(p: *const T, n: usize) -> Vec<T> {
    if n == 0 || p.is_null() {
        return Vec::new();
    }
    // SAFETY: the caller's promise.
    unsafe { std::slice::from_raw_parts(p, n) }.to_vec()
}

#[allow(clippy::too_many_arguments)]
extern "C" fn on_primitive(
    ctx: *mut c_void,
    part: i32,
    pos: *const f32,
    nrm: *const f32,
    nverts: usize,
    idx: *const u32,
    nidx: usize,
    color: *const f32,
    face: i32,
) {
    // SAFETY: as above; the arrays hold nverts*3 floats (positions, normals) and nidx indices.
    let ctx = unsafe { &mut *(ctx as *mut Ctx) };
    let positions = unsafe { copied(pos as *const [f32; 3], nverts) };
    let normals = unsafe { copied(nrm as *const [f32; 3], nverts) };
    let indices = unsafe { copied(idx, nidx) };
    match ctx.model.parts.get_mut(part as usize) {
        Some(p) => p.primitives.push(
            Primitive::new(positions, indices)
                .with_normals(normals)
                .with_color(rgba(color), face != 0),
        ),
        None => ctx.bad = Some(format!("primitive of unknown part {part}")),
    }
}

extern "C" fn on_node(
    ctx: *mut c_void,
    parent: i32,
    name: *const c_char,
    part: i32,
    world: *const f64,
    color: *const f32,
    visible: i32,
) -> i32 {
    // SAFETY: as above; world points at 16 doubles.
    let ctx = unsafe { &mut *(ctx as *mut Ctx) };
    let world = unsafe { *(world as *const [f64; 16]) };
    let id = ctx.model.nodes.len() as i32;
    ctx.model.nodes.push(Node {
        name: cstr(name),
        parent: u32::try_from(parent).ok(),
        part: u32::try_from(part).ok(),
        world,
        color: rgba(color),
        visible: visible != 0,
    });
    id
}

/// OCCT's data exchange keeps process-wide state (the `Interface_Static` parameters its STEP and IGES readers and
/// writers set and read, the shared XCAF application), so two calls at once on two threads can crash the
/// process: every call into the kernel holds this lock. The viewer runs one read per worker process anyway.
static KERNEL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn kernel_lock() -> std::sync::MutexGuard<'static, ()> {
    // A panic in a callback leaves nothing half-written on our side: the lock stays usable.
    KERNEL.lock().unwrap_or_else(|e| e.into_inner())
}

fn c_path(path: &Path) -> Result<CString, Error> {
    use std::os::unix::ffi::OsStrExt;
    CString::new(path.as_os_str().as_bytes())
        .map_err(|_| Error::Kernel(format!("{}: a path with a NUL byte", path.display())))
}

/// Reads a STEP or IGES file, tessellating each unique part once. `progress(stage, fraction)` returning
/// `true` stops the kernel (OCCT's user break) with [`Error::Stopped`].
pub fn read(
    path: &Path,
    format: Format,
    tess: &Tessellation,
    progress: &mut dyn FnMut(&str, f64) -> bool,
) -> Result<Model, Error> {
    let cpath = c_path(path)?;
    let mut ctx = Ctx {
        model: Model::default(),
        progress,
        bad: None,
    };
    let cb = ffi::Callbacks {
        ctx: &mut ctx as *mut Ctx as *mut c_void,
        progress: on_progress,
        part: on_part,
        primitive: on_primitive,
        node: on_node,
    };
    let t = ffi::Tessellation {
        relative: tess.relative,
        absolute: tess.absolute,
        angular: tess.angular,
    };
    let mut units = ffi::Units::default();
    let mut err = vec![0 as c_char; 2048];
    let _kernel = kernel_lock();
    // SAFETY: every pointer is valid for the call; the callbacks only touch ctx.
    let rc = unsafe {
        ffi::hr_read(
            cpath.as_ptr(),
            matches!(format, Format::Iges) as i32,
            &t,
            &cb,
            &mut units,
            err.as_mut_ptr(),
            err.len(),
        )
    };
    match rc {
        0 => {}
        2 => return Err(Error::Stopped),
        _ => return Err(Error::Kernel(cstr(err.as_ptr()))),
    }
    if let Some(bad) = ctx.bad {
        return Err(Error::Kernel(bad));
    }
    let mut model = ctx.model;
    model.model_unit_m = units.model_m;
    model.file_unit_m = (units.file_m > 0.0 && units.file_m.is_finite()).then_some(units.file_m);
    Ok(model)
}

/// Small models written by OCCT itself, for tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TestModel {
    /// Three boxes as separate free shapes.
    Boxes,
    /// One bolt shape placed `n` times on a plate, in one assembly.
    BoltPattern(u32),
    /// Part, face and occurrence colours, and a hidden occurrence.
    Coloured,
    /// `n` separate box solids in one shape.
    ManySolids(u32),
    /// The bolt pattern of `n` bolts as a sub-assembly placed twice ("left" and "right", 200 mm apart) in an
    /// assembly "two_patterns".
    BoltPatternPair(u32),
    /// A cylinder "cylinder" (radius 10 mm, height 20 mm, axis z from the origin) placed twice in an assembly
    /// "cylinders": "upright" where it is, "upside_down" turned 180° about x and moved to (50, 0, 20).
    Cylinder,
}

/// Writes a [`TestModel`] as STEP or IGES (tests only), with OCCT's writers. OCCT's IGES writer keeps no
/// sharing: every occurrence of a part is written as a copy of its geometry (see [`write_test_model_subfigures`]).
pub fn write_test_model(path: &Path, format: Format, model: TestModel) -> Result<(), Error> {
    write_test(path, matches!(format, Format::Iges) as i32, model)
}

/// Writes a [`TestModel`] as IGES with subfigures (tests only), the way IGES states that a part is placed several
/// times: every part is a subfigure definition (entity 308) of its geometry, every assembly a 308 of instances (408)
/// of its components, with names, colours (occurrence, part, face) and hidden occurrences (blank status). A part
/// placed once where its assembly is, with nothing of its own, is written inline in the assembly's 308.
pub fn write_test_model_subfigures(path: &Path, model: TestModel) -> Result<(), Error> {
    write_test(path, 2, model)
}

fn write_test(path: &Path, format: i32, model: TestModel) -> Result<(), Error> {
    let cpath = c_path(path)?;
    let (kind, count) = match model {
        TestModel::Boxes => (0, 0),
        TestModel::BoltPattern(n) => (1, n),
        TestModel::Coloured => (2, 0),
        TestModel::ManySolids(n) => (3, n),
        TestModel::BoltPatternPair(n) => (4, n),
        TestModel::Cylinder => (5, 0),
    };
    let mut err = vec![0 as c_char; 2048];
    let _kernel = kernel_lock();
    // SAFETY: valid pointers for the call.
    let rc = unsafe {
        ffi::hr_write_test(
            cpath.as_ptr(),
            format,
            kind,
            count.min(i32::MAX as u32) as i32,
            err.as_mut_ptr(),
            err.len(),
        )
    };
    if rc == 0 {
        Ok(())
    } else {
        Err(Error::Kernel(cstr(err.as_ptr())))
    }
}

/// Checks for tests of this crate and of the loader on [`TestModel::Cylinder`] (tests only).
pub mod testing {
    /// The kernel's normals on a cylinder (radius 10, height 20, axis z) in the part's coordinates: each triangle is
    /// a side triangle (its face normal across the axis) or a cap triangle; side vertices get the radial direction,
    /// cap vertices the axis out of the solid (-z at the bottom, +z at the top, one of the caps a reversed face), and
    /// every vertex normal lies on the side its triangle winds toward. Returns (side, cap) vertices checked.
    pub fn check_cylinder_normals(
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        indices: &[u32],
    ) -> (usize, usize) {
        assert_eq!(normals.len(), positions.len(), "one normal per vertex");
        let v = |a: [f32; 3]| [a[0] as f64, a[1] as f64, a[2] as f64];
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let (mut side, mut cap) = (0, 0);
        for t in indices.chunks(3) {
            let p: Vec<[f64; 3]> = t.iter().map(|&i| v(positions[i as usize])).collect();
            let face = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            let len = dot(face, face).sqrt();
            assert!(len > 0.0, "a degenerate triangle");
            let is_cap = face[2].abs() / len > 0.99;
            for (k, &i) in t.iter().enumerate() {
                let n = v(normals[i as usize]);
                assert!((dot(n, n).sqrt() - 1.0).abs() < 1e-5, "unit length: {n:?}");
                assert!(
                    dot(n, face) > 0.0,
                    "normal {n:?} against its triangle's winding {face:?}"
                );
                let want = if is_cap {
                    let z = p[k][2];
                    assert!(z.abs() < 1e-6 || (z - 20.0).abs() < 1e-6, "a cap vertex at z {z}");
                    [0.0, 0.0, if z < 10.0 { -1.0 } else { 1.0 }]
                } else {
                    let r = (p[k][0] * p[k][0] + p[k][1] * p[k][1]).sqrt();
                    assert!((r - 10.0).abs() < 1e-4, "a side vertex at radius {r}");
                    [p[k][0] / r, p[k][1] / r, 0.0]
                };
                assert!(
                    dot(n, want) > 0.9999,
                    "{} vertex {:?}: normal {n:?}, want {want:?}",
                    if is_cap { "cap" } else { "side" },
                    p[k]
                );
                if is_cap {
                    cap += 1;
                } else {
                    side += 1;
                }
            }
        }
        (side, cap)
    }
}
