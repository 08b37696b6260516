//! How the model is lit: the AO look (the default), or the sky light (ours, the paper's "environment shadows" of
//! §6; crates/hrtao-core/src/sky): an environment lights the model through each cell's transfer vector, so its
//! environment, rotation and intensity change no cell and no accumulation (`Invalidates::Nothing`).
use super::settings_group;
use crate::camera::UpAxis;

settings_group! {
    /// Lighting.
    pub struct LightSettings {
        /// Ours: light the model with an environment and its shadows (sky light, unbounded rays) instead of the
        /// AO look. The cells then gather the transfer of their rays: switching it re-keys the map.
        sky_light: bool = false, WholeMap, paper keep;
        /// The environment: `uniform`, `gradient` or an equirectangular Radiance `.hdr` file.
        environment: String = "gradient".to_string(), Nothing, paper keep;
        /// Turns the environment counter-clockwise seen from above, in degrees.
        environment_rotation: f32 = 0.0, Nothing, paper keep;
        /// Scales the environment's light (K).
        environment_intensity: f32 = 1.0, Nothing, paper keep;
        /// The zenith of the environment: the scene's up axis (`--up`). The transfer vectors are kept in the sky
        /// frame it sets: changing it re-keys the map.
        sky_up: UpAxis = UpAxis::Y, WholeMap, paper keep;
    }
}

/// The intensities the environment accepts (the panel's slider spans the same range).
pub const INTENSITY_RANGE: std::ops::RangeInclusive<f32> = 0.0..=16.0;

impl LightSettings {
    pub fn validate(&self) -> Result<(), String> {
        if !self.environment_rotation.is_finite() {
            return Err(format!(
                "environment rotation must be a finite angle, got {}",
                self.environment_rotation
            ));
        }
        if !(self.environment_intensity.is_finite() && INTENSITY_RANGE.contains(&self.environment_intensity))
        {
            return Err(format!(
                "environment intensity must be in {}..={}, got {}",
                INTENSITY_RANGE.start(),
                INTENSITY_RANGE.end(),
                self.environment_intensity
            ));
        }
        crate::sky::EnvironmentSpec::parse(&self.environment).map(|_| ())
    }
}

impl super::AsToggle for String {}
impl super::AsToggle for UpAxis {}
