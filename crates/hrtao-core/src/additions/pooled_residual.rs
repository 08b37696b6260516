//! Pooled residual control variate (ours, `YoungMapSettings::pooled_residual`, shaders/pooled_residual.glsl):
//! after the filter, a pixel of a young cell is corrected by the rays it and its same-surface 3x3 neighbours
//! traced this frame, where they differ from the cell by more than their noise. Phase 1 of the corrections pass.
use super::{Correction, YoungFrame};

/// Its bit of the corrections pass (corrections.comp `push.y`) and its phases.
const CORRECTION: Correction = Correction { mask: 1, phases: 1 };

/// Whether it runs in `frame`, as its correction.
pub fn correction(frame: &YoungFrame) -> Option<Correction> {
    (frame.young && frame.settings.young.pooled_residual).then_some(CORRECTION)
}
