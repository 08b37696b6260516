//! Guarded reading of a model file and of every file it references (glTF buffers, OBJ `mtllib`).
//!
//! A model is often a file someone sent; its references can point anywhere. Before anything is read:
//! - a reference must stay inside the model's own folder (or its subfolders): absolute paths, `file://`
//!   URIs and `..` that leave the folder are refused ([`resolve_reference`]);
//! - the path is opened with `O_NONBLOCK` (a FIFO cannot hang the open), and the *opened handle* is
//!   checked with `fstat` to be a regular file (devices, FIFOs, directories and sockets are refused, even
//!   behind a symlink or if the path was swapped after a check);
//! - the size is checked against what the model declares (glTF `byteLength`) and against the scene
//!   memory budget ([`Budget`]) before the buffer is allocated;
//! - at most that many bytes are read, in chunks, with the cancel flag checked between chunks.

use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::error::SceneError;
use crate::scene::LoadProgress;

/// Bytes read between two checks of the cancel flag (and two progress reports).
const CHUNK: usize = 4 << 20;

/// How a load is controlled from outside: cancellation and the memory limit.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Set to `true` from any thread to stop the load: it returns [`SceneError::Cancelled`] at the next
    /// chunk read or mesh decoded (within milliseconds).
    pub cancel: Arc<AtomicBool>,
    /// Bytes the scene may take in memory: file bytes read, external buffers, decoded geometry and
    /// instances, estimated from the counts the file declares *before* allocating
    /// ([`SceneError::TooLarge`] otherwise). The model file itself may not be larger either.
    pub max_memory: u64,
    /// STEP and IGES: the kernel's worker process and the tessellation.
    pub cad: CadOptions,
    /// Meshes without normals of their own (STL; OBJ without `vn`, PLY without nx/ny/nz): smooth normals by this
    /// crease angle in degrees (within 0..=180, [`crate::normals::smooth`]); `None` shades them with face normals.
    /// Files with their own normals, and glTF (whose spec says flat without NORMAL), ignore it. Default: the
    /// command line's (`--smooth-angle`/`--flat-normals`), else 40°, the renderer's feature-edge crease.
    pub crease_deg: Option<f32>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            cancel: Arc::new(AtomicBool::new(false)),
            max_memory: default_max_memory(),
            cad: CadOptions::default(),
            crease_deg: crate::normals::default_crease_deg(),
        }
    }
}

/// STEP or IGES.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CadFormat {
    Step,
    Iges,
}

impl CadFormat {
    pub fn name(self) -> &'static str {
        match self {
            CadFormat::Step => "STEP",
            CadFormat::Iges => "IGES",
        }
    }
}

/// How B-rep faces become triangles (OpenCASCADE's `BRepMesh_IncrementalMesh`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CadTessellation {
    /// Linear deflection as a fraction of each part's bounding-box diagonal; 0 uses `absolute`.
    pub relative: f64,
    /// Linear deflection in millimetres when `relative` is 0 (F3D's way: one tolerance for the whole model).
    pub absolute: f64,
    /// Angular deflection in degrees.
    pub angular_deg: f64,
}

impl CadTessellation {
    /// The fine tessellation, hrtao's default before B-rep faces carried their surface normals: 0.1 % of each
    /// part's size and 10 degrees, fine enough for the face normals of the triangles to shade curved faces
    /// smoothly. About 3.3x the default's triangles on AS1 (12,208 against 3,664) and 4.2x on component8
    /// (1,820 against 436) for an image within MAE 0.0006 (docs/benchmarks.md, STEP section);
    /// `--deflection 0.001 --angular-deflection 10` or the Load options panel choose it.
    pub const FINE: CadTessellation = CadTessellation {
        relative: 1e-3,
        absolute: 0.0,
        angular_deg: 10.0,
    };
}

impl Default for CadTessellation {
    /// 0.5 % of each part's size and 35 degrees, as CAD viewers tessellate for the eye: the kernel's surface
    /// normals shade curved faces smoothly, so triangles only need to keep silhouettes and AO true. Chosen by
    /// `scripts/step-tessellation-sweep.sh` where the image stops changing (AO within MAE 0.0003 and the
    /// shaded image within 0.0006 of a 0.02 %/5° tessellation on AS1 and component8) with under a third of
    /// [`CadTessellation::FINE`]'s triangles.
    fn default() -> Self {
        CadTessellation {
            relative: 5e-3,
            absolute: 0.0,
            angular_deg: 35.0,
        }
    }
}

/// STEP/IGES load options.
#[derive(Clone, Debug, PartialEq)]
pub struct CadOptions {
    /// The `hrtao` binary whose `occt-worker` subcommand runs the kernel; by default the one given to
    /// [`crate::set_default_cad_worker`] (the viewer's own executable).
    pub worker: Option<std::path::PathBuf>,
    pub tessellation: CadTessellation,
    /// CPU seconds the kernel may take (`HRTAO_OCCT_CPU_SECONDS`, default 300).
    pub cpu_seconds: u64,
}

impl Default for CadOptions {
    fn default() -> Self {
        CadOptions {
            worker: crate::default_cad_worker(),
            tessellation: crate::default_cad_tessellation(),
            cpu_seconds: std::env::var("HRTAO_OCCT_CPU_SECONDS")
                .ok()
                .and_then(|v| v.trim().parse().ok())
                .unwrap_or(300),
        }
    }
}

/// The default scene memory limit: `HRTAO_MAX_SCENE_MB` if set, else half the physical memory
/// (at most 16 GiB; 4 GiB if it cannot be read), so that no file can take the machine down.
pub fn default_max_memory() -> u64 {
    if let Some(mb) = std::env::var("HRTAO_MAX_SCENE_MB")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
    {
        return mb.saturating_mul(1 << 20);
    }
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        s.lines()
            .find_map(|l| l.strip_prefix("MemTotal:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map(|kb| kb * 1024)
    });
    match total {
        Some(t) => (t / 2).min(16 << 30),
        None => 4 << 30,
    }
}

impl LoadOptions {
    /// `Err(Cancelled)` once the cancel flag is set.
    pub(crate) fn check_cancel(&self, source: &Path) -> Result<(), SceneError> {
        if self.cancel.load(Ordering::Relaxed) {
            Err(SceneError::Cancelled(source.display().to_string()))
        } else {
            Ok(())
        }
    }
}

/// Reads the model file itself through the guard, and starts the memory budget of its load (which counts the
/// file's bytes). Every loader begins here.
pub(crate) fn read_model(
    path: &Path,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<(Vec<u8>, Budget), SceneError> {
    let mut budget = Budget::new(opts, path);
    let bytes = Fetch {
        model: path,
        target: Target::Model,
        declared: None,
    }
    .read(path, opts, &mut budget, progress)?;
    Ok((bytes, budget))
}

/// Running total of the memory a load will take, checked against [`LoadOptions::max_memory`].
pub(crate) struct Budget {
    limit: u64,
    used: u64,
    source: PathBuf,
}

impl Budget {
    pub fn new(opts: &LoadOptions, source: &Path) -> Budget {
        Budget {
            limit: opts.max_memory,
            used: 0,
            source: source.to_path_buf(),
        }
    }

    /// Adds `bytes` (for `what`) or fails with a "too large" error naming the file, before allocating.
    pub fn reserve(&mut self, bytes: u64, what: &str) -> Result<(), SceneError> {
        let total = self.used.saturating_add(bytes);
        if total > self.limit {
            return Err(SceneError::TooLarge(format!(
                "{}: {what} needs {} (scene total {}), over the scene memory limit of {} \
                 (HRTAO_MAX_SCENE_MB)",
                self.source.display(),
                mib(bytes),
                mib(total),
                mib(self.limit)
            )));
        }
        self.used = total;
        Ok(())
    }
}

pub(crate) fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1 << 20) as f64)
}

/// What is being read, for error messages: the model itself or a reference inside it.
#[derive(Clone, Copy)]
pub(crate) enum Target<'a> {
    Model,
    /// A reference of the model, as written in the file (URI or `mtllib` name).
    Reference(&'a str),
}

/// A guarded read: the model (for errors and cancel), what is read, the size declared by the model.
pub(crate) struct Fetch<'a> {
    pub model: &'a Path,
    pub target: Target<'a>,
    /// Bytes the model says the file holds (glTF `byteLength`): a shorter file is an error and no more
    /// is read. `None`: the whole file (within the memory budget).
    pub declared: Option<u64>,
}

impl Fetch<'_> {
    fn error(&self, path: &Path, message: String) -> SceneError {
        match self.target {
            Target::Model => SceneError::Unreadable {
                path: path.to_path_buf(),
                message,
            },
            Target::Reference(uri) => SceneError::Reference {
                model: self.model.to_path_buf(),
                uri: uri.to_string(),
                message,
            },
        }
    }

    /// Opens `path` without blocking, requires a regular file, checks the size, reads it in chunks.
    pub fn read(
        &self,
        path: &Path,
        opts: &LoadOptions,
        budget: &mut Budget,
        progress: &mut dyn FnMut(LoadProgress),
    ) -> Result<Vec<u8>, SceneError> {
        // Refuse special files before opening them (opening some devices has side effects) ...
        match std::fs::metadata(path) {
            Ok(m) if !m.is_file() => return Err(self.error(path, not_regular(&m.file_type()))),
            Ok(_) => {}
            Err(e) => return Err(self.io_error(path, e)),
        }
        // ... then check the opened handle, which cannot be swapped behind our back.
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
            .open(path)
            .map_err(|e| self.io_error(path, e))?;
        let meta = file.metadata().map_err(|e| self.io_error(path, e))?;
        if !meta.is_file() {
            return Err(self.error(path, not_regular(&meta.file_type())));
        }
        let size = meta.len();
        let want = match self.declared {
            Some(declared) if size < declared => {
                return Err(self.error(
                    path,
                    format!("the file has {size} bytes but the model declares byteLength {declared}"),
                ))
            }
            Some(declared) => {
                if size > declared {
                    log::warn!(
                        "{}: {} has {size} bytes, more than the declared {declared}; reading {declared}",
                        self.model.display(),
                        path.display()
                    );
                }
                declared
            }
            None => size,
        };
        let what = match self.target {
            Target::Model => "the file".to_string(),
            Target::Reference(uri) => format!("`{uri}`"),
        };
        budget.reserve(want, &what)?;
        let want = usize::try_from(want)
            .map_err(|_| self.error(path, format!("{want} bytes do not fit in memory")))?;
        let mut data = Vec::new();
        data.try_reserve_exact(want)
            .map_err(|e| self.error(path, format!("cannot allocate {want} bytes: {e}")))?;
        // Appends into the reserved capacity: memory is touched only as bytes arrive.
        while data.len() < want {
            opts.check_cancel(self.model)?;
            let chunk = CHUNK.min(want - data.len()) as u64;
            let n = (&mut file)
                .take(chunk)
                .read_to_end(&mut data)
                .map_err(|e| self.io_error(path, e))?;
            if n == 0 {
                return Err(self.error(
                    path,
                    format!(
                        "the file ended after {} of {want} bytes (it shrank while reading)",
                        data.len()
                    ),
                ));
            }
            progress(LoadProgress {
                stage: "read",
                done: data.len() as u64,
                total: want as u64,
            });
        }
        Ok(data)
    }

    fn io_error(&self, path: &Path, e: std::io::Error) -> SceneError {
        match self.target {
            Target::Model => SceneError::Io {
                path: path.to_path_buf(),
                source: e,
            },
            Target::Reference(_) => {
                let message = if e.kind() == std::io::ErrorKind::NotFound {
                    format!("{} does not exist", path.display())
                } else if e.raw_os_error() == Some(libc::ENXIO) {
                    // Opening a socket gives ENXIO.
                    format!("{} is a socket, not a regular file", path.display())
                } else {
                    format!("cannot read {}: {e}", path.display())
                };
                self.error(path, message)
            }
        }
    }
}

/// Names what a non-regular file is.
fn not_regular(t: &std::fs::FileType) -> String {
    let kind = if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    };
    format!("it is {kind}, not a regular file")
}

/// Resolves a reference written in a model (`rel`: relative to the model's folder, or absolute) and
/// requires it to stay inside `dir`, the model's folder, or its subfolders. The check is lexical
/// (`..` is resolved on the path's text); symlinks inside the folder are followed, and what they lead to
/// must still be a regular file of the declared size ([`Fetch::read`]).
pub(crate) fn resolve_reference(model: &Path, rel: &Path, uri: &str) -> Result<PathBuf, SceneError> {
    let dir = model.parent().unwrap_or(Path::new(""));
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let base = absolute(dir);
    let joined = normalize(&base.join(rel));
    if !joined.starts_with(&base) {
        return Err(SceneError::Reference {
            model: model.to_path_buf(),
            uri: uri.to_string(),
            message: format!(
                "it points outside the model's folder {} (to {}); only files in that folder or its \
                 subfolders are read",
                base.display(),
                joined.display()
            ),
        });
    }
    Ok(joined)
}

fn absolute(p: &Path) -> PathBuf {
    normalize(&std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf()))
}

/// Removes `.` and resolves `..` lexically (never above the root).
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_stay_in_the_model_folder() {
        let model = Path::new("/data/models/part.gltf");
        let ok = |r: &str| resolve_reference(model, Path::new(r), r).unwrap();
        assert_eq!(ok("part.bin"), Path::new("/data/models/part.bin"));
        assert_eq!(ok("bin/./part.bin"), Path::new("/data/models/bin/part.bin"));
        assert_eq!(ok("bin/../part.bin"), Path::new("/data/models/part.bin"));
        assert_eq!(ok("/data/models/x/y.bin"), Path::new("/data/models/x/y.bin"));
        for bad in [
            "../part.bin",
            "../../../../etc/passwd",
            "/dev/zero",
            "/data/modelsX/a.bin",
            "bin/../../a",
        ] {
            let e = resolve_reference(model, Path::new(bad), bad)
                .unwrap_err()
                .to_string();
            assert!(e.contains("outside the model's folder") && e.contains(bad), "{e}");
        }
    }

    #[test]
    fn budget_refuses_before_allocating() {
        let opts = LoadOptions {
            max_memory: 1000,
            ..Default::default()
        };
        let mut b = Budget::new(&opts, Path::new("m.gltf"));
        b.reserve(600, "a").unwrap();
        let e = b.reserve(u64::MAX, "buffer 3").unwrap_err();
        assert!(matches!(e, SceneError::TooLarge(_)));
        let e = e.to_string();
        assert!(
            e.contains("m.gltf") && e.contains("buffer 3") && e.contains("limit"),
            "{e}"
        );
        b.reserve(400, "b").unwrap();
    }
}
