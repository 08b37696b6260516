//! Real spherical harmonics in the sky frame (b_z the zenith): the basis the sky light's cells will store their
//! directional visibility in (a transfer vector, Sloan et al. 2002), the projection of an environment onto it,
//! its rotation about the zenith (the environment rotation, free: no new rays), and the clamped-cosine
//! convolution of Ramamoorthi & Hanrahan 2001 that gives the light of an unshadowed surface.
//!
//! Index of (l, m): l(l + 1) + m, m in -l..=l; the basis is orthonormal over the sphere. m > 0 carries cos(mφ),
//! m < 0 sin(|m|φ), with φ = atan2(b_y, b_x) and the polar angle from +b_z.
use glam::DVec3;

/// The highest band this module evaluates.
pub const MAX_BAND: usize = 8;

/// Coefficients of bands 0..=`band`.
pub const fn coefficient_count(band: usize) -> usize {
    (band + 1) * (band + 1)
}

fn factorial(n: usize) -> f64 {
    (1..=n).map(|k| k as f64).product()
}

/// The associated Legendre polynomial P_l^m(x), m ≥ 0, with the Condon–Shortley phase (the usual recurrences).
fn legendre(l: usize, m: usize, x: f64) -> f64 {
    let mut pmm = 1.0;
    if m > 0 {
        let s = ((1.0 - x) * (1.0 + x)).max(0.0).sqrt();
        let mut odd = 1.0;
        for _ in 0..m {
            pmm *= -odd * s;
            odd += 2.0;
        }
    }
    if l == m {
        return pmm;
    }
    let mut pm1 = x * (2 * m + 1) as f64 * pmm;
    if l == m + 1 {
        return pm1;
    }
    let mut pll = 0.0;
    for ll in m + 2..=l {
        pll = ((2 * ll - 1) as f64 * x * pm1 - (ll + m - 1) as f64 * pmm) / (ll - m) as f64;
        pmm = pm1;
        pm1 = pll;
    }
    pll
}

/// Every basis function of bands 0..=`band` at the unit direction `b` (sky frame), into `out`.
pub fn eval(band: usize, b: DVec3, out: &mut [f64]) {
    assert!(band <= MAX_BAND && out.len() >= coefficient_count(band));
    let b = b.normalize();
    let (x, phi) = (b.z.clamp(-1.0, 1.0), b.y.atan2(b.x));
    for l in 0..=band {
        for m in 0..=l {
            let k = ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI) * factorial(l - m) / factorial(l + m))
                .sqrt();
            let p = legendre(l, m, x);
            let c = l * (l + 1);
            if m == 0 {
                out[c] = k * p;
            } else {
                let a = std::f64::consts::SQRT_2 * k * p;
                out[c + m] = a * (m as f64 * phi).cos();
                out[c - m] = a * (m as f64 * phi).sin();
            }
        }
    }
}

/// An RGB function of direction projected onto bands 0..=`band`: ∫ f(ω) Y_i(ω) dω per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct ShRgb {
    pub band: usize,
    pub coefficients: Vec<[f64; 3]>,
}

impl ShRgb {
    /// Projects `f` by `sphere_quadrature(rows)`.
    pub fn project(band: usize, rows: usize, f: impl Fn(DVec3) -> [f64; 3]) -> ShRgb {
        let n = coefficient_count(band);
        let mut coefficients = vec![[0.0; 3]; n];
        let mut y = vec![0.0; n];
        for (b, w) in sphere_quadrature(rows) {
            let v = f(b);
            eval(band, b, &mut y);
            for (acc, yi) in coefficients.iter_mut().zip(&y) {
                for ch in 0..3 {
                    acc[ch] += v[ch] * yi * w;
                }
            }
        }
        ShRgb { band, coefficients }
    }

    /// The function turned by `theta_deg` counter-clockwise seen from above (f′(b) = f(R_z(−θ)·b)).
    pub fn rotated_about_zenith(&self, theta_deg: f64) -> ShRgb {
        let t = theta_deg.to_radians();
        let mut out = self.clone();
        for l in 1..=self.band {
            let c = l * (l + 1);
            for m in 1..=l {
                let (s, co) = (m as f64 * t).sin_cos();
                let (cos_m, sin_m) = (self.coefficients[c + m], self.coefficients[c - m]);
                for ch in 0..3 {
                    out.coefficients[c + m][ch] = cos_m[ch] * co - sin_m[ch] * s;
                    out.coefficients[c - m][ch] = cos_m[ch] * s + sin_m[ch] * co;
                }
            }
        }
        out
    }

    /// The light of an unshadowed white Lambertian surface of normal `n`, (1/π) ∫ f(ω) max(0, n·ω) dω, from
    /// the coefficients: the clamped cosine's own coefficients Â_l (Ramamoorthi & Hanrahan 2001, eq. 8).
    pub fn unshadowed(&self, n: DVec3) -> [f64; 3] {
        let mut y = vec![0.0; coefficient_count(self.band)];
        eval(self.band, n, &mut y);
        let mut out = [0.0; 3];
        for (i, (c, yi)) in self.coefficients.iter().zip(&y).enumerate() {
            // Band l holds indices l²..(l + 1)².
            let l = (i as f64).sqrt() as usize;
            let a = clamped_cosine_band(l) / std::f64::consts::PI;
            for (o, ci) in out.iter_mut().zip(c) {
                *o += a * ci * yi;
            }
        }
        out
    }
}

/// A quadrature over the sphere: `rows` × 2·`rows` cells of equal latitude and longitude steps, each its centre's
/// direction and its solid angle (the band of latitudes' area over its columns); the weights sum to 4π.
pub fn sphere_quadrature(rows: usize) -> impl Iterator<Item = (DVec3, f64)> {
    let cols = 2 * rows;
    let (dt, dp) = (
        std::f64::consts::PI / rows as f64,
        2.0 * std::f64::consts::PI / cols as f64,
    );
    (0..rows).flat_map(move |r| {
        let theta = (r as f64 + 0.5) * dt;
        let w = ((r as f64 * dt).cos() - ((r + 1) as f64 * dt).cos()) * dp;
        (0..cols).map(move |c| {
            let phi = (c as f64 + 0.5) * dp;
            let b = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            (b, w)
        })
    })
}

/// Â_l: band l of max(0, cos θ) as a zonal kernel (4π/(2l+1))^½ times its coefficient; π, 2π/3, π/4, 0, −π/24, …
pub fn clamped_cosine_band(l: usize) -> f64 {
    use std::f64::consts::PI;
    match l {
        0 => PI,
        1 => 2.0 * PI / 3.0,
        _ if !l.is_multiple_of(2) => 0.0,
        _ => {
            let sign = if (l / 2).is_multiple_of(2) { -1.0 } else { 1.0 };
            2.0 * PI * sign / ((l + 2) as f64 * (l - 1) as f64) * factorial(l)
                / (2f64.powi(l as i32) * factorial(l / 2).powi(2))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The basis is orthonormal: its projection of each basis function is that function's unit vector.
    #[test]
    fn the_basis_is_orthonormal() {
        let band = 4;
        let n = coefficient_count(band);
        for i in 0..n {
            let p = ShRgb::project(band, 96, |b| {
                let mut y = vec![0.0; n];
                eval(band, b, &mut y);
                [y[i], 0.0, 0.0]
            });
            for (j, c) in p.coefficients.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((c[0] - want).abs() < 2e-3, "<Y{i}, Y{j}> = {}", c[0]);
            }
        }
    }

    /// The clamped cosine's bands against the closed forms.
    #[test]
    fn clamped_cosine_bands() {
        use std::f64::consts::PI;
        for (l, want) in [
            (0, PI),
            (1, 2.0 * PI / 3.0),
            (2, PI / 4.0),
            (3, 0.0),
            (4, -PI / 24.0),
            (6, PI / 64.0),
        ] {
            assert!((clamped_cosine_band(l) - want).abs() < 1e-12, "band {l}");
        }
    }

    /// Turning the coefficients equals projecting the turned function.
    #[test]
    fn rotation_about_the_zenith_turns_the_function() {
        let f = |b: DVec3| {
            let lobe = DVec3::new(0.7, 0.2, 0.6).normalize();
            let c = b.dot(lobe).max(0.0).powi(3);
            [c, 0.5 * c + b.x.max(0.0), 1.0]
        };
        let theta: f64 = 70.0;
        let turned = ShRgb::project(4, 128, |b| {
            let t = -theta.to_radians();
            f(DVec3::new(
                t.cos() * b.x - t.sin() * b.y,
                t.sin() * b.x + t.cos() * b.y,
                b.z,
            ))
        });
        let rotated = ShRgb::project(4, 128, f).rotated_about_zenith(theta);
        for (a, b) in turned.coefficients.iter().zip(&rotated.coefficients) {
            for ch in 0..3 {
                assert!((a[ch] - b[ch]).abs() < 1e-3, "{a:?} vs {b:?}");
            }
        }
    }
}
