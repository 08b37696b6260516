//! The ray-tracing pipeline of a pass that traces rays, under `RayBackend::Pipeline`: the pass's ray-generation
//! variant (`<shader>.rgen`, compiled by build.rs from the pass's own compute source, trace.glsl), the shared miss
//! shader (trace_miss.rmiss) and closest-hit shader (trace_hit.rchit), on the one pipeline layout of every pass
//! (pass.rs), and its shader binding table. `RtPipeline` owns the pipeline and the table's buffer.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::{CoreError, Result};
use crate::pass::shader_module;

/// The miss and closest-hit shaders every traced pass shares.
const MISS_SHADER: &str = "trace_miss.rmiss";
const HIT_SHADER: &str = "trace_hit.rchit";

/// One pass's ray-tracing pipeline and its shader binding table (one ray-generation record, one miss record,
/// one triangle hit group).
pub struct RtPipeline {
    gpu: Arc<Gpu>,
    pub(crate) pipeline: vk::Pipeline,
    /// Holds the three records, each region starting at `shaderGroupBaseAlignment`.
    _table: Buffer,
    /// The ray-generation, miss, hit and (empty) callable regions, as `vkCmdTraceRaysKHR` takes them.
    pub(crate) regions: [vk::StridedDeviceAddressRegionKHR; 4],
}

fn align_up(v: u64, a: u64) -> u64 {
    v.div_ceil(a) * a
}

impl RtPipeline {
    /// The pipeline of the pass whose ray-generation shader is `rgen` (`<shader>.rgen`), on `layout`.
    pub fn new(gpu: &Arc<Gpu>, layout: vk::PipelineLayout, rgen: &str) -> Result<RtPipeline> {
        let rt = gpu.rt.as_ref().ok_or_else(|| {
            CoreError::Invalid("ray-tracing pipelines are not enabled on this device".into())
        })?;
        let device = &gpu.device;
        let names = [rgen, MISS_SHADER, HIT_SHADER];
        let kinds = [
            vk::ShaderStageFlags::RAYGEN_KHR,
            vk::ShaderStageFlags::MISS_KHR,
            vk::ShaderStageFlags::CLOSEST_HIT_KHR,
        ];
        let mut modules = Vec::new();
        for name in names {
            match shader_module(gpu, name) {
                Ok(m) => modules.push(m),
                Err(e) => {
                    for m in modules {
                        unsafe { device.destroy_shader_module(m, None) };
                    }
                    return Err(e);
                }
            }
        }
        let stages: Vec<vk::PipelineShaderStageCreateInfo> = modules
            .iter()
            .zip(kinds)
            .map(|(&module, stage)| {
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(stage)
                    .module(module)
                    .name(c"main")
            })
            .collect();
        let general = |i: u32| {
            vk::RayTracingShaderGroupCreateInfoKHR::default()
                .ty(vk::RayTracingShaderGroupTypeKHR::GENERAL)
                .general_shader(i)
                .closest_hit_shader(vk::SHADER_UNUSED_KHR)
                .any_hit_shader(vk::SHADER_UNUSED_KHR)
                .intersection_shader(vk::SHADER_UNUSED_KHR)
        };
        let groups = [
            general(0),
            general(1),
            vk::RayTracingShaderGroupCreateInfoKHR::default()
                .ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
                .general_shader(vk::SHADER_UNUSED_KHR)
                .closest_hit_shader(2)
                .any_hit_shader(vk::SHADER_UNUSED_KHR)
                .intersection_shader(vk::SHADER_UNUSED_KHR),
        ];
        let info = [vk::RayTracingPipelineCreateInfoKHR::default()
            .stages(&stages)
            .groups(&groups)
            .max_pipeline_ray_recursion_depth(1)
            .layout(layout)];
        let created = unsafe {
            rt.loader.create_ray_tracing_pipelines(
                vk::DeferredOperationKHR::null(),
                vk::PipelineCache::null(),
                &info,
                None,
            )
        };
        for m in modules {
            unsafe { device.destroy_shader_module(m, None) };
        }
        let pipeline = created.map_err(|(_, e)| CoreError::from_vk("vkCreateRayTracingPipelinesKHR", e))?[0];
        let table = (|| {
            let handle_size = rt.handle_size as usize;
            let handles = unsafe {
                rt.loader
                    .get_ray_tracing_shader_group_handles(
                        pipeline,
                        0,
                        groups.len() as u32,
                        groups.len() * handle_size,
                    )
                    .map_err(|e| CoreError::from_vk("vkGetRayTracingShaderGroupHandlesKHR", e))?
            };
            let base = rt.base_alignment as u64;
            let stride = align_up(rt.handle_size as u64, rt.handle_alignment as u64);
            let region_size = align_up(stride, base);
            // The buffer's own address need not meet the base alignment: room to move the table up to it.
            let mut bytes = vec![0u8; (base + 3 * region_size) as usize];
            let buffer = Buffer::new(
                gpu,
                &format!("shader binding table ({rgen})"),
                bytes.len() as u64,
                MemoryLocation::CpuToGpu,
                vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR,
            )?;
            let start = align_up(buffer.address, base) - buffer.address;
            for g in 0..3 {
                let at = (start + g as u64 * region_size) as usize;
                bytes[at..at + handle_size].copy_from_slice(&handles[g * handle_size..(g + 1) * handle_size]);
            }
            let mut buffer = buffer;
            buffer.write_bytes(0, &bytes)?;
            let region = |g: u64| vk::StridedDeviceAddressRegionKHR {
                device_address: buffer.address + start + g * region_size,
                stride,
                size: stride,
            };
            // The ray-generation region's size equals its stride (VUID-vkCmdTraceRaysKHR-size-04023).
            let regions = [
                region(0),
                region(1),
                region(2),
                vk::StridedDeviceAddressRegionKHR::default(),
            ];
            Ok((buffer, regions))
        })();
        match table {
            Ok((table, regions)) => Ok(RtPipeline {
                gpu: gpu.clone(),
                pipeline,
                _table: table,
                regions,
            }),
            Err(e) => {
                unsafe { device.destroy_pipeline(pipeline, None) };
                Err(e)
            }
        }
    }

    /// The device's ray-tracing pipeline functions (an `RtPipeline` exists only where they do).
    fn rt(&self) -> &crate::context::RtSupport {
        self.gpu
            .rt
            .as_ref()
            .expect("an RtPipeline exists only with ray-tracing pipelines")
    }

    /// Records a launch of `width` x `height` x 1 ray-generation invocations.
    pub(crate) fn trace(&self, cmd: vk::CommandBuffer, width: u32, height: u32) {
        let rt = self.rt();
        let [raygen, miss, hit, callable] = &self.regions;
        unsafe {
            rt.loader
                .cmd_trace_rays(cmd, raygen, miss, hit, callable, width, height, 1)
        };
    }

    /// Records a launch whose size (`VkTraceRaysIndirectCommandKHR`) lies at device address `args`.
    pub(crate) fn trace_indirect(&self, cmd: vk::CommandBuffer, args: u64) {
        let rt = self.rt();
        let [raygen, miss, hit, callable] = &self.regions;
        unsafe {
            rt.loader
                .cmd_trace_rays_indirect(cmd, raygen, miss, hit, callable, args)
        };
    }
}

impl Drop for RtPipeline {
    fn drop(&mut self) {
        unsafe { self.gpu.device.destroy_pipeline(self.pipeline, None) };
    }
}
