//! Adaptive sampling of young cells (ours, `YoungMapSettings::adaptive_rays`, shaders/adaptive_rays.glsl): in a
//! young map's frame the ray-tracing update traces a quarter of the budget, weighs the pixels by the noise their
//! cells still have, and shares the rest by those weights.
use super::YoungFrame;

/// The ray-tracing update's dispatches (`push.x` of ao_update.comp, adaptive_rays.glsl `PHASE_*`): the whole
/// budget in one, or split in three (the first quarter, the weights, the rest).
pub fn update_phases(frame: &YoungFrame) -> &'static [u32] {
    if frame.young && frame.settings.young.adaptive_rays {
        &[1, 2, 3]
    } else {
        &[0]
    }
}
