//! Device cost of the viewer's moving frames (a development tool): orbits the bundled scene's camera by 2° per
//! frame at the viewer's moving size, with the viewer's moving settings (1 filter iteration, the default ray
//! budget spread over the pixels), and prints the median GPU milliseconds per pass over frames 5.. .
//!
//! `cargo run --release -p hrtao-core --example orbit_profile -- [--size 323x280] [--frames 40] [--rays 3] [--fraction 1] [--view-height 800] [--step-deg 2 (0: still frames)] [--lattice 1]
//! [--primary raster|rayquery] [--scene FILE] [--set '{"filter_iterations": 1}']`
mod cli_args;
use std::collections::BTreeMap;
use std::path::PathBuf;

use glam::{Quat, Vec3};
use hrtao_core::stats::median;
use hrtao_core::{AoSettings, Camera, ContextOptions, Gpu, Renderer, SceneGpu};

fn main() -> anyhow::Result<()> {
    let mut args = cli_args::Args::from_env();
    let size = args.take("--size", "323x280");
    let frames: usize = args.take("--frames", "40").parse()?;
    let rays: u32 = args.take("--rays", "3").parse()?;
    let fraction: f32 = args.take("--fraction", "1").parse()?;
    // The viewer's view is 800 pixels high: s_p counts view pixels, so its cells are that much finer.
    let view_height: u32 = args.take("--view-height", "800").parse()?;
    let primary = args.primary();
    let extra = args.take("--set", r#"{"filter_iterations": 1}"#);
    // 0: a still camera (the viewer's still frames: jittered, refined).
    let step_deg: f32 = args.take("--step-deg", "2").parse()?;
    // Slices: every lattice-th pixel per frame (still frames of the viewer).
    let lattice: u32 = args.take("--lattice", "1").parse()?;
    let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let scene_path = args.take("--scene", assets.join("default.glb").to_str().unwrap());
    let (w, h) = size.split_once('x').unwrap();
    let (w, h): (u32, u32) = (w.parse()?, h.parse()?);
    let scene = hrtao_scene::load(&scene_path, &mut |_| {})?;
    let mut camera = if scene_path.ends_with("default.glb") {
        Camera::load(&assets.join("default.camera.json"))?
    } else {
        let b = scene.bounds();
        Camera::fit(b.min, b.max, Default::default(), 45.0, w, h)
    };
    camera.width = w;
    camera.height = h;
    let mut settings = cli_args::with_overrides(&AoSettings::default(), &extra)?;
    settings.map.rays_per_pixel = rays;
    let gpu = Gpu::new(&ContextOptions::default())?;
    let sg = SceneGpu::new(&gpu, &scene)?;
    let mut r = Renderer::new(&gpu)?;
    r.set_primary(primary);
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let (mut walls, mut rays_sum) = (Vec::new(), 0u64);
    let up = Vec3::from(camera.up).normalize();
    for i in 0..frames {
        let frame = hrtao_core::FrameDesc {
            view_height,
            budget: Some(hrtao_core::RayBudget {
                rays_per_pixel: rays,
                trace_fraction: fraction,
            }),
            jitter: step_deg == 0.0,
            lattice,
            ..hrtao_core::FrameDesc::new(&sg, scene.f(), camera, &settings)
        };
        let rep = r.render(&frame)?;
        if i >= 4 {
            walls.push(rep.wall_ms);
            rays_sum += rep.rays;
            for (k, ms) in &rep.gpu_ms {
                per_pass.entry(k.clone()).or_default().push(*ms);
            }
        }
        let t = Vec3::from(camera.target);
        let e = Quat::from_axis_angle(up, step_deg.to_radians()) * (Vec3::from(camera.eye) - t) + t;
        camera.eye = e.into();
    }
    let n = walls.len().max(1);
    println!(
        "{w}x{h}, {} frames after 4: median wall {:.1} ms, {:.0} rays/frame",
        walls.len(),
        median(&walls),
        rays_sum as f64 / n as f64
    );
    for (k, v) in per_pass {
        println!("  {k:>20}: {:7.1} ms", median(&v));
    }
    Ok(())
}
