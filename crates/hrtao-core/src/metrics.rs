//! Error metrics between AO images (used by tests, `hrtao bench` and reference comparisons).

/// Error of an AO image against a reference, over the pixels not open (AO < 0.999) in both.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct AoError {
    pub mae: f64,
    pub rmse: f64,
    pub pixels: usize,
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

#[cfg(test)]
mod tests {
    use super::*;

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
