//! Image quality of HRTAO against Blender Cycles references (a development tool; the published figures come from
//! `hrtao bench`): the repository's `testdata/refs` (keys rod, cycloidal), and with `HRTAO_SHARED=DIR` also the
//! views of `DIR/refs/index.json` (extra scenes that are not in the repository, e.g. engine, duplex, sf).
//!
//! `cargo run --release -p hrtao-core --example quality -- [--size 640x360] [--rays 8] [--frames 32]
//! [--set '{"refine": false}'] KEY...` (`--set` overrides AoSettings fields, e.g. the paper's behaviour).
//!
//! Per scene: MAE of one frame from an empty map (per-pixel RTAO and HRTAO), MAE after N still frames (HRTAO,
//! and per-pixel RTAO with the same total rays), and HRTAO's flicker (mean |ΔAO| between consecutive still
//! frames after frame 4).
mod cli_args;
use std::path::{Path, PathBuf};

use anyhow::Context;
use hrtao_core::{metrics, AoSettings, Camera, ContextOptions, Gpu, Mode, Renderer, SceneGpu};

/// The folders holding `scenes/` and `refs/index.json`: the repository's test data, then `$HRTAO_SHARED`.
fn roots() -> Vec<PathBuf> {
    let mut roots = vec![PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../testdata")];
    if let Some(dir) = std::env::var_os("HRTAO_SHARED") {
        roots.push(PathBuf::from(dir));
    }
    roots
}

/// The first root whose index lists `key`, with its index entry.
fn find(key: &str) -> anyhow::Result<(PathBuf, serde_json::Value)> {
    for root in roots() {
        let path = root.join("refs/index.json");
        let index: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?,
        )?;
        if index[key].is_object() {
            return Ok((root, index[key].clone()));
        }
    }
    anyhow::bail!("no scene {key:?} in testdata/refs/index.json (rod, cycloidal); set HRTAO_SHARED=DIR for the views of DIR/refs/index.json")
}

/// A reference image (`KEY_WxH.cycles.exr`: R = G = B = AO, row 0 at the top) and its size.
fn read_exr(path: &Path) -> anyhow::Result<(u32, u32, Vec<f32>)> {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| (size.width(), vec![0.0f32; size.area()]),
        |(width, ao), pos, (r, _g, _b, _a): (f32, f32, f32, f32)| ao[pos.y() * *width + pos.x()] = r,
    )
    .with_context(|| format!("reading {}", path.display()))?;
    let size = image.layer_data.size;
    let (_, ao) = image.layer_data.channel_data.pixels;
    Ok((size.width() as u32, size.height() as u32, ao))
}

fn main() -> anyhow::Result<()> {
    let mut args = cli_args::Args::from_env();
    let size = args.take("--size", "640x360");
    let rays: u32 = args.take("--rays", "8").parse()?;
    let frames: u32 = args.take("--frames", "32").parse()?;
    let extra = args.take("--set", "{}");
    let dump = args.take("--dump", "");
    let keys = if args.0.is_empty() {
        vec!["rod".to_string(), "cycloidal".to_string()]
    } else {
        args.0
    };
    let gpu = Gpu::new(&ContextOptions::default())?;
    println!("| scene | RTAO 1f | HRTAO 1f | ratio | RTAO eq. rays | HRTAO {frames}f | ratio | HRTAO rays/px | flicker | ms/frame 1st, still |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut curves = Vec::new();
    for key in keys {
        let (root, entry) = find(&key)?;
        let file = entry["scene"].as_str().context("index entry without a scene")?;
        let scene = hrtao_scene::load(root.join(file).to_str().unwrap(), &mut |_| {})?;
        let radius = entry["radius"].as_f64().unwrap() as f32;
        let cam = Camera::load(&root.join(format!("refs/{key}_{size}.camera.json")))?;
        let (_, _, reference) = read_exr(&root.join(format!("refs/{key}_{size}.cycles.exr")))?;
        let sg = SceneGpu::new(&gpu, &scene)?;
        let base = {
            let mut s = AoSettings::default();
            s.map.ao_radius = radius;
            s.map.rays_per_pixel = rays;
            s
        };
        let mut settings = cli_args::with_overrides(&base, &extra)?;
        settings.display.mode = Mode::Hrtao;
        // HRTAO: one frame, then still frames.
        let mut r = Renderer::new(&gpu)?;
        let mut total_rays = 0u64;
        let mut hrtao_1 = 0.0;
        let mut prev: Vec<f32> = Vec::new();
        let (mut flicker, mut flicker_n) = (0.0f64, 0u32);
        let mut ms = (0.0, 0.0);
        let mut hrtao_curve = Vec::new(); // (frames, cumulative rays, MAE)
        for f in 0..frames {
            let rep = r.render(&hrtao_core::FrameDesc::new(&sg, scene.f(), cam, &settings))?;
            total_rays += rep.rays;
            if f == 0 {
                ms.0 = rep.wall_ms;
            } else {
                ms.1 += rep.wall_ms / (frames - 1).max(1) as f64;
            }
            let ao = r.read_ao()?;
            let e = metrics::ao_error(&ao, &reference).mae;
            hrtao_curve.push((f + 1, total_rays, e));
            if f == 0 {
                hrtao_1 = e;
                if !dump.is_empty() {
                    let d = PathBuf::from(&dump);
                    std::fs::create_dir_all(&d)?;
                    let (w, h) = (cam.width, cam.height);
                    hrtao_core::imageio::write_pfm(&d.join(format!("{key}_hrtao1.pfm")), w, h, &ao)?;
                    let rays = r.read_pixel_rays()?;
                    let open: Vec<f32> = rays.iter().map(|p| p.open as f32).collect();
                    let traced: Vec<f32> = rays.iter().map(|p| p.near_traced as f32).collect();
                    hrtao_core::imageio::write_pfm(&d.join(format!("{key}_open.pfm")), w, h, &open)?;
                    hrtao_core::imageio::write_pfm(&d.join(format!("{key}_traced.pfm")), w, h, &traced)?;
                    let plan: Vec<f32> = r
                        .read_filter_plan()?
                        .iter()
                        .map(|p| (p >> hrtao_core::gpu::FILTER_PLAN_BITS) as f32)
                        .collect();
                    hrtao_core::imageio::write_pfm(&d.join(format!("{key}_samples.pfm")), w, h, &plan)?;
                    let gb = r.read_gbuffer()?;
                    let mask: Vec<f32> = gb.iter().map(|p| if p.t >= 0.0 { 1.0 } else { 0.0 }).collect();
                    hrtao_core::imageio::write_pfm(&d.join(format!("{key}_mask.pfm")), w, h, &mask)?;
                    // The G-buffer's position and normal, one channel per file, for offline analyses.
                    for (name, i) in [("px", 0), ("py", 1), ("pz", 2), ("nx", 3), ("ny", 4), ("nz", 5)] {
                        let c: Vec<f32> = gb
                            .iter()
                            .map(|p| if i < 3 { p.position[i] } else { p.normal[i - 3] })
                            .collect();
                        hrtao_core::imageio::write_pfm(&d.join(format!("{key}_{name}.pfm")), w, h, &c)?;
                    }
                }
            }
            if f >= 4 {
                let d: f64 = ao
                    .iter()
                    .zip(&prev)
                    .map(|(a, b)| (a - b).abs() as f64)
                    .sum::<f64>();
                flicker += d / ao.len() as f64;
                flicker_n += 1;
            }
            prev = ao;
        }
        let hrtao_n = metrics::ao_error(&prev, &reference).mae;
        if !dump.is_empty() {
            let path = PathBuf::from(&dump).join(format!("{key}_hrtao{frames}.pfm"));
            hrtao_core::imageio::write_pfm(&path, cam.width, cam.height, &prev)?;
        }
        let gbuf = r.read_gbuffer()?;
        let geometry = gbuf.iter().filter(|p| p.t >= 0.0).count().max(1) as f64;
        let rays_px = total_rays as f64 / geometry;
        // Per-pixel RTAO: one frame, and the frame count that matches HRTAO's total rays.
        let rt_settings = {
            let mut s = settings.clone();
            s.display.mode = Mode::Rtao;
            s
        };
        let mut rt = Renderer::new(&gpu)?;
        let eq_frames = ((rays_px / rays as f64).round() as u32).max(1);
        let mut rtao_curve = Vec::new();
        for i in 0..eq_frames.max(frames) {
            rt.render(&hrtao_core::FrameDesc::new(&sg, scene.f(), cam, &rt_settings))?;
            let ao = rt.read_ao()?;
            if i == 0 && !dump.is_empty() {
                let path = PathBuf::from(&dump).join(format!("{key}_rtao1.pfm"));
                hrtao_core::imageio::write_pfm(&path, cam.width, cam.height, &ao)?;
            }
            rtao_curve.push(metrics::ao_error(&ao, &reference).mae);
        }
        if !dump.is_empty() {
            let d = PathBuf::from(&dump);
            let ao = rt.read_ao()?;
            hrtao_core::imageio::write_pfm(
                &d.join(format!("{key}_rtao_many.pfm")),
                cam.width,
                cam.height,
                &ao,
            )?;
        }
        let rtao_1 = rtao_curve[0];
        let rtao_eq = rtao_curve[eq_frames as usize - 1];
        // The still-camera curve: HRTAO after n frames beside per-pixel RTAO with the same total rays.
        let mut line = format!("| {key} |");
        for &(n, cum, e) in &hrtao_curve {
            if n.is_power_of_two() {
                let eq = ((cum as f64 / geometry / rays as f64).round() as usize).clamp(1, rtao_curve.len());
                line += &format!(" {e:.4} / {:.4} |", rtao_curve[eq - 1]);
            }
        }
        curves.push(line);
        println!(
            "| {key} | {rtao_1:.4} | {hrtao_1:.4} | {:.2} | {rtao_eq:.4} ({eq_frames}f) | {hrtao_n:.4} | {:.2} | {rays_px:.2} | {:.5} | {:.0}, {:.0} |",
            rtao_1 / hrtao_1,
            hrtao_n / rtao_eq,
            flicker / flicker_n.max(1) as f64,
            ms.0,
            ms.1
        );
    }
    println!("\nStill camera, MAE after n frames: HRTAO / per-pixel RTAO with the same total rays\n");
    let header: Vec<String> = (0..32)
        .map(|i| 1u32 << i)
        .take_while(|&n| n <= frames)
        .map(|n| n.to_string())
        .collect();
    println!("| scene | {} |", header.join(" | "));
    println!("|---|{}", "---|".repeat(header.len()));
    for c in curves {
        println!("{c}");
    }
    Ok(())
}
