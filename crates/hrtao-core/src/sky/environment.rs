//! The environment that lights the sky mode, as the measurable contract fixes it (`--light-out`): directions in
//! the scene file's coordinates are turned into the sky frame b (b_z the zenith: b = (x, −z, y) for a Y-up file,
//! as Blender's glTF import does, b = (x, y, z) for a Z-up one), rotated by θ counter-clockwise seen from above
//! (b′ = R_z(−θ)·b), and then:
//! - `Uniform`: E = (1, 1, 1);
//! - `Gradient`: E = G + (S − G)·(1 + b′_z)/2, S = (0.6, 0.8, 1.0) at the zenith, G = (0.4, 0.3, 0.2) at the nadir;
//! - `Equirect`: a Radiance .hdr, bilinear at u = 0.5 − atan2(b′_y, b′_x)/2π from the left edge (wrapping: the
//!   image centre faces +b_x) and t = 0.5 − asin(b′_z)/π from the top row (the first row is the zenith).
//!
//! Scaled by the intensity K. The renderer will light with its spherical-harmonic projection (`sh.rs`).
use std::path::Path;

use glam::DVec3;

use crate::camera::UpAxis;

use super::sh::ShRgb;

/// Colour at the zenith of the built-in gradient.
pub const GRADIENT_SKY: [f64; 3] = [0.6, 0.8, 1.0];
/// Colour at the nadir of the built-in gradient.
pub const GRADIENT_GROUND: [f64; 3] = [0.4, 0.3, 0.2];

/// An equirectangular environment image: linear RGB, row 0 the zenith.
#[derive(Clone, Debug, PartialEq)]
pub struct Equirect {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl Equirect {
    /// Reads a Radiance RGBE (.hdr) file; a clear error for anything else or an unusable size.
    pub fn load(path: &Path) -> anyhow::Result<Equirect> {
        use anyhow::Context;
        let file = std::fs::File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
        let decoder = image::codecs::hdr::HdrDecoder::new(std::io::BufReader::new(file))
            .with_context(|| format!("{} is not a Radiance .hdr image", path.display()))?;
        let img = image::DynamicImage::from_decoder(decoder)
            .with_context(|| format!("cannot decode {}", path.display()))?
            .into_rgb32f();
        let (width, height) = (img.width() as usize, img.height() as usize);
        anyhow::ensure!(
            width >= 2 && height >= 1,
            "{}: a {width}×{height} environment is too small",
            path.display()
        );
        let pixels: Vec<[f32; 3]> = img.pixels().map(|p| p.0).collect();
        anyhow::ensure!(
            pixels
                .iter()
                .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)),
            "{}: the environment has negative or non-finite pixels",
            path.display()
        );
        Ok(Equirect {
            width,
            height,
            pixels,
        })
    }

    fn texel(&self, x: isize, y: isize) -> [f64; 3] {
        let x = x.rem_euclid(self.width as isize) as usize;
        let y = y.clamp(0, self.height as isize - 1) as usize;
        self.pixels[y * self.width + x].map(f64::from)
    }

    /// Bilinear at (u, t) in [0, 1]² (pixel centres at (i + ½)/W, (j + ½)/H), wrapping in u, clamped in t.
    pub fn bilinear(&self, u: f64, t: f64) -> [f64; 3] {
        let (x, y) = (u * self.width as f64 - 0.5, t * self.height as f64 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as isize, y0 as isize);
        let mut out = [0.0; 3];
        for (dx, dy, w) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let p = self.texel(x0 + dx, y0 + dy);
            for ch in 0..3 {
                out[ch] += w * p[ch];
            }
        }
        out
    }
}

/// What lights the sky mode.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    Uniform,
    Gradient,
    Equirect(Equirect),
}

/// The sky frame's direction of a direction in the scene file's coordinates.
/// The sky frame is the up axis's right-handed frame (e1, e2, up): the zenith is +z.
pub fn sky_frame(d: DVec3, up: UpAxis) -> DVec3 {
    up.to_frame(d)
}

/// b′ = R_z(−θ)·b: the environment turned by θ counter-clockwise seen from above.
pub fn rotate(b: DVec3, theta_deg: f64) -> DVec3 {
    let (s, c) = (-theta_deg.to_radians()).sin_cos();
    DVec3::new(c * b.x - s * b.y, s * b.x + c * b.y, b.z)
}

impl Environment {
    /// E at the sky-frame direction b′ (already rotated), intensity 1.
    pub fn radiance(&self, b: DVec3) -> [f64; 3] {
        let b = b.normalize();
        match self {
            Environment::Uniform => [1.0; 3],
            Environment::Gradient => {
                let s = 0.5 * (1.0 + b.z);
                std::array::from_fn(|ch| GRADIENT_GROUND[ch] + (GRADIENT_SKY[ch] - GRADIENT_GROUND[ch]) * s)
            }
            Environment::Equirect(img) => {
                let u = 0.5 - b.y.atan2(b.x) / (2.0 * std::f64::consts::PI);
                let t = 0.5 - b.z.clamp(-1.0, 1.0).asin() / std::f64::consts::PI;
                img.bilinear(u, t)
            }
        }
    }

    /// The projection onto bands 0..=`band` at rotation 0 (rotate the result with `ShRgb::rotated_about_zenith`).
    /// The quadrature is finer than the image's pixels.
    pub fn project(&self, band: usize) -> ShRgb {
        let rows = match self {
            Environment::Equirect(img) => (2 * img.height).max(64),
            _ => 64,
        };
        ShRgb::project(band, rows, |b| self.radiance(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// (1/π) ∫ E(ω) max(0, n·ω) dω by a fine quadrature: the light of an open white surface.
    fn unshadowed_exact(env: &Environment, n: DVec3) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (b, w) in super::super::sh::sphere_quadrature(256) {
            let k = w * b.dot(n).max(0.0) / std::f64::consts::PI;
            let e = env.radiance(b);
            for ch in 0..3 {
                out[ch] += k * e[ch];
            }
        }
        out
    }

    fn normals() -> Vec<DVec3> {
        let mut v = Vec::new();
        for i in 0..24 {
            let z = -1.0 + (i as f64 + 0.5) / 12.0;
            let phi = i as f64 * 2.399963;
            let s = (1.0 - z * z).sqrt();
            v.push(DVec3::new(s * phi.cos(), s * phi.sin(), z));
        }
        v
    }

    /// The contract's anchors: an open surface under `uniform` gives 1; `gradient` is linear in b_z, so bands
    /// 0–1 light any open surface exactly (its zenith-facing light is (S + G)/2 + (S − G)/3).
    #[test]
    fn uniform_and_gradient_are_exact_in_the_first_bands() {
        for n in normals() {
            let u = Environment::Uniform.project(1).unshadowed(n);
            assert!(u.iter().all(|c| (c - 1.0).abs() < 1e-3), "{u:?}");
            let g = Environment::Gradient.project(1).unshadowed(n);
            let exact = unshadowed_exact(&Environment::Gradient, n);
            for ch in 0..3 {
                assert!((g[ch] - exact[ch]).abs() < 2e-3, "{g:?} vs {exact:?} at {n}");
            }
        }
        let up = Environment::Gradient.project(1).unshadowed(DVec3::Z);
        for ch in 0..3 {
            let want = 0.5 * (GRADIENT_SKY[ch] + GRADIENT_GROUND[ch])
                + (GRADIENT_SKY[ch] - GRADIENT_GROUND[ch]) / 3.0;
            assert!((up[ch] - want).abs() < 2e-3, "{up:?}");
        }
    }

    /// The frame and the image lookup: a Y-up file's +y is the zenith (row 0), its +x the image centre, and
    /// a turn of 90° brings what faced +b_y to +b_x.
    #[test]
    fn the_frame_and_the_equirect_lookup_follow_the_contract() {
        assert_eq!(sky_frame(DVec3::Y, UpAxis::Y), DVec3::Z);
        assert_eq!(sky_frame(DVec3::Z, UpAxis::Y), -DVec3::Y);
        assert_eq!(sky_frame(DVec3::Z, UpAxis::Z), DVec3::Z);
        // A 4×2 image whose pixels are their own indices.
        let img = Equirect {
            width: 4,
            height: 2,
            pixels: (0..8).map(|i| [i as f32, 0.0, 0.0]).collect(),
        };
        let env = Environment::Equirect(img.clone());
        // +b_x is u = 0.5 (between columns 1 and 2) on the horizon t = 0.5 (between rows 0 and 1).
        let e = env.radiance(DVec3::new(1.0, 0.0, 0.0));
        assert!((e[0] - 3.5).abs() < 1e-9, "{e:?}: the mean of pixels 1, 2, 5, 6");
        // Straight up: row 0 only, the mean of the row's two pixels around u (clamped in t).
        let zenith = img.bilinear(0.5, 0.0);
        assert!((zenith[0] - 1.5).abs() < 1e-9, "{zenith:?}");
        // Wrapping: u = 0 blends column 3 and column 0.
        assert!((img.bilinear(0.0, 0.25)[0] - 1.5).abs() < 1e-9);
        // The turn: b′ of +b_x turned by 90° is −b_y, what faced −b_y before now lights +b_x.
        let turned = rotate(DVec3::X, 90.0);
        assert!((turned - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12, "{turned}");
    }

    /// The sky references' test environment (testdata/env/sky_lobe_64x32.hdr, scripts/make-sky-hdr.py): the
    /// gradient plus a broad warm lobe (2.0, 1.4, 0.8)·max(0, b·l)⁸ at azimuth 30°, elevation 30°.
    fn lobe_environment(b: DVec3) -> [f64; 3] {
        let (az, el) = (30f64.to_radians(), 30f64.to_radians());
        let lobe = DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        let g = Environment::Gradient.radiance(b);
        let k = b.normalize().dot(lobe).max(0.0).powi(8);
        [g[0] + 2.0 * k, g[1] + 1.4 * k, g[2] + 0.8 * k]
    }

    fn committed_lobe() -> Environment {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/env/sky_lobe_64x32.hdr");
        Environment::Equirect(Equirect::load(&path).unwrap())
    }

    /// The committed .hdr reads back (image's Radiance decoder) as the formula at each pixel centre, within
    /// RGBE's precision (a 1/256 step of the largest channel), and row 0 is the zenith.
    #[test]
    fn the_committed_test_environment_reads_back_as_its_formula() {
        let Environment::Equirect(img) = committed_lobe() else {
            unreachable!()
        };
        assert_eq!((img.width, img.height), (64, 32));
        for j in 0..img.height {
            for i in 0..img.width {
                let u = (i as f64 + 0.5) / img.width as f64;
                let t = (j as f64 + 0.5) / img.height as f64;
                let (phi, el) = (
                    (0.5 - u) * 2.0 * std::f64::consts::PI,
                    (0.5 - t) * std::f64::consts::PI,
                );
                let b = DVec3::new(el.cos() * phi.cos(), el.cos() * phi.sin(), el.sin());
                let want = lobe_environment(b);
                let got = img.pixels[j * img.width + i];
                let step = want.iter().cloned().fold(0.0, f64::max) / 128.0;
                for ch in 0..3 {
                    assert!(
                        (got[ch] as f64 - want[ch]).abs() <= step,
                        "pixel {i},{j}: {got:?} vs {want:?}"
                    );
                }
            }
        }
        // The top rows are the sky's blue, the bottom rows the ground's brown.
        assert!(img.pixels[0][2] > img.pixels[0][0] && img.pixels[31 * 64][0] > img.pixels[31 * 64][2]);
    }

    /// The test environment is not band-limited: how well the bands light an open surface, band by band. The
    /// clamped cosine's bands fall as l^−2.5, so bands 0–2 stay within a few per cent (Ramamoorthi & Hanrahan).
    #[test]
    fn a_lobe_lights_an_open_surface_within_a_few_percent_from_band_2() {
        let env = committed_lobe();
        let mut worst = [0.0f64; 5];
        for n in normals() {
            let exact = unshadowed_exact(&env, n);
            for (band, worst) in worst.iter_mut().enumerate() {
                let sh = env.project(band).unshadowed(n);
                for ch in 0..3 {
                    *worst = worst.max((sh[ch] - exact[ch]).abs() / exact[ch]);
                }
            }
        }
        eprintln!("worst relative error of an open surface's light, bands 0..=0..4: {worst:?}");
        assert!(worst[1] > worst[2], "band 2 helps: {worst:?}");
        assert!(worst[2] < 0.05 && worst[4] < 0.03, "{worst:?}");
    }
}
