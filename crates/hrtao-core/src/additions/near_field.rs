//! Near-field control variate (ours, `YoungMapSettings::near_field`, shaders/near_field.glsl): in a young map's
//! frame the ray-tracing update classifies its rays by whether they hit within half the AO radius, and the
//! resolve corrects each pixel's cell estimate by its own near-open fraction minus its cells'.
use super::YoungFrame;
use crate::gpu;

/// Its share of `FrameGlobals::flags`.
pub fn flags(frame: &YoungFrame) -> u32 {
    if frame.young && frame.settings.young.near_field {
        gpu::FLAG_NEAR_FIELD
    } else {
        0
    }
}
