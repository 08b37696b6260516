//! Contact detail (ours, `YoungMapSettings::contact_detail`, shaders/contact_detail.glsl): while cells are young,
//! the creases and contacts the G-buffer shows around a pixel, finer than its cells, darken it by a gain fitted
//! each frame to the rays the pixels traced. Its obscurance pass (contact_detail.comp) runs right after primary
//! visibility; the corrections pass fits the gain in phase 1 (after the corrections listed before it) and
//! corrects in phase 2. It owns its buffer, which its passes reach through their push constants.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{Correction, YoungFrame};
use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::Result;
use crate::pass::{Pass, Resource};
use crate::recorder::Recorder;

/// Its obscurance pass: the G-buffer around each pixel → its buffer (and the fit's sums reset).
pub const OBSCURANCE: Pass = Pass::new(
    "contact_detail",
    "per-pixel AO",
    &[Resource::GBuffer],
    &[Resource::ContactDetail],
);

/// Its mask in the corrections pass and its phases, generated from its shader file.
const CORRECTION: Correction = super::generated::CONTACT_DETAIL;

/// Bytes of the fit's two i64 sums at the start of its buffer (contact_detail.glsl `ContactDetailRef`).
const SUMS_BYTES: u64 = 16;

/// Its buffer (`Resource::ContactDetail`): the fit's sums, then one f32 obscurance per pixel.
pub struct Target {
    buffer: Buffer,
}

impl Target {
    /// For images of up to `pixels` pixels.
    pub fn new(gpu: &Arc<Gpu>, pixels: u64) -> Result<Target> {
        let bytes = SUMS_BYTES + pixels * 4;
        let buffer = Buffer::new(
            gpu,
            "contact detail",
            bytes,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        Ok(Target { buffer })
    }

    /// The last two words of its passes' push constants: its buffer's address.
    pub fn push(&self) -> [u32; 2] {
        self.buffer.address_words()
    }
}

fn on(frame: &YoungFrame) -> bool {
    frame.young && frame.settings.young.contact_detail
}

/// Whether it runs in `frame`, as its correction.
pub fn correction(frame: &YoungFrame) -> Option<Correction> {
    on(frame).then_some(CORRECTION)
}

/// Records the obscurance over the frame's `width` x `height` pixels (its slice) when it runs: it reads only the
/// G-buffer, so it shares the cell finder's barrier.
pub fn record_obscurance(rec: &mut Recorder, frame: &YoungFrame, target: &Target, width: u32, height: u32) {
    if on(frame) {
        let [lo, hi] = target.push();
        rec.dispatch(OBSCURANCE, width, height, [0, 0, lo, hi]);
    }
}

#[cfg(test)]
mod tests {
    use crate::testkit::*;

    /// One frame from an empty map at 8 rays per pixel on the cycloidal gearbox at 320x180 against its Cycles
    /// reference, without and with contact detail (every other setting at its default): the creases between the
    /// gearbox's pins, rollers and discs are finer than its cells, and the detail brings them back, so the error
    /// falls (measured 0.0188-0.0189 -> 0.0166). The margin is ten times the run-to-run spread of one frame (thread
    /// order decides which pixel takes which of a cell's rays).
    #[test]
    fn contact_detail_lowers_the_first_frame_error() {
        let e = first_frame_errors(
            "cycloidal",
            320,
            180,
            &[r#"{"contact_detail": false}"#, r#"{"contact_detail": true}"#],
        );
        println!(
            "cycloidal 320x180, HRTAO 1 frame: without contact detail {:.4}, with {:.4}",
            e[0], e[1]
        );
        assert!(e[1] < e[0] - 0.001, "cycloidal: without {}, with {}", e[0], e[1]);
    }
}
