//! Adaptive sampling of young cells (ours, `YoungMapSettings::adaptive_rays`, shaders/adaptive_rays.glsl): in a
//! young map's frame the ray-tracing update traces a quarter of the budget, weighs the pixels by the noise their
//! cells still have, and shares the rest by those weights.
use super::YoungFrame;

/// The ray-tracing update's dispatches (`push.x` of ao_update.comp, adaptive_rays.glsl `PHASE_*`): the whole
/// budget in one, or split in three (the first quarter, the weights, the rest).
pub fn update_phases(frame: &YoungFrame) -> &'static [u32] {
    if frame.young && frame.settings.young.adaptive_rays {
        &[1, 2, 3]
    } else {
        &[0]
    }
}

/// The most rays a queued pixel traces in the ray-tracing update's dispatch `phase` (adaptive_rays.glsl's
/// `PHASE_*`) with a budget of `rays_per_pixel`, for the dispatch plan (`crate::dispatch_plan`): the budget,
/// or a quarter of it in PHASE_FIRST; 1 for PHASE_WEIGH, which traces none but must run once per pixel (one
/// chunk of rays, bands of rows still); PHASE_SECOND gives a pixel up to ADAPT_MAX_SHARE = 4 times its even
/// share of the other three quarters, rounded up: at most 4 x the budget. An underestimate would cost only the
/// bound: the last chunk traces to the end of the pixel's budget (`Chunk::last_rays`).
pub fn update_rays(phase: u32, rays_per_pixel: u32) -> u32 {
    match phase {
        2 => 1,
        3 => 4 * rays_per_pixel,
        _ => rays_per_pixel,
    }
}

#[cfg(test)]
mod tests {
    use crate::testkit::*;

    /// HRTAO's first frame with the same total rays (ours: adaptive sampling,
    /// docs/algorithm.md): on a wedge most of the floor is open, and its cells come out open after a quarter of
    /// the budget; the rest of the frame's rays go to the noisy cells near the wall. Mean |AO - analytic| over the
    /// floor pixels within R of the wall, one frame from an empty map at 8 rays per pixel: the paper's
    /// allocation (every pixel traces its 8 rays) and finest level against the defaults.
    #[test]
    fn adaptive_sampling_cuts_first_frame_error_at_equal_rays() {
        let gpu = gpu();
        let scene = wedge();
        let radius = 1.0;
        let cam = wedge_camera([10.0, 0.0, 12.0], [4.0, 0.0, 0.0]);
        let sg = hrtao_core::SceneGpu::new(&gpu, &scene).expect("scene upload");
        let first_frame = |settings: hrtao_core::AoSettings| {
            let mut r = Headless::new(&gpu, cam.width, cam.height, settings).expect("renderer");
            let rays = r.render(&sg, scene.f(), &cam).expect("frame").rays;
            let ao = r.read_ao().unwrap();
            let gb = r.read_gbuffer().unwrap();
            let (error, n) = wedge_floor_error(&ao, &gb, radius, 0.01, radius);
            let (_, open) = wedge_floor_error(&ao, &gb, radius, radius, f32::INFINITY);
            assert!(
                n > 300 && open > n,
                "floor pixels near the wall ({n}) and open ({open})"
            );
            (error, rays)
        };
        let ours = hrtao(8, radius);
        assert!(ours.young.adaptive_rays, "on by default");
        let paper_like = {
            let mut s = ours.clone();
            s.young.adaptive_rays = false;
            s
        };
        let (before, rays_before) = first_frame(paper_like);
        let (after, rays_after) = first_frame(ours);
        println!(
            "wedge within R, HRTAO 1 frame: {before:.4} ({rays_before} rays), adaptive sampling {after:.4} \
             ({rays_after} rays)"
        );
        assert!(
            (rays_after as f64) <= rays_before as f64 * 1.01,
            "adaptive sampling keeps the budget: {rays_after} rays against {rays_before}"
        );
        assert!(
            after < 0.85 * before,
            "adaptive sampling {after} against {before}"
        );
        assert_clean(&gpu);
    }
}
