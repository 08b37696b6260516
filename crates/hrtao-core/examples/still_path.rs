//! The path of a still image to its converged state (a development tool): orbit the camera for a few frames at a
//! reduced scale (the viewer's moving frames), stop, and render still frames in slices until the image converges,
//! printing each presented frame's roughness (`metrics::roughness`, over the converged frame's G-buffer so the
//! first round of slices counts too) and, with `--ref EXR`, its MAE against a Cycles reference.
//!
//! `cargo run --release -p hrtao-core --example still_path -- SCENE CAMERA.json [--size 806x800] [--radius 8]
//! [--lattice 2] [--rays 4] [--orbit 20] [--set JSON] [--dump DIR] [--every 1]`
mod cli_args;
use std::path::PathBuf;

use glam::{Quat, Vec3};
use hrtao_core::{metrics, Camera, ContextOptions, FrameDesc, Gpu, RayBudget, Renderer, SceneGpu};

fn orbit(c: &Camera, degrees: f32) -> Camera {
    let target = Vec3::from(c.target);
    let q = Quat::from_axis_angle(Vec3::from(c.up).normalize(), degrees.to_radians());
    Camera {
        eye: (target + q * (Vec3::from(c.eye) - target)).into(),
        ..*c
    }
}

fn main() -> anyhow::Result<()> {
    let mut args = cli_args::Args::from_env();
    let size = args.take("--size", "806x800");
    let radius: f32 = args.take("--radius", "8").parse()?;
    let lattice: u32 = args.take("--lattice", "2").parse()?;
    let rays: u32 = args.take("--rays", "4").parse()?;
    let orbit_frames: u32 = args.take("--orbit", "20").parse()?;
    let extra = args.take("--set", "{}");
    let dump = args.take("--dump", "");
    let every: usize = args.take("--every", "1").parse()?;
    let max_frames: u32 = args.take("--max-frames", "2000").parse()?;
    let (w, h) = size
        .split_once('x')
        .map(|(a, b)| (a.parse().unwrap(), b.parse().unwrap()))
        .unwrap();
    let [scene_path, camera_path] = &args.0[..] else {
        anyhow::bail!("usage: still_path SCENE CAMERA.json [options]");
    };
    let gpu = Gpu::new(&ContextOptions::default())?;
    let scene = hrtao_scene::load(scene_path, &mut |_| {})?;
    let sg = SceneGpu::new(&gpu, &scene)?;
    let mut settings = hrtao_core::AoSettings::default();
    settings.map.ao_radius = radius;
    let settings = cli_args::with_overrides(&settings, &extra)?;
    let cam = Camera {
        width: w,
        height: h,
        ..Camera::load(std::path::Path::new(camera_path))?
    };
    let mut r = Renderer::new(&gpu)?;
    // The viewer's moving frames: 0.4 scale, per-frame budget from the settings.
    let (mw, mh) = ((w as f32 * 0.4) as u32, (h as f32 * 0.4) as u32);
    for i in 0..orbit_frames {
        let c = Camera {
            width: mw,
            height: mh,
            ..orbit(&cam, 2.0 * (i as f32 - orbit_frames as f32))
        };
        let mut s = settings.clone();
        s.filter.filter_iterations = s.filter.filter_iterations.min(2);
        r.render(&FrameDesc {
            view_height: h,
            jitter: true,
            ..FrameDesc::new(&sg, scene.f(), c, &s)
        })?;
    }
    let mut frames = Vec::new();
    let mut converged_at = None;
    for i in 0..max_frames {
        let rep = r.render(&FrameDesc {
            view_height: h,
            jitter: true,
            lattice,
            budget: Some(RayBudget {
                rays_per_pixel: rays,
                trace_fraction: 1.0,
            }),
            ..FrameDesc::new(&sg, scene.f(), cam, &settings)
        })?;
        frames.push((r.read_ao()?, rep.slice, rep.wall_ms));
        if rep.converged {
            converged_at = Some(i);
            break;
        }
    }
    let gbuffer = r.read_gbuffer()?;
    let last = frames.len() - 1;
    let final_r = metrics::roughness(&frames[last].0, &gbuffer, w as usize, h as usize).unwrap_or(f32::NAN);
    let mut peak = (0.0f32, 0usize);
    for (i, (ao, slice, ms)) in frames.iter().enumerate() {
        let rough = metrics::roughness(ao, &gbuffer, w as usize, h as usize).unwrap_or(f32::NAN);
        if rough > peak.0 {
            peak = (rough, i);
        }
        if i % every == 0 || i == last {
            println!(
                "frame {i:4} slice {slice} roughness {rough:.4} ({:.2}x) {ms:.0} ms",
                rough / final_r
            );
        }
        if !dump.is_empty() {
            let d = PathBuf::from(&dump);
            std::fs::create_dir_all(&d)?;
            hrtao_core::imageio::write_pfm(&d.join(format!("frame_{i:04}.pfm")), w, h, ao)?;
        }
    }
    println!(
        "converged at {converged_at:?} roughness {final_r:.4}; largest {:.4} ({:.2}x) at frame {}",
        peak.0,
        peak.0 / final_r,
        peak.1
    );
    Ok(())
}
