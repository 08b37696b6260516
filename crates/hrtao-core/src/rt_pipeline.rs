//! The ray-tracing pipeline of a pass that traces rays, under `RayBackend::Pipeline`: the pass's ray-generation
//! variant (`<shader>.rgen`, compiled by build.rs from the pass's own compute source, trace.glsl), the shared miss
//! and closest-hit shaders (trace.glsl: the hit record's pair, index 0, and the distance-only pair, index 1), on
//! the one pipeline layout of every pass (pass.rs), and its shader binding table. `RtPipeline` owns the pipeline
//! and the table's buffer.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::{CoreError, Result};
use crate::pass::shader_module;

/// The miss and closest-hit shaders every traced pass shares, by the index trace.glsl's `traceRayEXT` calls give
/// them (miss index, hit record offset): 0 fills a hit record, 1 only a distance.
const MISS_SHADERS: [&str; 2] = ["trace_miss.rmiss", "trace_distance_miss.rmiss"];
const HIT_SHADERS: [&str; 2] = ["trace_hit.rchit", "trace_distance_hit.rchit"];

/// One pass's ray-tracing pipeline and its shader binding table (one ray-generation record, the miss records,
/// one triangle hit group per closest-hit shader).
pub struct RtPipeline {
    gpu: Arc<Gpu>,
    pub(crate) pipeline: vk::Pipeline,
    /// Holds the records, each region starting at `shaderGroupBaseAlignment`.
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
        // Stages and groups in the table's order: ray generation, misses, hit groups.
        let names: Vec<&str> = [rgen]
            .into_iter()
            .chain(MISS_SHADERS)
            .chain(HIT_SHADERS)
            .collect();
        let misses = MISS_SHADERS.len() as u32;
        let kinds = (0..names.len() as u32).map(|i| match i {
            0 => vk::ShaderStageFlags::RAYGEN_KHR,
            i if i <= misses => vk::ShaderStageFlags::MISS_KHR,
            _ => vk::ShaderStageFlags::CLOSEST_HIT_KHR,
        });
        let mut modules = Vec::new();
        for &name in &names {
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
        let hit_group = |i: u32| {
            vk::RayTracingShaderGroupCreateInfoKHR::default()
                .ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
                .general_shader(vk::SHADER_UNUSED_KHR)
                .closest_hit_shader(i)
                .any_hit_shader(vk::SHADER_UNUSED_KHR)
                .intersection_shader(vk::SHADER_UNUSED_KHR)
        };
        let groups: Vec<_> = (0..names.len() as u32)
            .map(|i| if i <= misses { general(i) } else { hit_group(i) })
            .collect();
        // Records per region: ray generation, miss, hit.
        let counts = [1, MISS_SHADERS.len(), HIT_SHADERS.len()];
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
            let sizes = counts.map(|n| align_up(n as u64 * stride, base));
            let offsets = [0, sizes[0], sizes[0] + sizes[1]];
            // The buffer's own address need not meet the base alignment: room to move the table up to it.
            let mut bytes = vec![0u8; (base + sizes.iter().sum::<u64>()) as usize];
            let buffer = Buffer::new(
                gpu,
                &format!("shader binding table ({rgen})"),
                bytes.len() as u64,
                MemoryLocation::CpuToGpu,
                vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR,
            )?;
            let start = align_up(buffer.address, base) - buffer.address;
            let mut g = 0;
            for (region, &n) in counts.iter().enumerate() {
                for record in 0..n {
                    let at = (start + offsets[region] + record as u64 * stride) as usize;
                    bytes[at..at + handle_size]
                        .copy_from_slice(&handles[g * handle_size..(g + 1) * handle_size]);
                    g += 1;
                }
            }
            let mut buffer = buffer;
            buffer.write_bytes(0, &bytes)?;
            let region = |r: usize| vk::StridedDeviceAddressRegionKHR {
                device_address: buffer.address + start + offsets[r],
                stride,
                size: counts[r] as u64 * stride,
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
