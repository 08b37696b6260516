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

const MAX_SCOPES: u32 = 64;

pub struct GpuTimer {
    gpu: Arc<Gpu>,
    pool: vk::QueryPool,
    sections: Vec<&'static str>,
    open: bool,
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
            sections: Vec::new(),
            open: false,
        }))
    }

    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.sections.clear();
        unsafe {
            self.gpu
                .device
                .cmd_reset_query_pool(cmd, self.pool, 0, MAX_SCOPES * 2)
        };
    }

    pub fn begin(&mut self, cmd: vk::CommandBuffer, section: &'static str) {
        if self.sections.len() as u32 >= MAX_SCOPES {
            return;
        }
        let q = self.sections.len() as u32 * 2;
        self.sections.push(section);
        self.open = true;
        unsafe {
            self.gpu
                .device
                .cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.pool, q);
        }
    }

    pub fn end(&mut self, cmd: vk::CommandBuffer) {
        if !self.open {
            return;
        }
        self.open = false;
        let q = (self.sections.len() as u32 - 1) * 2 + 1;
        unsafe {
            self.gpu
                .device
                .cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.pool, q);
        }
    }

    /// Milliseconds per section, in first-use order, summed over dispatches of the same section.
    pub fn read(&self) -> Result<Vec<(String, f64)>> {
        let n = self.sections.len();
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
            &self.sections,
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
