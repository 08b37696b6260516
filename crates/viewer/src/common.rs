//! Helpers shared by the commands: opening the device, loading a scene, writing JSON, the bundled scene's path.
use std::path::Path;
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
        memory_limit: hrtao_core::context::memory_limit_from_env(),
        ..Default::default()
    };
    let gpu = Gpu::new(&opts)?;
    log::info!(
        "device: {} ({}; {})",
        gpu.info.name,
        gpu.info.kind,
        gpu.info.driver
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

/// The default scene bundled in `assets/`.
pub fn default_scene_path() -> std::path::PathBuf {
    let beside_exe = std::env::current_exe()
        .ok()
        .and_then(|p| p.parent().map(|d| d.join("assets")));
    let candidates = [
        Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/default.glb")),
        beside_exe.map(|d| d.join("default.glb")),
        Some(Path::new("assets/default.glb").to_path_buf()),
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|p| p.exists())
        .unwrap_or_else(|| "assets/default.glb".into())
}
