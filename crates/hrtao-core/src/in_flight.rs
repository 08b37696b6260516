//! Frames in flight: what a frame recorded but not yet finished (`Renderer::finish_frame`) keeps of its own,
//! so that the next frame can be recorded and submitted before the device completes this one. Each of
//! `MAX_FRAMES_IN_FLIGHT` slots owns the host-visible copy of a frame's statistics and the frame's timestamp
//! queries; the frame's globals are written by the frame's own commands (`buffer::record_update`), in queue
//! order, so they need no slot. A frame takes the slot no unfinished frame holds; `finish_frame` reads the
//! oldest unfinished frame's slot, after the caller waited for that frame.
use std::collections::VecDeque;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::{CoreError, Result};
use crate::frame::FrameKey;
use crate::gpu::FrameStats;
use crate::probes::ProbeBuffer;
use crate::timer::GpuTimer;

/// The most frames recorded and not yet finished: two lets the host record frame N+1 while the device runs
/// frame N.
pub const MAX_FRAMES_IN_FLIGHT: usize = 2;

/// One frame's own resources.
pub struct Slot {
    /// `FrameStats` copied at the end of the frame, read by the host once the frame completed.
    pub readback: Buffer,
    /// The frame's per-section timestamps (None: the queue has none).
    pub timer: Option<GpuTimer>,
    /// The frame's probe rays and their hits (`probes.rs`).
    pub probes: ProbeBuffer,
}

/// What `finish_frame` needs of a recorded frame: its slot and the renderer's state when it was recorded
/// (the renderer has moved on when frames are in flight).
#[derive(Clone, Debug)]
pub struct Recorded {
    pub slot: usize,
    pub key: FrameKey,
    /// The renderer's frame index after this frame (a hash cell's "last used" stamp of the next one).
    pub frame_index: u32,
    pub still_index: u32,
    pub slice: u32,
    pub lattice: u32,
    pub pixels: usize,
}

pub struct InFlight {
    slots: Vec<Slot>,
    recorded: VecDeque<Recorded>,
}

impl InFlight {
    pub fn new(gpu: &Arc<Gpu>) -> Result<InFlight> {
        let slots = (0..MAX_FRAMES_IN_FLIGHT)
            .map(|i| {
                Ok(Slot {
                    readback: Buffer::new(
                        gpu,
                        &format!("frame stats readback {i}"),
                        std::mem::size_of::<FrameStats>() as u64,
                        MemoryLocation::GpuToCpu,
                        vk::BufferUsageFlags::empty(),
                    )?,
                    timer: GpuTimer::new(gpu)?,
                    probes: ProbeBuffer::new(gpu, &format!("probe rays {i}"))?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(InFlight {
            slots,
            recorded: VecDeque::new(),
        })
    }

    /// The slot the next recorded frame takes: one no unfinished frame holds. An error when
    /// `MAX_FRAMES_IN_FLIGHT` frames are unfinished.
    pub fn free_slot(&self) -> Result<usize> {
        (0..self.slots.len())
            .find(|&s| self.recorded.iter().all(|r| r.slot != s))
            .ok_or_else(|| {
                CoreError::Invalid(format!(
                    "{MAX_FRAMES_IN_FLIGHT} frames are recorded and not finished (finish_frame)"
                ))
            })
    }

    pub fn slot(&self, slot: usize) -> &Slot {
        &self.slots[slot]
    }

    pub fn slot_mut(&mut self, slot: usize) -> &mut Slot {
        &mut self.slots[slot]
    }

    /// A frame was recorded into `r.slot`.
    pub fn push(&mut self, r: Recorded) {
        self.recorded.push_back(r);
    }

    /// The oldest frame recorded and not finished.
    pub fn pop(&mut self) -> Option<Recorded> {
        self.recorded.pop_front()
    }

    /// Frames recorded and not finished.
    pub fn len(&self) -> usize {
        self.recorded.len()
    }

    pub fn is_empty(&self) -> bool {
        self.recorded.is_empty()
    }

    /// Forgets the unfinished frames (the caller waited for the device, or dropped the frames' results).
    pub fn clear(&mut self) {
        self.recorded.clear();
    }

    /// The readback buffers, for the renderer's first clear.
    pub fn readbacks(&self) -> impl Iterator<Item = vk::Buffer> + '_ {
        self.slots.iter().map(|s| s.readback.raw)
    }
}
