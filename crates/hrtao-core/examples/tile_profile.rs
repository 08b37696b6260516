//! Cost of one background-screenshot tile (a development tool): renders tile K of a WxH shot of the bundled scene
//! until converged, as `view/shot.rs` does, and prints GPU milliseconds per pass summed over the tile's frames.
//!
//! `cargo run -p hrtao-core --example tile_profile -- [--size 3840x2160] [--slice 84560] [--tile 60]
//! [--set '{"variance_filter": false}'] [--primary raster|rayquery]`
mod cli_args;
use std::collections::BTreeMap;
use std::path::PathBuf;

use hrtao_core::renderer::AA_FRAMES;
use hrtao_core::tile::TileGrid;
use hrtao_core::{AoSettings, Camera, ContextOptions, Gpu, Renderer, SceneGpu};

fn main() -> anyhow::Result<()> {
    let mut args = cli_args::Args::from_env();
    let size = args.take("--size", "3840x2160");
    let slice: u64 = args.take("--slice", "84560").parse()?;
    let tile: usize = args.take("--tile", "60").parse()?;
    let extra = args.take("--set", "{}");
    let primary = args.primary();
    let (w, h) = size.split_once('x').unwrap();
    let (w, h): (u32, u32) = (w.parse()?, h.parse()?);
    let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let scene = hrtao_scene::load(assets.join("default.glb").to_str().unwrap(), &mut |_| {})?;
    let camera = Camera {
        width: w,
        height: h,
        ..Camera::load(&assets.join("default.camera.json"))?
    };
    let mut settings = cli_args::with_overrides(&AoSettings::default(), &extra)?;
    settings.map.rays_per_pixel = settings.still.still_samples.div_ceil(AA_FRAMES).clamp(1, 64);
    let margin = if settings.filter.filter_iterations > 0 {
        2 * ((1u32 << settings.filter.filter_iterations.min(8)) - 1) + 1
    } else {
        1
    };
    let grid = TileGrid::new(w, h, slice, margin);
    let (tw, th) = grid.render_size();
    let gpu = Gpu::new(&ContextOptions::default())?;
    let sg = SceneGpu::new(&gpu, &scene)?;
    let mut r = Renderer::new(&gpu)?;
    r.set_primary(primary);
    let frame = hrtao_core::FrameDesc {
        jitter: true,
        tile: Some(grid.tile(tile.min(grid.len() - 1))),
        ..hrtao_core::FrameDesc::new(
            &sg,
            scene.f(),
            Camera {
                width: tw,
                height: th,
                ..camera
            },
            &settings,
        )
    };
    println!("{} tiles of {tw}x{th} (margin {margin})", grid.len());
    let mut sums: BTreeMap<String, f64> = BTreeMap::new();
    let t0 = std::time::Instant::now();
    let (mut frames, mut gpu_total, mut rays) = (0, 0.0, 0u64);
    loop {
        let rep = r.render(&frame)?;
        frames += 1;
        gpu_total += rep.gpu_total_ms;
        rays += rep.rays;
        for (k, ms) in &rep.gpu_ms {
            *sums.entry(k.clone()).or_default() += ms;
        }
        if frames == 1 {
            println!(
                "frame 1: {:.0} ms wall, {:.0} ms GPU",
                rep.wall_ms, rep.gpu_total_ms
            );
        }
        if rep.converged || frames >= 64 {
            break;
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    println!(
        "{frames} frames, {wall:.1} s wall, {:.1} s GPU, {:.1} Mrays ({:.2} Mrays/s)",
        gpu_total / 1000.0,
        rays as f64 / 1e6,
        rays as f64 / 1e6 / wall
    );
    for (k, ms) in sums {
        println!("  {k:>14}: {:7.0} ms", ms);
    }
    Ok(())
}
