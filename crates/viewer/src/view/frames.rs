//! Frames submitted and not yet completed (`Presenter::submit`): what the viewer reads of each once the device
//! completed it (the renderer's report, the background screenshot's tile, the window capture), in order. With
//! one frame in flight the viewer waits for each frame before presenting it; with two it records the next
//! frame while the device runs this one and completes the oldest after submitting the newest.
use std::collections::VecDeque;
use std::time::Instant;

use super::frame_loop::UiCapture;
use super::{pacer, stats};

/// A frame submitted to the device.
pub(super) struct Submitted {
    /// The presenter's slot (`Presenter::wait`).
    pub slot: usize,
    /// Already waited for (one frame in flight waits before presenting).
    pub waited: bool,
    pub plan: pacer::FramePlan,
    /// The view's renderer recorded a frame (`Renderer::finish_frame` reads it).
    pub rendered: bool,
    /// The background screenshot recorded a tile frame (`Shots::finish_frame`).
    pub shot: bool,
    pub shot_error: Option<anyhow::Error>,
    pub capture: Option<UiCapture>,
    /// When its recording started.
    pub t0: Instant,
    pub presented_ms: f64,
    pub split: stats::CpuSplit,
    pub laps: stats::Laps,
    /// When its UI pass started: its wall time runs from there to its completion.
    pub ui_started: Instant,
    /// When it was submitted.
    pub submitted: Instant,
    /// Its device time: the wait for its fence with one frame in flight, else from its submission to its
    /// completion (`complete`).
    pub device_ms: f64,
    /// The view it rendered (the camera may have moved on by its completion).
    pub camera: hrtao_core::Camera,
    /// The input it answers (`Latency::take_input` when it was recorded): the first and last event's stamps.
    pub input: Option<(f64, f64)>,
}

/// The frames in flight, oldest first, and how many may be.
pub(super) struct Frames {
    /// Frames the viewer keeps in flight: 1 or 2 (`prefs::frames_in_flight`).
    pub limit: usize,
    queue: VecDeque<Submitted>,
    /// Frames completed after the host began the next frame (its UI pass, and maybe its recording).
    pub overlapped: u64,
}

impl Frames {
    pub fn new(limit: usize) -> Frames {
        Frames {
            limit: limit.max(1),
            queue: VecDeque::new(),
            overlapped: 0,
        }
    }

    pub fn push(&mut self, f: Submitted) {
        self.queue.push_back(f);
    }

    /// The oldest frame while more than `keep` are in flight.
    pub fn pop_over(&mut self, keep: usize) -> Option<Submitted> {
        (self.queue.len() > keep)
            .then(|| self.queue.pop_front())
            .flatten()
    }

    /// The oldest frame's slot.
    pub fn oldest_slot(&self) -> Option<usize> {
        self.queue.front().map(|f| f.slot)
    }

    /// Forgets every frame (the device is idle and their results are not wanted: shutdown).
    pub fn clear(&mut self) {
        self.queue.clear();
    }
}
