//! Near-field control variate (ours, `YoungMapSettings::near_field`, shaders/near_field.glsl): in a young map's
//! frame the ray-tracing update classifies its rays by whether they hit within half the AO radius, and the
//! resolve corrects each pixel's cell estimate by its own near-open fraction minus its cells'.
use super::YoungFrame;
use crate::gpu;

/// Its share of `FrameGlobals::flags`.
pub fn flags(frame: &YoungFrame) -> u32 {
    if frame.young && frame.settings.young.near_field {
        gpu::FLAG_NEAR_FIELD
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use crate::testkit::*;

    /// HRTAO's first frame near a contact: a cell averages the AO of floor pixels near and far from the wall, so
    /// the pixels closest to the crease come out too bright; each pixel's own near-open rays correct that. Mean
    /// |AO - analytic| over the floor pixels within R/4 of the wall (one finest cell), one frame from an empty map,
    /// without the correction and with it (the other settings at their defaults, as in the ablation's row).
    #[test]
    fn near_field_control_variate_cuts_contact_error() {
        let gpu = gpu();
        let scene = wedge();
        let radius = 1.0;
        let cam = wedge_camera([6.0, 0.0, 8.0], [1.0, 0.0, 0.0]);
        let contact_error = |settings: hrtao_core::AoSettings| {
            let (r, _sg) = render(&gpu, &scene, &cam, settings, 1);
            let ao = r.read_ao().unwrap();
            let gb = r.read_gbuffer().unwrap();
            let (error, n) = wedge_floor_error(&ao, &gb, radius, 0.01, radius / 4.0);
            assert!(n > 200, "enough floor pixels near the crease ({n})");
            error
        };
        let ours = hrtao(8, radius);
        assert!(ours.young.near_field, "the correction is on by default");
        let cells = contact_error({
            let mut s = ours.clone();
            s.young.near_field = false;
            s
        });
        let corrected = contact_error(ours);
        println!("wedge contact, HRTAO 1 frame: cells {cells:.4}, near-field corrected {corrected:.4}");
        // Measured 0.0162 -> 0.0134-0.0136 over three runs (contact detail, on in both, corrects part of the
        // crease too; with it off the cells alone were at 0.030 and corrected 0.014).
        assert!(
            corrected < 0.9 * cells,
            "near-field corrected contact error {corrected} (cells alone {cells})"
        );
        assert_clean(&gpu);
    }

    // The near-field control variate (ours, `near_field`, near_field.glsl) corrects a young pixel with its own
    // few rays. Where a pixel's rays were unlucky and its neighbours' were not, that correction is a dark or light
    // dot: the first frames of a new view speckled. The correction now takes its strength from the rays of the
    // pixel's same-surface 3x3 neighbours (pool.glsl), which a contact shadow shares and an unlucky pixel does not.

    /// Pixel-scale roughness of an AO image (`hrtao_core::metrics::roughness_masked`) over the occluded pixels of
    /// flat faces, Cycles (< 0.95) saying which are occluded. Over such pixels the true AO is smooth, so what rises
    /// above the reference's roughness is noise.
    fn roughness(ao: &[f32], f: &FirstFrames, w: usize, h: usize) -> f32 {
        let (r, n) = hrtao_core::metrics::roughness_masked(ao, &f.gbuffer, &f.cycles, w, h)
            .expect("occluded flat pixels");
        assert!(n > 5000, "enough occluded flat pixels ({n})");
        r
    }

    /// One frame from an empty map on the default scene's reference view (cycloidal) at the viewer's working size,
    /// 640x360, 8 rays: with the near-field correction (the default) the image is about as smooth as without it
    /// (before pooling: 0.0093 against 0.0055, Cycles 0.0053), and the correction still lowers the error.
    #[test]
    fn near_field_correction_does_not_speckle_the_first_frame() {
        let (w, h) = (640, 360);
        let f = first_frames("cycloidal", w, h, &[r#"{"near_field": false}"#, "{}"]);
        let rough: Vec<f32> =
            f.ao.iter()
                .map(|a| roughness(a, &f, w as usize, h as usize))
                .collect();
        let cycles = roughness(&f.cycles, &f, w as usize, h as usize);
        let err: Vec<f32> = f.ao.iter().map(|a| mae(a, &f.cycles)).collect();
        println!(
            "cycloidal 640x360, 1 frame: roughness without / with the near-field correction {:.4} / {:.4} (Cycles \
             {cycles:.4}); MAE {:.4} / {:.4}",
            rough[0], rough[1], err[0], err[1]
        );
        assert!(
            rough[1] < 1.25 * rough[0],
            "the correction speckles: roughness {} against {} without it",
            rough[1],
            rough[0]
        );
        assert!(
            err[1] < err[0] - 0.0003,
            "the correction lowers the error: {} against {}",
            err[1],
            err[0]
        );
    }
}
