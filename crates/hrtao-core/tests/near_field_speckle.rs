//! The near-field control variate (ours, `near_field`, near_field.glsl) corrects a young pixel with its own
//! few rays. Where a pixel's rays were unlucky and its neighbours' were not, that correction is a dark or light
//! dot: the first frames of a new view speckled. The correction now takes its strength from the rays of the
//! pixel's same-surface 3x3 neighbours (pool.glsl), which a contact shadow shares and an unlucky pixel does not.
mod common;
use common::*;

/// Pixel-scale roughness of an AO image (`hrtao_core::metrics::roughness_masked`) over the occluded pixels of
/// flat faces, Cycles (< 0.95) saying which are occluded. Over such pixels the true AO is smooth, so what rises
/// above the reference's roughness is noise.
fn roughness(ao: &[f32], f: &FirstFrames, w: usize, h: usize) -> f32 {
    let (r, n) =
        hrtao_core::metrics::roughness_masked(ao, &f.gbuffer, &f.cycles, w, h).expect("occluded flat pixels");
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
