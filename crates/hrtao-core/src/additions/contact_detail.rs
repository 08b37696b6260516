//! Contact detail (ours, `YoungMapSettings::contact_detail`, shaders/contact_detail.glsl): while cells are young,
//! the creases and contacts the G-buffer shows around a pixel, finer than its cells, darken it by a gain fitted
//! each frame to the rays the pixels traced. Its obscurance pass (contact_detail.comp) runs right after primary
//! visibility; the corrections pass fits the gain in phase 1 (after the pooled residual) and corrects in phase 2.
use super::{Correction, YoungFrame};
use crate::pass::{Pass, Recorder, Resource};

/// Its obscurance pass: the G-buffer around each pixel → `Obscurance`.
pub const OBSCURANCE: Pass = Pass::new(
    "contact_detail",
    "per-pixel AO",
    &[Resource::GBuffer],
    &[Resource::Obscurance],
);

/// Its bit of the corrections pass (corrections.comp `push.y`).
const CORRECTION: Correction = Correction { bit: 2, phases: 2 };

fn on(frame: &YoungFrame) -> bool {
    frame.young && frame.settings.young.contact_detail
}

/// Whether it runs in `frame`, as its correction.
pub fn correction(frame: &YoungFrame) -> Option<Correction> {
    on(frame).then_some(CORRECTION)
}

/// Records the obscurance over the frame's `width` x `height` pixels (its slice) when it runs: it reads only the
/// G-buffer, so it shares the cell finder's barrier.
pub fn record_obscurance(rec: &mut Recorder, frame: &YoungFrame, width: u32, height: u32) {
    if on(frame) {
        rec.dispatch(OBSCURANCE, width, height, [0; 4]);
    }
}
