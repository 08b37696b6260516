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

/// Its bit of the corrections pass (corrections.comp `push.y`) and its phases.
const CORRECTION: Correction = Correction { mask: 2, phases: 2 };

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
