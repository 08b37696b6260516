//! The sky light on the renderer's side: which environment the settings name (`EnvironmentSpec`), its
//! projection onto the transfer vectors' bands, loaded once per environment (`SkyLight`), and the frame's GPU
//! parameters: the sky frame's axes and the coefficients turned by the rotation and scaled by the intensity,
//! which are all a rotation changes (shaders/sky.glsl).
use std::path::PathBuf;

use glam::DVec3;

use super::environment::{sky_frame, Environment, Equirect};
use super::sh::ShRgb;
use crate::camera::UpAxis;
use crate::gpu::{self, FrameGlobals};
use crate::settings::LightSettings;

/// An environment as the settings and the command line name it.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentSpec {
    Uniform,
    Gradient,
    /// An equirectangular Radiance .hdr file.
    File(PathBuf),
}

impl EnvironmentSpec {
    /// `uniform`, `gradient`, or the path of a `.hdr` file (not read here); a clear error otherwise.
    pub fn parse(s: &str) -> Result<EnvironmentSpec, String> {
        match s {
            "uniform" => Ok(EnvironmentSpec::Uniform),
            "gradient" => Ok(EnvironmentSpec::Gradient),
            _ if s.to_ascii_lowercase().ends_with(".hdr") => Ok(EnvironmentSpec::File(PathBuf::from(s))),
            _ => Err(format!(
                "environment must be `uniform`, `gradient` or a Radiance .hdr file, got {s:?}"
            )),
        }
    }

    /// The environment it names (reads the file).
    pub fn load(&self) -> anyhow::Result<Environment> {
        Ok(match self {
            EnvironmentSpec::Uniform => Environment::Uniform,
            EnvironmentSpec::Gradient => Environment::Gradient,
            EnvironmentSpec::File(path) => Environment::Equirect(Equirect::load(path)?),
        })
    }
}

/// An environment's projection onto the transfer vectors' bands (`gpu::SKY_BAND`), at rotation 0 and
/// intensity 1, and the setting it was loaded for.
#[derive(Clone, Debug)]
pub struct SkyLight {
    environment: String,
    coefficients: ShRgb,
}

impl SkyLight {
    /// The environment `environment` (a `LightSettings::environment`) projected; an error names what is wrong.
    pub fn load(environment: &str) -> anyhow::Result<SkyLight> {
        let spec = EnvironmentSpec::parse(environment).map_err(anyhow::Error::msg)?;
        Ok(SkyLight {
            environment: environment.to_string(),
            coefficients: spec.load()?.project(gpu::SKY_BAND as usize),
        })
    }

    /// The setting it was loaded for.
    pub fn environment(&self) -> &str {
        &self.environment
    }

    /// The coefficients the composite lights with: turned by `rotation_deg`, scaled by `intensity`.
    pub fn coefficients(&self, rotation_deg: f32, intensity: f32) -> [f32; 3 * gpu::SKY_COEFFS as usize] {
        let turned = self.coefficients.rotated_about_zenith(rotation_deg as f64);
        let mut out = [0.0; 3 * gpu::SKY_COEFFS as usize];
        for (i, c) in turned.coefficients.iter().enumerate() {
            for ch in 0..3 {
                out[3 * i + ch] = (c[ch] * intensity as f64) as f32;
            }
        }
        out
    }

    /// The frame's sky parameters (`FrameGlobals::sky_*`, and FLAG_SKY): the sky frame of `light.sky_up` and
    /// the coefficients of `light`'s rotation and intensity. The buffers' addresses are the renderer's.
    pub fn write_gpu(&self, light: &LightSettings, g: &mut FrameGlobals) {
        g.flags |= gpu::FLAG_SKY;
        let [x, y, z] = sky_axes(light.sky_up);
        (g.sky_axis_x, g.sky_axis_y, g.sky_axis_z) = (x, y, z);
        g.sky_env = self.coefficients(light.environment_rotation, light.environment_intensity);
    }
}

/// The sky frame's axes in world coordinates: b_i = axis_i · d (`environment::sky_frame`).
pub fn sky_axes(up: UpAxis) -> [[f32; 4]; 3] {
    let row = |i: usize| {
        let mut e = [0.0f64; 3];
        // Column i of the linear map d -> sky_frame(d), as a row of the inverse's transpose: the map is a
        // rotation, so its rows are the images of the basis under its transpose.
        let b = |d: DVec3| sky_frame(d, up);
        let image = [b(DVec3::X), b(DVec3::Y), b(DVec3::Z)];
        for (j, v) in image.iter().enumerate() {
            e[j] = v[i];
        }
        [e[0] as f32, e[1] as f32, e[2] as f32, 0.0]
    };
    [row(0), row(1), row(2)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sky_axes_map_directions_as_the_sky_frame_does() {
        for up in [UpAxis::Y, UpAxis::Z] {
            let axes = sky_axes(up);
            for d in [DVec3::new(0.3, -0.5, 0.8), DVec3::X, DVec3::NEG_Z] {
                let want = sky_frame(d, up);
                for (i, a) in axes.iter().enumerate() {
                    let got = a[0] as f64 * d.x + a[1] as f64 * d.y + a[2] as f64 * d.z;
                    assert!((got - want[i]).abs() < 1e-6, "{up:?} {d:?}: axis {i}");
                }
            }
        }
    }

    #[test]
    fn environments_are_named_or_refused_clearly() {
        assert_eq!(EnvironmentSpec::parse("uniform"), Ok(EnvironmentSpec::Uniform));
        assert!(matches!(
            EnvironmentSpec::parse("a/b.HDR"),
            Ok(EnvironmentSpec::File(_))
        ));
        assert!(EnvironmentSpec::parse("sunset.png").unwrap_err().contains(".hdr"));
        let missing = SkyLight::load("/nonexistent/sky.hdr").unwrap_err();
        assert!(
            format!("{missing:#}").contains("/nonexistent/sky.hdr"),
            "{missing:#}"
        );
    }

    /// Uniform light of intensity K is K times band 0 alone (an open surface then gets K).
    #[test]
    fn intensity_scales_and_rotation_keeps_a_uniform_sky() {
        let sky = SkyLight::load("uniform").unwrap();
        let c = sky.coefficients(37.0, 2.5);
        // e_0 = ∫ K Y_0 dω = K 4π / (2 √π) = 2 K √π; the other bands see nothing.
        for (i, v) in c.iter().enumerate() {
            let want = if i < 3 {
                2.0 * 2.5 * std::f32::consts::PI.sqrt()
            } else {
                0.0
            };
            assert!((v - want).abs() < 2e-3, "coefficient {i}: {v} vs {want}");
        }
    }
}
