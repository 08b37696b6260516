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
        /// The environment: `uniform` (white light from every direction: an open surface gets 1), `gradient` (a
        /// blue sky over a brown ground) or an equirectangular Radiance `.hdr` file (its centre facing +x).
        environment: String = "gradient".to_string(), Nothing, paper keep, check environment_rule, custom,
            needs "sky_light";
        /// Turns the environment counter-clockwise seen from above, in degrees (no new rays).
        environment_rotation: f32 = 0.0, Nothing, paper keep, range -180.0..=180.0, label "rotation °",
            needs "sky_light";
        /// Scales the environment's light (K).
        environment_intensity: f32 = 1.0, Nothing, paper keep, range INTENSITY_RANGE, label "intensity",
            needs "sky_light";
        /// The zenith of the environment: the scene's up axis (`--up`). The transfer vectors are kept in the sky
        /// frame it sets: changing it re-keys the map.
        sky_up: UpAxis = UpAxis::Y, WholeMap, paper keep, hidden;
    }
}

/// The intensities the environment accepts (`environment_intensity`'s range).
pub const INTENSITY_RANGE: std::ops::RangeInclusive<f32> = 0.0..=16.0;

/// `environment`'s rule: a name or a file `crate::sky::EnvironmentSpec` parses.
fn environment_rule(s: &str) -> Result<(), String> {
    crate::sky::EnvironmentSpec::parse(s).map(|_| ())
}
