//! `hrtao render`: load, build, render K frames headless, write images and statistics.
use std::time::Instant;

use anyhow::{bail, Result};
use hrtao_core::camera::UpAxis;
use hrtao_core::{imageio, Camera, FrameReport, Renderer, SceneGpu};

use crate::cli::{DeviceArgs, RenderArgs};
use crate::common::{load_scene, open_gpu, write_json};

fn parse_up(s: &str) -> Result<UpAxis> {
    match s.to_ascii_lowercase().as_str() {
        "y" => Ok(UpAxis::Y),
        "z" => Ok(UpAxis::Z),
        _ => bail!("--up must be y or z, got `{s}`"),
    }
}

#[derive(serde::Serialize)]
struct RenderStats<'a> {
    device: &'a hrtao_core::DeviceInfo,
    scene: String,
    unique_triangles: u64,
    instanced_triangles: u64,
    instances: usize,
    meshes: usize,
    width: u32,
    height: u32,
    settings: &'a hrtao_core::AoSettings,
    load_ms: f64,
    build: &'a hrtao_core::accel::BuildStats,
    frames: &'a [FrameReport],
    total_rays: u64,
    render_ms: f64,
    validation_messages: u32,
    /// The section planes (scene coordinates) and the instances they keep, cross and cut away.
    sections: &'a hrtao_core::Sections,
    section_sides: [usize; 3],
}

pub fn run(args: &RenderArgs) -> Result<()> {
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let (scene, load_ms) = load_scene(&args.scene)?;
    let bounds = scene.bounds();
    let mut camera = match &args.camera {
        Some(p) => Camera::load_in(p, scene.origin)?,
        None => Camera::fit(bounds.min, bounds.max, parse_up(&args.up)?, 40.0, 640, 360),
    };
    if let Some(w) = args.width {
        camera.width = w;
    }
    if let Some(h) = args.height {
        camera.height = h;
    }
    camera.validate().map_err(|e| anyhow::anyhow!("camera: {e}"))?;
    let settings = args.ao.settings(bounds.diagonal().length())?;
    settings.validate().map_err(|e| anyhow::anyhow!(e))?;

    let sections = args.sections.sections(&scene).map_err(|e| anyhow::anyhow!(e))?;
    let gpu = open_gpu(&args.device)?;
    let mut scene_gpu = SceneGpu::new(&gpu, &scene)?;
    scene_gpu.set_sections(&scene, &sections, u32::MAX)?;
    log::info!(
        "acceleration structures: {} BLAS in {:.0} ms, TLAS of {} instances in {:.1} ms",
        scene_gpu.stats.blas_count,
        scene_gpu.stats.blas_ms,
        scene_gpu.stats.tlas_instances,
        scene_gpu.stats.tlas_ms
    );
    let mut renderer = Renderer::new(&gpu, camera.width, camera.height, settings.clone())?;
    let t0 = Instant::now();
    let mut frames = Vec::new();
    for i in 0..args.frames {
        let report = renderer.render(&scene_gpu, scene.f(), &camera)?;
        log::info!(
            "frame {i}: {:.1} ms wall, {:.1} ms GPU, {} rays{}",
            report.wall_ms,
            report.gpu_total_ms,
            report.rays,
            if settings.mode.uses_hash() {
                format!(
                    ", {} cells ({:.1}% load), {} failed inserts",
                    report.occupied_cells,
                    report.load_factor * 100.0,
                    report.failed_inserts
                )
            } else {
                String::new()
            }
        );
        frames.push(report);
    }
    let render_ms = t0.elapsed().as_secs_f64() * 1e3;
    let (w, h) = renderer.size();
    if let Some(out) = &args.out {
        let rgba = renderer.read_rgba()?;
        imageio::write_png(out, w, h, &rgba)?;
        log::info!("wrote {}", out.display());
    }
    if let Some(out) = &args.ao_out {
        let ao = renderer.read_ao()?;
        imageio::write_ao(out, w, h, &ao)?;
        log::info!("wrote {}", out.display());
    }
    let validation_messages = gpu.validation_messages();
    if let Some(path) = &args.stats {
        let stats = RenderStats {
            device: &gpu.info,
            scene: args.scene.clone(),
            unique_triangles: scene.unique_triangle_count(),
            instanced_triangles: scene.instanced_triangle_count(),
            instances: scene.instances.len(),
            meshes: scene.meshes.len(),
            width: w,
            height: h,
            settings: &settings,
            load_ms,
            build: &scene_gpu.stats,
            total_rays: frames.iter().map(|f| f.rays).sum(),
            frames: &frames,
            render_ms,
            validation_messages,
            sections: &sections,
            section_sides: scene_gpu.section_sides,
        };
        write_json(path, &stats)?;
    }
    if validation_messages > 0 {
        log::warn!("the validation layer reported {validation_messages} messages");
    }
    Ok(())
}

pub fn list_devices(d: &DeviceArgs) -> Result<()> {
    let gpu = open_gpu(d)?;
    println!(
        "{} ({}), driver {}, Vulkan {}",
        gpu.info.name, gpu.info.kind, gpu.info.driver, gpu.info.api_version
    );
    Ok(())
}
