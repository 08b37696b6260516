//! Pooled residual control variate (ours, `YoungMapSettings::pooled_residual`, shaders/pooled_residual.glsl):
//! after the filter, a pixel of a young cell is corrected by the rays it and its same-surface 3x3 neighbours
//! traced this frame, where they differ from the cell by more than their noise. Phase 1 of the corrections pass.
use super::{Correction, YoungFrame};

/// Its mask in the corrections pass and its phases, generated from its shader file.
const CORRECTION: Correction = super::generated::POOLED_RESIDUAL;

/// Whether it runs in `frame`, as its correction.
pub fn correction(frame: &YoungFrame) -> Option<Correction> {
    (frame.young && frame.settings.young.pooled_residual).then_some(CORRECTION)
}

#[cfg(test)]
mod tests {
    use crate::testkit::*;
    use crate::{AoSettings, SceneGpu};

    /// One frame from an empty map at 8 rays per pixel on the cycloidal gearbox (320x180) against its Cycles
    /// reference: the correction lowers the error at the same rays (measured 0.0185 -> 0.0166, the same on a second
    /// run; the bound asks for half of that gain).
    #[test]
    fn pooled_residual_cuts_first_frame_error_at_equal_rays() {
        let gpu = gpu();
        let (scene, cam, radius) = shared_scene("cycloidal", 320, 180);
        let cycles = cycles_ref("cycloidal", 320, 180);
        let sg = SceneGpu::new(&gpu, &scene).expect("scene upload");
        let first_frame = |settings: AoSettings| {
            let mut r = Headless::new(&gpu, cam.width, cam.height, settings).expect("renderer");
            let rays = r.render(&sg, scene.f(), &cam).expect("frame").rays;
            (mae(&r.read_ao().unwrap(), &cycles), rays)
        };
        let ours = hrtao(8, radius);
        assert!(ours.young.pooled_residual, "on by default");
        assert!(!ours.paper().young.pooled_residual, "off in the paper's mode");
        let (before, rays_before) = first_frame({
            let mut s = ours.clone();
            s.young.pooled_residual = false;
            s
        });
        let (after, rays_after) = first_frame(ours);
        println!(
            "cycloidal 320x180, HRTAO 1 frame: {before:.4} -> {after:.4} ({rays_before} / {rays_after} rays)"
        );
        assert!(
            (rays_after as f64) <= rays_before as f64 * 1.01,
            "no more rays: {rays_after} against {rays_before}"
        );
        assert!(after < 0.95 * before, "pooled residual {after} against {before}");
        assert_clean(&gpu);
    }

    /// Once every cell a pixel uses is full (max_samples), nothing traces and the pass leaves the image as the
    /// paper's resolve and filter made it: the same image with the correction on and off.
    #[test]
    fn pooled_residual_leaves_full_cells_alone() {
        let gpu = gpu();
        let (scene, cam, radius) = shared_scene("cycloidal", 160, 90);
        let sg = SceneGpu::new(&gpu, &scene).expect("scene upload");
        // One map for both images: which pixel takes which of a cell's samples depends on the GPU's thread order,
        // so two renderers fill their cells with different rays (a few pixels differ between runs).
        let settings = {
            let mut s = hrtao(8, radius);
            s.map.max_samples = 16;
            s.still.refine = false;
            s.young.pooled_residual = true;
            s
        };
        let mut r = Headless::new(&gpu, cam.width, cam.height, settings.clone()).expect("renderer");
        let mut last_rays = 0;
        for _ in 0..6 {
            last_rays = r.render(&sg, scene.f(), &cam).expect("frame").rays;
        }
        let on = r.read_ao().unwrap();
        r.set_settings({
            let mut s = settings;
            s.young.pooled_residual = false;
            s
        })
        .expect("settings");
        r.render(&sg, scene.f(), &cam).expect("frame");
        let off = r.read_ao().unwrap();
        assert_eq!(last_rays, 0, "the cells are full: the last frame traces nothing");
        let differing = off.iter().zip(&on).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "pixels changed by the correction on full cells");
        assert_clean(&gpu);
    }
}
