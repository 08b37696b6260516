//! Helpers shared by the commands: opening the device, loading a scene, writing JSON, the bundled scene, progress
//! bars.
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use hrtao_core::{ContextOptions, Gpu};
use hrtao_scene::Scene;

use crate::cli::DeviceArgs;

pub fn open_gpu(d: &DeviceArgs) -> Result<Arc<Gpu>> {
    let opts = ContextOptions {
        validation: d.validation || hrtao_core::context::validation_requested_by_env(),
        device: d.device.clone(),
        ray_backend: d.ray_backend,
        memory_limit: hrtao_core::context::memory_limit_from_env(),
        ..Default::default()
    };
    let gpu = Gpu::new(&opts)?;
    log::info!(
        "device: {} ({}; {}; rays traced by {})",
        gpu.info.name,
        gpu.info.kind,
        gpu.info.driver,
        gpu.info.ray_backend.name()
    );
    Ok(gpu)
}

pub fn load_scene(spec: &str) -> Result<(Scene, f64)> {
    let t0 = Instant::now();
    let mut last = Instant::now();
    let scene = hrtao_scene::load(spec, &mut |p| {
        if last.elapsed().as_millis() > 500 {
            log::info!("loading {spec}: {} {}/{}", p.stage, p.done, p.total);
            last = Instant::now();
        }
    })
    .with_context(|| format!("cannot load scene `{spec}`"))?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    log::info!(
        "scene {}: {} meshes, {} instances, {} unique / {} instanced triangles, loaded in {ms:.0} ms",
        scene.name,
        scene.meshes.len(),
        scene.instances.len(),
        scene.unique_triangle_count(),
        scene.instanced_triangle_count()
    );
    Ok((scene, ms))
}

pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// The bundled scene (a cycloidal gearbox, MIT: assets/default.LICENSE.md) and its camera, in the binary: an
/// installed `hrtao` needs no file of the source tree.
const DEFAULT_GLB: &[u8] = include_bytes!("../../../assets/default.glb");
const DEFAULT_CAMERA: &[u8] = include_bytes!("../../../assets/default.camera.json");

/// The bundled scene as a file (the loaders read files): written once into the user's cache directory
/// (`~/.cache/hrtao/bundled/default.glb`, else the temporary directory) with its camera beside it, and rewritten
/// when this binary bundles other bytes.
pub fn default_scene_path() -> PathBuf {
    let dirs = [dirs::cache_dir(), Some(std::env::temp_dir())];
    let mut last_error = None;
    for dir in dirs.into_iter().flatten() {
        let dir = dir.join("hrtao").join("bundled");
        let glb = dir.join("default.glb");
        match write_if_changed(&glb, DEFAULT_GLB)
            .and_then(|()| write_if_changed(&dir.join("default.camera.json"), DEFAULT_CAMERA))
        {
            Ok(()) => return glb,
            Err(e) => last_error = Some(format!("{}: {e}", dir.display())),
        }
    }
    log::warn!(
        "cannot write the bundled scene: {}",
        last_error.unwrap_or_default()
    );
    PathBuf::from("default.glb")
}

/// Writes `bytes` to `path` unless it already holds them; through a temporary file and a rename, so that a
/// process reading the file (another `hrtao`) never sees it half written.
fn write_if_changed(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if std::fs::read(path).is_ok_and(|old| old == bytes) {
        return Ok(());
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// `-q`: no progress bars (warnings and errors only in the log).
static QUIET: AtomicBool = AtomicBool::new(false);

pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// A progress bar of `len` steps on stderr; hidden with `-q` or when stderr is not a terminal.
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    if QUIET.load(Ordering::Relaxed) || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len).with_message(what.to_string());
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg:>12} [{bar:30}] {pos}/{len} {elapsed_precise} (ETA {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar
}
