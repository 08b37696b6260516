//! The near-field control variate (ours, `near_weight`, docs/algorithm.md) corrects a young pixel with its own
//! few rays. Where a pixel's rays were unlucky and its neighbours' were not, that correction is a dark or light
//! dot: the first frames of a new view speckled. The correction now takes its strength from the rays of the
//! pixel's same-surface 3x3 neighbours (pool.glsl), which a contact shadow shares and an unlucky pixel does not.
mod common;
use common::*;

/// Pixel-scale roughness of an AO image: mean |AO - median of its 8 neighbours| over the interior pixels of
/// flat faces (the 8 neighbours' normals within 8 degrees of the pixel's) that are occluded (Cycles < 0.95).
/// Over such pixels the true AO is smooth, so what rises above the reference's roughness is noise.
fn roughness(ao: &[f32], f: &FirstFrames, w: usize, h: usize) -> f32 {
    let (mut sum, mut n) = (0.0f32, 0usize);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let p = &f.gbuffer[i];
            if p.t < 0.0 || f.cycles[i] >= 0.95 {
                continue;
            }
            let mut ring = Vec::with_capacity(8);
            let mut flat = true;
            for (dx, dy) in [
                (-1, -1),
                (0, -1),
                (1, -1),
                (-1, 0),
                (1, 0),
                (-1, 1),
                (0, 1),
                (1, 1),
            ] {
                let j = (y as i32 + dy) as usize * w + (x as i32 + dx) as usize;
                let q = &f.gbuffer[j];
                let dot: f32 = (0..3).map(|k| p.normal[k] * q.normal[k]).sum();
                flat &= q.t >= 0.0 && dot > 0.99;
                ring.push(ao[j]);
            }
            if !flat {
                continue;
            }
            ring.sort_by(|a, b| a.partial_cmp(b).unwrap());
            sum += (ao[i] - 0.5 * (ring[3] + ring[4])).abs();
            n += 1;
        }
    }
    assert!(n > 5000, "enough occluded flat pixels ({n})");
    sum / n as f32
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
