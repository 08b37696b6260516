//! Our additions that run in the frames of a young map (docs/algorithm.md, `settings::YoungMapSettings`): while
//! cells hold few rays they bring back the detail finer than the cells and cut their noise. Each is one file
//! here (when it runs and what the frame records for it) and one shader file (its GPU code and constants):
//!
//! - `adaptive_rays` (adaptive_rays.glsl): the ray-tracing update's budget in three dispatches;
//! - `near_field` (near_field.glsl): the update classifies its rays, the resolve corrects by them;
//! - `pooled_residual` (pooled_residual.glsl) and `contact_detail` (contact_detail.glsl, contact_detail.comp):
//!   corrections after the filter, in the young map's corrections pass (corrections.comp), which
//!   `record_corrections` records for the corrections on.
//!
//! Each one's switch is a `bool` of `YoungMapSettings` (off = the paper). The renderer calls them through the
//! hooks below (`flags`, `update_phases`, `record_after_primary`, `record_corrections`) and names none of them
//! (`tests/addition_files.rs`); docs/architecture.md "Where an addition goes" lists what adding or deleting one
//! touches.
use std::sync::Arc;

use ash::vk;

use crate::context::Gpu;
use crate::error::Result;
use crate::gpu;
use crate::pass::{Pass, Resource};
use crate::recorder::Recorder;
use crate::settings::AoSettings;

pub mod adaptive_rays;
pub mod contact_detail;
pub mod near_field;
pub mod pooled_residual;

/// What the young map's additions need to know of a frame.
#[derive(Clone, Copy)]
pub struct YoungFrame<'a> {
    pub settings: &'a AoSettings,
    /// The frame renders the hash map's AO (not per-pixel RTAO, nor no AO) and the map is young
    /// (`WorldHashMap::young`).
    pub young: bool,
}

/// The buffers of the additions that own one, sized for the renderer's images (held with its targets).
pub struct Targets {
    pub contact_detail: contact_detail::Target,
}

impl Targets {
    /// For images of up to `pixels` pixels.
    pub fn new(gpu: &Arc<Gpu>, pixels: u64) -> Result<Targets> {
        Ok(Targets {
            contact_detail: contact_detail::Target::new(gpu, pixels)?,
        })
    }
}

/// A correction of the corrections pass (corrections.comp): its mask in the pass's `push.y` (one bit, its own)
/// and the phases it needs (1 to 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Correction {
    pub mask: u32,
    pub phases: u32,
}

/// The young map's corrections pass (corrections.comp), over the ray queue: each correction reads the pixels' own
/// rays and their neighbours' and writes the AO in place; the contact detail reads its obscurance and sums its
/// fit in its buffer.
pub const CORRECTIONS: Pass = Pass::new(
    "corrections",
    "per-pixel AO",
    &[
        Resource::Stats,
        Resource::RayQueue,
        Resource::FilterPlan,
        Resource::GBuffer,
        Resource::PixelRays,
        Resource::ContactDetail,
        Resource::Ao,
    ],
    &[Resource::Ao, Resource::ContactDetail],
);

/// The additions' share of `FrameGlobals::flags` in `frame` (the near field's).
pub fn flags(frame: &YoungFrame) -> u32 {
    near_field::flags(frame)
}

/// The ray-tracing update's dispatches in `frame` (`push.x` of ao_update.comp): one, or adaptive sampling's.
pub fn update_phases(frame: &YoungFrame) -> &'static [u32] {
    adaptive_rays::update_phases(frame)
}

/// Records the additions' passes that read only the G-buffer, right after primary visibility (beside the cell
/// finder, behind one barrier), over the frame's `width` x `height` pixels (its slice).
pub fn record_after_primary(
    rec: &mut Recorder,
    frame: &YoungFrame,
    targets: &Targets,
    width: u32,
    height: u32,
) {
    contact_detail::record_obscurance(rec, frame, &targets.contact_detail, width, height);
}

/// The corrections on in `frame`, in the order the pass applies them.
fn corrections_on(frame: &YoungFrame) -> impl Iterator<Item = Correction> {
    [
        pooled_residual::correction(frame),
        contact_detail::correction(frame),
    ]
    .into_iter()
    .flatten()
}

/// The corrections on in `frame`, folded into the pass's push constants: (masks, phases).
fn corrections(frame: &YoungFrame) -> (u32, u32) {
    corrections_on(frame).fold((0, 0), |(bits, phases), c| (bits | c.mask, phases.max(c.phases)))
}

/// Records the corrections pass over the pixels that traced rays into their cells this frame (the ray queue,
/// an indirect dispatch sized at `RAY_ARGS_OFFSET` of `args`), once per phase the corrections on need.
pub fn record_corrections(rec: &mut Recorder, frame: &YoungFrame, targets: &Targets, args: vk::Buffer) {
    let (bits, phases) = corrections(frame);
    let [lo, hi] = targets.contact_detail.push();
    for phase in 1..=phases {
        rec.dispatch_indirect(CORRECTIONS, args, gpu::RAY_ARGS_OFFSET, [phase, bits, lo, hi]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame_of(settings: &AoSettings, young: bool) -> (u32, u32) {
        corrections(&YoungFrame { settings, young })
    }

    #[test]
    fn the_corrections_pass_runs_the_phases_of_the_corrections_on() {
        let mut s = AoSettings::default();
        assert_eq!(
            frame_of(&s, true),
            (0b11, 2),
            "both: the pooled residual, then the detail's two phases"
        );
        assert_eq!(
            frame_of(&s, false),
            (0, 0),
            "a map that is not young corrects nothing"
        );
        s.young.contact_detail = false;
        assert_eq!(frame_of(&s, true), (0b01, 1));
        s.young.pooled_residual = false;
        s.young.contact_detail = true;
        assert_eq!(frame_of(&s, true), (0b10, 2));
        assert_eq!(frame_of(&s.paper(), true), (0, 0), "none in the paper's mode");
    }

    #[test]
    fn each_correction_has_a_bit_of_its_own() {
        let s = AoSettings::default();
        let frame = YoungFrame {
            settings: &s,
            young: true,
        };
        let mut seen = 0u32;
        for c in corrections_on(&frame) {
            assert_eq!(c.mask.count_ones(), 1, "{c:?}: one bit");
            assert_eq!(seen & c.mask, 0, "{c:?}: a bit no other correction has");
            assert!((1..=2).contains(&c.phases), "{c:?}");
            seen |= c.mask;
        }
        assert_eq!(seen.count_ones(), 2, "every correction is on by default");
    }
}
