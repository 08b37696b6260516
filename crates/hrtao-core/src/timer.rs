//! GPU timestamps per named section (the paper's Table 2 columns), read back after the frame.
//!
//! Every stamp is written at BOTTOM_OF_PIPE, at the section's start and end: the start waits for everything
//! recorded before it, so where a GPU overlaps consecutive passes a section counts only the time it ran beyond
//! the ones before it, and the sections' sum never exceeds the frame (TOP_OF_PIPE starts counted overlapped
//! work twice). Stamps are masked to the queue's valid bits and subtracted modulo 2^bits (a counter that
//! wrapped between two stamps still gives their distance).
use std::sync::Arc;

use ash::vk;

use crate::context::Gpu;
use crate::error::{CoreError, Result};

/// Scopes a frame can time. Consecutive dispatches of one section share a scope (`Scopes`), so a frame uses
/// one per change of section: ~10 for a whole frame, ~2 per filter iteration or slice chunk between other
/// sections. Past it, the frame's later sections go untimed and the timer says so (`GpuTimer::read`).
const MAX_SCOPES: u32 = 128;

/// A timestamp to write: query `0` of a scope's pair (its start) or `1` (its end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stamp {
    Start(u32),
    End(u32),
}

/// The scopes of a frame, without the device (the tests drive it): a section's scope stays open across its
/// consecutive dispatches (the end stamp waits until another section begins or the recording finishes), so
/// that a pass split into many dispatches (ray-tracing chunks, filter iterations) takes one scope, not one per
/// dispatch.
#[derive(Default)]
struct Scopes {
    sections: Vec<&'static str>,
    /// A section is between `begin` and `end`.
    open: bool,
    /// The last scope ended but its end stamp is not written yet (the next `begin` of the same section
    /// continues it).
    pending_end: bool,
    /// Scopes whose both stamps are written.
    complete: usize,
    /// Sections begun after the pool was full: not timed.
    dropped: u32,
}

impl Scopes {
    fn begin(&mut self, section: &'static str) -> Vec<Stamp> {
        let mut out = Vec::new();
        if self.pending_end {
            if self.sections.last() == Some(&section) {
                self.pending_end = false;
                self.open = true;
                return out;
            }
            out.extend(self.flush());
        }
        if self.sections.len() as u32 >= MAX_SCOPES {
            self.dropped += 1;
            return out;
        }
        out.push(Stamp::Start(self.sections.len() as u32 * 2));
        self.sections.push(section);
        self.open = true;
        out
    }

    fn end(&mut self) {
        if self.open {
            self.open = false;
            self.pending_end = true;
        }
    }

    /// The pending end stamp, if any: before another section or the end of the recording.
    fn flush(&mut self) -> Option<Stamp> {
        if !self.pending_end {
            return None;
        }
        self.pending_end = false;
        self.complete = self.sections.len();
        Some(Stamp::End((self.sections.len() as u32 - 1) * 2 + 1))
    }
}

pub struct GpuTimer {
    gpu: Arc<Gpu>,
    pool: vk::QueryPool,
    scopes: Scopes,
}

impl GpuTimer {
    /// None when the device's queue has no timestamps.
    pub fn new(gpu: &Arc<Gpu>) -> Result<Option<GpuTimer>> {
        if !gpu.info.timestamps {
            return Ok(None);
        }
        let pool = unsafe {
            gpu.device
                .create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(MAX_SCOPES * 2),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateQueryPool", e))?
        };
        Ok(Some(GpuTimer {
            gpu: gpu.clone(),
            pool,
            scopes: Scopes::default(),
        }))
    }

    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.scopes = Scopes::default();
        unsafe {
            self.gpu
                .device
                .cmd_reset_query_pool(cmd, self.pool, 0, MAX_SCOPES * 2)
        };
    }

    fn write(&self, cmd: vk::CommandBuffer, stamp: Stamp) {
        let q = match stamp {
            Stamp::Start(q) | Stamp::End(q) => q,
        };
        unsafe {
            self.gpu
                .device
                .cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.pool, q);
        }
    }

    pub fn begin(&mut self, cmd: vk::CommandBuffer, section: &'static str) {
        for stamp in self.scopes.begin(section) {
            self.write(cmd, stamp);
        }
    }

    pub fn end(&mut self, _cmd: vk::CommandBuffer) {
        self.scopes.end();
    }

    /// Writes the last scope's end stamp: called once the frame's commands are recorded.
    pub fn finish(&mut self, cmd: vk::CommandBuffer) {
        if let Some(stamp) = self.scopes.flush() {
            self.write(cmd, stamp);
        }
    }

    /// Milliseconds per section, in first-use order, summed over dispatches of the same section. Only scopes
    /// whose both stamps were recorded are read (waiting on an unwritten query would never return); sections
    /// past the pool's `MAX_SCOPES` are left out with a warning.
    pub fn read(&self) -> Result<Vec<(String, f64)>> {
        let n = self.scopes.complete;
        if self.scopes.dropped > 0 {
            log::warn!(
                "GPU timer: {} dispatches of this frame were not timed (more than {MAX_SCOPES} scopes)",
                self.scopes.dropped
            );
        }
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut raw = vec![0u64; n * 2];
        unsafe {
            self.gpu
                .device
                .get_query_pool_results(
                    self.pool,
                    0,
                    &mut raw,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
                .map_err(|e| CoreError::from_vk("vkGetQueryPoolResults", e))?;
        }
        let info = &self.gpu.info;
        Ok(section_ms(
            &self.scopes.sections[..n],
            &raw,
            info.timestamp_valid_bits,
            info.timestamp_period_ns as f64,
        ))
    }
}

/// Milliseconds per section name, in first-use order, summed over its scopes: `raw` holds each scope's start
/// and end stamps, valid in their low `valid_bits` bits, `period_ns` nanoseconds a tick.
fn section_ms(sections: &[&str], raw: &[u64], valid_bits: u32, period_ns: f64) -> Vec<(String, f64)> {
    let mask = if valid_bits >= 64 {
        u64::MAX
    } else {
        (1u64 << valid_bits) - 1
    };
    let mut out: Vec<(String, f64)> = Vec::new();
    for (i, s) in sections.iter().enumerate() {
        let ticks = (raw[i * 2 + 1] & mask).wrapping_sub(raw[i * 2] & mask) & mask;
        let ms = ticks as f64 * period_ns * 1e-6;
        match out.iter_mut().find(|(name, _)| name == s) {
            Some(e) => e.1 += ms,
            None => out.push((s.to_string(), ms)),
        }
    }
    out
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        unsafe { self.gpu.device.destroy_query_pool(self.pool, None) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 36-bit counter that wraps inside a section: the section's ticks are its distance modulo 2^36, and
    /// garbage above the valid bits is ignored.
    #[test]
    fn stamps_wrap_at_the_valid_bits() {
        let top = 1u64 << 36;
        let garbage = 0xABCD << 40;
        let raw = [(top - 1000) | garbage, 500 | garbage, 500, 2500];
        let ms = section_ms(&["update", "filter"], &raw, 36, 1e6);
        assert_eq!(
            ms,
            vec![("update".to_string(), 1500.0), ("filter".to_string(), 2000.0)]
        );
        // 64 valid bits: a plain difference.
        assert_eq!(
            section_ms(&["a"], &[10, 30], 64, 1e6),
            vec![("a".to_string(), 20.0)]
        );
    }

    /// Consecutive dispatches of one section share a scope; a section that comes back after another opens a new
    /// one; the last end stamp waits for `flush`; past MAX_SCOPES sections are counted as dropped, and what
    /// was written is still complete.
    #[test]
    fn consecutive_dispatches_share_a_scope() {
        let mut s = Scopes::default();
        assert_eq!(s.begin("update"), vec![Stamp::Start(0)]);
        s.end();
        assert_eq!(s.begin("update"), vec![]);
        s.end();
        assert_eq!(s.begin("filter"), vec![Stamp::End(1), Stamp::Start(2)]);
        s.end();
        assert_eq!(s.complete, 1, "the filter's end is not written yet");
        assert_eq!(s.begin("update"), vec![Stamp::End(3), Stamp::Start(4)]);
        s.end();
        assert_eq!(s.flush(), Some(Stamp::End(5)));
        assert_eq!(s.flush(), None);
        assert_eq!(
            (s.sections.as_slice(), s.complete),
            (&["update", "filter", "update"][..], 3)
        );

        let mut s = Scopes::default();
        let names = ["a", "b"];
        for i in 0..MAX_SCOPES + 5 {
            s.begin(names[i as usize % 2]);
            s.end();
        }
        // The last timed scope ended when the first untimed section began.
        assert_eq!(s.flush(), None);
        assert_eq!((s.complete as u32, s.dropped), (MAX_SCOPES, 5));
        // A thousand chunks of one pass take one scope.
        let mut s = Scopes::default();
        for _ in 0..1000 {
            s.begin("update");
            s.end();
        }
        s.flush();
        assert_eq!((s.complete, s.dropped), (1, 0));
    }

    /// Scopes of one name add up; with start stamps written after the previous scope's work (BOTTOM_OF_PIPE),
    /// overlapped passes split the frame instead of counting their overlap twice: three passes each running
    /// 0-10, 5-15, 12-20 ticks of a 20-tick frame stamp (0, 10), (10, 15), (15, 20) and sum to 20.
    #[test]
    fn overlapping_passes_sum_to_the_frame() {
        let raw = [0, 10, 10, 15, 15, 20];
        let ms = section_ms(&["update", "filter", "update"], &raw, 64, 1e6);
        assert_eq!(
            ms,
            vec![("update".to_string(), 15.0), ("filter".to_string(), 5.0)]
        );
        let total: f64 = ms.iter().map(|(_, m)| m).sum();
        assert_eq!(total, 20.0);
    }
}
