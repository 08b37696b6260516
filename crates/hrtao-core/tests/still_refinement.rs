//! Still-camera refinement (ours, docs/algorithm.md) against the paper's behaviour on an analytic wedge, validation
//! on: the default refinement (pooled own-ray residuals, a smoothed still image) keeps a still image as steady as
//! the paper's cells (flicker), and still converges to the ray-traced value where the cells are biased (the
//! contact shadow at the crease).
mod common;
use common::*;
use hrtao_core::gpu::GPixel;
use hrtao_core::{AoSettings, Camera, SceneGpu};
use hrtao_scene::Scene;

const RADIUS: f32 = 4.0;
const FRAMES: u32 = 16;

/// A still run: flicker (mean |ΔAO| between consecutive frames after frame 4, as `hrtao bench`) and the last
/// image with its G-buffer.
fn still_run(
    gpu: &std::sync::Arc<hrtao_core::Gpu>,
    scene: &Scene,
    cam: &Camera,
    settings: AoSettings,
) -> (f64, Vec<f32>, Vec<GPixel>) {
    let sg = SceneGpu::new(gpu, scene).unwrap();
    let mut r = Headless::new(gpu, cam.width, cam.height, settings).unwrap();
    let (mut flicker, mut n) = (0.0, 0);
    let mut prev = Vec::new();
    for f in 1..=FRAMES {
        r.render(&sg, scene.f(), cam).unwrap();
        let img = r.read_ao().unwrap();
        if f >= 5 {
            flicker += img
                .iter()
                .zip(&prev)
                .map(|(a, b): (&f32, &f32)| (a - b).abs() as f64)
                .sum::<f64>()
                / img.len() as f64;
            n += 1;
        }
        prev = img;
    }
    (flicker / n as f64, prev, r.read_gbuffer().unwrap())
}

/// Mean |AO - analytic| over floor pixels with `lo <= x < hi` (distance from the wall).
fn wedge_error(ao: &[f32], gb: &[GPixel], lo: f32, hi: f32) -> f32 {
    let (e, n) = wedge_floor_error(ao, gb, RADIUS, lo, hi);
    assert!(n > 100, "enough floor pixels in [{lo}, {hi}): {n}");
    e
}

#[test]
fn still_wedge_flickers_no_more_than_the_paper_and_converges_at_the_crease() {
    let gpu = gpu();
    let (scene, cam) = (wedge(), wedge_camera([6.0, 0.0, 8.0], [2.0, 0.0, 0.0]));
    let ours = hrtao(8, RADIUS);
    let (flicker, ao, gb) = still_run(&gpu, &scene, &cam, ours.clone());
    let (paper_flicker, paper_ao, _) = still_run(&gpu, &scene, &cam, ours.paper());
    let all = wedge_error(&ao, &gb, 0.02, 100.0);
    let paper_all = wedge_error(&paper_ao, &gb, 0.02, 100.0);
    // Cells far wider than the contact shadow (s_p 16, no cap against R): the paper's estimate is biased at
    // the crease, and the refinement must converge past it.
    let coarse = {
        let mut s = ours.clone();
        s.map.s_p = 16.0;
        s.map.cell_cap = false;
        s
    };
    let (_, coarse_ao, coarse_gb) = still_run(&gpu, &scene, &cam, coarse.clone());
    let (_, coarse_paper_ao, _) = still_run(&gpu, &scene, &cam, coarse.paper());
    let crease = (0.02, 1.0);
    let (ours_crease, paper_crease) = (
        wedge_error(&coarse_ao, &coarse_gb, crease.0, crease.1),
        wedge_error(&coarse_paper_ao, &coarse_gb, crease.0, crease.1),
    );
    println!(
        "wedge, {FRAMES} still frames: flicker ours {flicker:.6}, paper \
         {paper_flicker:.6}; MAE ours {all:.4}, paper {paper_all:.4}; coarse cells, MAE at the crease ours \
         {ours_crease:.4}, paper {paper_crease:.4}"
    );
    assert!(
        flicker <= paper_flicker,
        "still flicker {flicker} above the paper's {paper_flicker}"
    );
    assert!(
        ours_crease < 0.8 * paper_crease,
        "the crease does not converge past the cells' bias: {ours_crease} vs the paper's {paper_crease}"
    );
    assert!(
        all < 0.005,
        "MAE against the analytic wedge {all} (paper {paper_all})"
    );
    assert_clean(&gpu);
}

/// "Clear cache" (the panel's button, a new scene, each of `hrtao bench`'s first-frame repetitions) forgets all
/// cached AO: after a still image's refinement frames, the next frame is a first frame from an empty map, as a
/// fresh renderer's (no accumulated frames, no refinement rays, the same rays). Before, it cleared the map only,
/// and the next frame was the still image's next refinement frame (the bench timed those as first frames).
#[test]
fn clear_cache_starts_from_an_empty_map_and_a_new_still_image() {
    let (gpu, scene, cam, sg) = on_gpu((wedge(), wedge_camera([6.0, 0.0, 8.0], [2.0, 0.0, 0.0])));
    let settings = hrtao(4, RADIUS);
    assert!(settings.still.refine, "refinement on by default");
    let fresh = {
        let mut r = Headless::new(&gpu, cam.width, cam.height, settings.clone()).unwrap();
        r.render(&sg, scene.f(), &cam).unwrap()
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
    for _ in 0..3 {
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    let refining = r.render(&sg, scene.f(), &cam).unwrap();
    assert!(
        refining.accumulated_frames > 1 && refining.refine_rays > 0,
        "the still image refines: {} frames, {} own rays",
        refining.accumulated_frames,
        refining.refine_rays
    );
    r.r.clear_cache().unwrap();
    let first = r.render(&sg, scene.f(), &cam).unwrap();
    println!(
        "after clear_cache: {} accumulated frames, {} refinement rays, {} rays (fresh renderer: {} / {} / {})",
        first.accumulated_frames,
        first.refine_rays,
        first.rays,
        fresh.accumulated_frames,
        fresh.refine_rays,
        fresh.rays
    );
    assert_eq!(
        (first.accumulated_frames, first.refine_rays),
        (fresh.accumulated_frames, fresh.refine_rays),
        "a first frame"
    );
    assert!(
        (first.rays as f64 - fresh.rays as f64).abs() <= 0.01 * fresh.rays as f64,
        "a first frame's rays: {} against {}",
        first.rays,
        fresh.rays
    );
    assert_clean(&gpu);
}
