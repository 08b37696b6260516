//! GPU timestamps per named section (the paper's Table 2 columns), read back after the frame.
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
                .cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, self.pool, q);
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
        let period = self.gpu.info.timestamp_period_ns as f64;
        let mut out: Vec<(String, f64)> = Vec::new();
        for (i, s) in self.sections.iter().enumerate() {
            let ms = raw[i * 2 + 1].saturating_sub(raw[i * 2]) as f64 * period * 1e-6;
            match out.iter_mut().find(|(name, _)| name == s) {
                Some(e) => e.1 += ms,
                None => out.push((s.to_string(), ms)),
            }
        }
        Ok(out)
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        unsafe { self.gpu.device.destroy_query_pool(self.pool, None) }
    }
}
