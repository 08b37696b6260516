//! Error metrics between AO images (used by tests, `hrtao bench` and reference comparisons), and the
//! pixel-scale roughness of one AO image (grain that the true AO of a flat face does not have).
use crate::gpu::GPixel;

/// Error of an AO image against a reference, over the pixels not open (AO < 0.999) in both.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct AoError {
    pub mae: f64,
    pub rmse: f64,
    pub pixels: usize,
}

/// Error of a sky light image (linear RGB, background 0: `--light-out`) against a reference, over the pixels
/// that show the model in either: the mean over them and the channels of |L − L_ref|, and the reference's mean
/// there (the relative error is their ratio).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LightError {
    pub mae: f64,
    pub reference_mean: f64,
    pub pixels: usize,
}

impl LightError {
    /// The MAE relative to the reference's mean.
    pub fn relative(&self) -> f64 {
        self.mae / self.reference_mean.max(1e-12)
    }
}

pub fn light_error(image: &[[f32; 3]], reference: &[[f32; 3]]) -> LightError {
    let (mut abs, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for (a, r) in image.iter().zip(reference) {
        if a.iter().chain(r).all(|c| *c == 0.0) {
            continue;
        }
        for ch in 0..3 {
            abs += (a[ch] as f64 - r[ch] as f64).abs() / 3.0;
            sum += r[ch] as f64 / 3.0;
        }
        n += 1;
    }
    if n == 0 {
        return LightError::default();
    }
    LightError {
        mae: abs / n as f64,
        reference_mean: sum / n as f64,
        pixels: n,
    }
}

pub fn ao_error(image: &[f32], reference: &[f32]) -> AoError {
    let (mut abs, mut sq, mut n) = (0.0f64, 0.0f64, 0usize);
    for (a, r) in image.iter().zip(reference) {
        if *a < 0.999 || *r < 0.999 {
            let d = (*a as f64) - (*r as f64);
            abs += d.abs();
            sq += d * d;
            n += 1;
        }
    }
    if n == 0 {
        return AoError::default();
    }
    AoError {
        mae: abs / n as f64,
        rmse: (sq / n as f64).sqrt(),
        pixels: n,
    }
}

/// A pixel counts as occluded (and its roughness is measured) below this AO.
pub const ROUGHNESS_OCCLUDED: f32 = 0.95;
/// Two normals belong to one flat face when their dot product exceeds this (within about 8 degrees).
pub const ROUGHNESS_FLAT_DOT: f32 = 0.99;

/// The 8 neighbours of a pixel.
const RING: [(i32, i32); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Pixel-scale roughness of an AO image: mean |AO - median of its 8 neighbours| over the interior pixels of flat
/// faces (the pixel and its 8 neighbours hit geometry, the neighbours' normals within about 8 degrees of the
/// pixel's) that are occluded (`mask` < 0.95: a reference image, or the image itself). Over such pixels the true AO
/// is smooth, so what rises above a converged image's roughness is noise. Returns the mean and the number of
/// pixels measured; None when the sizes disagree or no pixel qualifies.
pub fn roughness_masked(
    ao: &[f32],
    gbuffer: &[GPixel],
    mask: &[f32],
    w: usize,
    h: usize,
) -> Option<(f32, usize)> {
    let n_px = w.checked_mul(h)?;
    if ao.len() != n_px || gbuffer.len() != n_px || mask.len() != n_px || w < 3 || h < 3 {
        return None;
    }
    let (mut sum, mut n) = (0.0f64, 0usize);
    let mut ring = [0.0f32; 8];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let p = &gbuffer[i];
            // NaN in the mask or the image never counts.
            let occluded = mask[i].is_finite() && mask[i] < ROUGHNESS_OCCLUDED;
            if p.t < 0.0 || !occluded || !ao[i].is_finite() {
                continue;
            }
            let mut flat = true;
            for (k, (dx, dy)) in RING.iter().enumerate() {
                let j = (y as i32 + dy) as usize * w + (x as i32 + dx) as usize;
                let q = &gbuffer[j];
                let dot: f32 = (0..3).map(|c| p.normal[c] * q.normal[c]).sum();
                flat &= q.t >= 0.0 && dot > ROUGHNESS_FLAT_DOT && ao[j].is_finite();
                ring[k] = ao[j];
            }
            if !flat {
                continue;
            }
            ring.sort_by(f32::total_cmp);
            sum += (ao[i] - 0.5 * (ring[3] + ring[4])).abs() as f64;
            n += 1;
        }
    }
    (n > 0).then(|| ((sum / n as f64) as f32, n))
}

/// `roughness_masked` with the image itself as the occlusion mask (its own AO < 0.95): the roughness of a frame
/// with no reference at hand (the viewer's `--ao-out`).
pub fn roughness(ao: &[f32], gbuffer: &[GPixel], w: usize, h: usize) -> Option<f32> {
    roughness_masked(ao, gbuffer, ao, w, h).map(|(r, _)| r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn px(normal: [f32; 3]) -> GPixel {
        GPixel {
            position: [0.0; 3],
            t: 1.0,
            normal,
            instance: 0,
            color: 0xff80_8080,
            flags: 0,
            shading: crate::gpu::pack_normal(normal),
        }
    }

    /// A deterministic ±`amp` pattern (a hash of the pixel index): white noise of known magnitude.
    fn noise(i: usize, amp: f32) -> f32 {
        let mut x = (i as u32).wrapping_mul(0x9E37_79B9) ^ 0x5bd1_e995;
        x ^= x >> 15;
        x = x.wrapping_mul(0x2c1b_3c6d);
        x ^= x >> 12;
        if x & 1 == 0 {
            amp
        } else {
            -amp
        }
    }

    #[test]
    fn a_flat_field_with_known_noise_has_the_expected_roughness() {
        let (w, h) = (64, 48);
        let g = vec![px([0.0, 0.0, 1.0]); w * h];
        // A smooth ramp has no pixel-scale roughness (the median of the ring is the pixel's own value).
        let ramp: Vec<f32> = (0..w * h).map(|i| 0.3 + 0.002 * (i % w) as f32).collect();
        let (r, n) = roughness_masked(&ramp, &g, &ramp, w, h).unwrap();
        assert!(r < 1e-6, "{r}");
        assert_eq!(n, (w - 2) * (h - 2));
        // ±a around 0.5 by fair coin flips: the ring's median is the pixel's own value (deviation 0, probability
        // 93/256), 0 (deviation a, 70/256) or the opposite (2a, 93/256): the expected roughness is exactly a.
        let a = 0.01;
        let noisy: Vec<f32> = (0..w * h).map(|i| 0.5 + noise(i, a)).collect();
        let r1 = roughness(&noisy, &g, w, h).unwrap();
        assert!((r1 - a).abs() < 0.1 * a, "{r1}");
        let louder: Vec<f32> = (0..w * h).map(|i| 0.5 + noise(i, 2.0 * a)).collect();
        let r2 = roughness(&louder, &g, w, h).unwrap();
        assert!((r2 / r1 - 2.0).abs() < 1e-3, "{r1} {r2}");
        // Unoccluded pixels (>= 0.95) are not measured: an open image has no roughness.
        let open: Vec<f32> = noisy.iter().map(|v| v + 0.49).collect();
        assert_eq!(roughness(&open, &g, w, h), None);
        // Size mismatch, tiny images.
        assert_eq!(roughness(&noisy[1..], &g[1..], w, h - 1), None);
        assert_eq!(roughness(&[0.5; 4], &g[..4], 2, 2), None);
    }

    #[test]
    fn a_step_across_a_crease_is_not_counted() {
        // Left half faces +z with AO 0.2, right half faces +x with AO 0.8: a crease with a step in AO. Pixels
        // whose ring crosses the crease are not flat and are skipped; the rest are constant: roughness 0.
        let (w, h) = (32, 16);
        let g: Vec<GPixel> = (0..w * h)
            .map(|i| {
                px(if i % w < w / 2 {
                    [0.0, 0.0, 1.0]
                } else {
                    [1.0, 0.0, 0.0]
                })
            })
            .collect();
        let ao: Vec<f32> = (0..w * h)
            .map(|i| if i % w < w / 2 { 0.2 } else { 0.8 })
            .collect();
        let (r, n) = roughness_masked(&ao, &g, &ao, w, h).unwrap();
        assert_eq!(r, 0.0);
        // The two columns next to the crease are left out.
        assert_eq!(n, (w - 4) * (h - 2));
        // On one flat face a one-pixel line of 0.8 across the 0.2 counts: 0.6 on each of its interior pixels.
        let flat = vec![px([0.0, 0.0, 1.0]); w * h];
        let line: Vec<f32> = (0..w * h)
            .map(|i| if i % w == w / 2 { 0.8 } else { 0.2 })
            .collect();
        let (r, n) = roughness_masked(&line, &flat, &vec![0.0; w * h], w, h).unwrap();
        assert_eq!(n, (w - 2) * (h - 2));
        assert!((r - 0.6 / (w - 2) as f32).abs() < 1e-6, "{r}");
        // The same line on a crease (its own normal) is not counted.
        let mut crease = flat.clone();
        for y in 0..h {
            crease[y * w + w / 2].normal = [1.0, 0.0, 0.0];
        }
        let (r, n) = roughness_masked(&line, &crease, &vec![0.0; w * h], w, h).unwrap();
        assert_eq!((r, n), (0.0, (w - 5) * (h - 2)));
        // A miss (t < 0) in the ring excludes the pixel too.
        let mut holes = flat.clone();
        for y in 0..h {
            holes[y * w + w / 2].t = -1.0;
        }
        let (_, n) = roughness_masked(&ao, &holes, &ao, w, h).unwrap();
        assert_eq!(n, (w - 5) * (h - 2));
    }

    #[test]
    fn error_ignores_pixels_open_in_both() {
        let a = [1.0, 0.5, 0.25, 1.0];
        let r = [1.0, 0.7, 0.25, 0.9];
        let e = ao_error(&a, &r);
        assert_eq!(e.pixels, 3);
        assert!((e.mae - (0.2 + 0.0 + 0.1) / 3.0).abs() < 1e-6);
        assert!((e.rmse - ((0.04 + 0.01) / 3.0f64).sqrt()).abs() < 1e-6);
        assert_eq!(ao_error(&[1.0], &[1.0]), AoError::default());
    }
}
