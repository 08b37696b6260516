//! The one way to declare and record a compute pass.
//!
//! Every pass shares one pipeline layout: set 0 = { binding 0: the TLAS, binding 1: `FrameGlobals` },
//! plus 16 bytes of push constants. Buffers are reached through device addresses stored in `FrameGlobals`,
//! so a pass is only its shader: `Pass` names it, `PassSet` builds all pipelines, `Recorder::dispatch`
//! binds, dispatches over pixels, times it under its Table-2 section and inserts the barrier after it.
use std::sync::Arc;

use ash::vk;

use crate::buffer::{full_barrier, Buffer};
use crate::context::Gpu;
use crate::error::{CoreError, Result};
use crate::gpu::WORKGROUP_SIZE;
use crate::timer::GpuTimer;

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Every compute pass of the renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pass {
    Clear,
    Primary,
    GbufferFromVis,
    Rtao,
    CellFinder,
    AoUpdate,
    QueueArgs,
    Resolve,
    Filter,
    Residual,
    Detail,
    Composite,
    HashTest,
}

impl Pass {
    pub const ALL: [Pass; 13] = [
        Pass::Clear,
        Pass::Primary,
        Pass::GbufferFromVis,
        Pass::Rtao,
        Pass::CellFinder,
        Pass::QueueArgs,
        Pass::AoUpdate,
        Pass::Resolve,
        Pass::Filter,
        Pass::Residual,
        Pass::Detail,
        Pass::Composite,
        Pass::HashTest,
    ];

    /// The shader file (`shaders/<name>.comp`).
    pub fn shader(self) -> &'static str {
        match self {
            Pass::Clear => "clear",
            Pass::Primary => "primary",
            Pass::GbufferFromVis => "gbuffer_from_vis",
            Pass::Rtao => "rtao",
            Pass::CellFinder => "cell_finder",
            Pass::QueueArgs => "queue_args",
            Pass::AoUpdate => "ao_update",
            Pass::Resolve => "resolve",
            Pass::Filter => "filter",
            Pass::Residual => "residual",
            Pass::Detail => "detail",
            Pass::Composite => "composite",
            Pass::HashTest => "hash_test",
        }
    }

    /// The timing section it belongs to (the paper's Table 2 columns, plus ours).
    pub fn section(self) -> &'static str {
        match self {
            Pass::Clear => "clear",
            Pass::Primary | Pass::GbufferFromVis => "primary visibility",
            Pass::Rtao => "per-pixel RTAO",
            Pass::CellFinder => "cell finder",
            Pass::QueueArgs | Pass::AoUpdate => "ray-tracing update",
            Pass::Resolve | Pass::Residual | Pass::Detail => "per-pixel AO",
            Pass::Filter => "filtering",
            Pass::Composite => "composite",
            Pass::HashTest => "hash test",
        }
    }
}

/// Pipelines of all passes and their shared layout and descriptor set.
pub struct PassSet {
    gpu: Arc<Gpu>,
    set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    pipelines: Vec<(Pass, vk::Pipeline)>,
    bound_tlas: vk::AccelerationStructureKHR,
    /// The TLAS build generation binding 0 was last written for (0: never).
    bound_generation: u64,
    /// Descriptor writes of binding 0 so far (`Renderer::tlas_descriptor_writes`).
    tlas_writes: u64,
}

fn spirv_words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// A shader module of the compiled shader `name` (see build.rs); the caller destroys it.
pub(crate) fn shader_module(gpu: &Gpu, name: &str) -> Result<vk::ShaderModule> {
    let spirv = SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| CoreError::Invalid(format!("shader {name} was not compiled")))?
        .1;
    let words = spirv_words(spirv);
    unsafe {
        gpu.device
            .create_shader_module(&vk::ShaderModuleCreateInfo::builder().code(&words), None)
            .map_err(|e| CoreError::from_vk("vkCreateShaderModule", e))
    }
}

impl PassSet {
    pub fn new(gpu: &Arc<Gpu>, globals: &Buffer) -> Result<PassSet> {
        let device = &gpu.device;
        unsafe {
            let bindings = [
                vk::DescriptorSetLayoutBinding::builder()
                    .binding(0)
                    .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
                    .build(),
                vk::DescriptorSetLayoutBinding::builder()
                    .binding(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
                    .build(),
            ];
            let set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::builder().bindings(&bindings),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateDescriptorSetLayout", e))?;
            let push = [vk::PushConstantRange {
                stage_flags: vk::ShaderStageFlags::COMPUTE,
                offset: 0,
                size: 16,
            }];
            let set_layouts = [set_layout];
            let layout = device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::builder()
                        .set_layouts(&set_layouts)
                        .push_constant_ranges(&push),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreatePipelineLayout", e))?;
            let sizes = [
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
                    descriptor_count: 1,
                },
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::STORAGE_BUFFER,
                    descriptor_count: 1,
                },
            ];
            let pool = device
                .create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::builder()
                        .max_sets(1)
                        .pool_sizes(&sizes),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateDescriptorPool", e))?;
            let set = device
                .allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::builder()
                        .descriptor_pool(pool)
                        .set_layouts(&set_layouts),
                )
                .map_err(|e| CoreError::from_vk("vkAllocateDescriptorSets", e))?[0];
            let buffer_info = [vk::DescriptorBufferInfo {
                buffer: globals.raw,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }];
            let write = vk::WriteDescriptorSet::builder()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&buffer_info)
                .build();
            device.update_descriptor_sets(&[write], &[]);
            let mut passes = PassSet {
                gpu: gpu.clone(),
                set_layout,
                layout,
                pool,
                set,
                pipelines: Vec::new(),
                bound_tlas: vk::AccelerationStructureKHR::null(),
                bound_generation: 0,
                tlas_writes: 0,
            };
            for pass in Pass::ALL {
                let module = shader_module(gpu, pass.shader())?;
                let entry = c"main";
                let stage = vk::PipelineShaderStageCreateInfo::builder()
                    .stage(vk::ShaderStageFlags::COMPUTE)
                    .module(module)
                    .name(entry)
                    .build();
                let info = [vk::ComputePipelineCreateInfo::builder()
                    .stage(stage)
                    .layout(layout)
                    .build()];
                let result = device.create_compute_pipelines(vk::PipelineCache::null(), &info, None);
                device.destroy_shader_module(module, None);
                let pipeline = result.map_err(|(_, e)| CoreError::from_vk("vkCreateComputePipelines", e))?[0];
                passes.pipelines.push((pass, pipeline));
            }
            Ok(passes)
        }
    }

    /// Points binding 0 at `tlas` of build `generation` (`SceneGpu::tlas_generation`): written again for every
    /// new generation, never judged by the handle value, which a rebuild may get back from a freed TLAS. Must not
    /// be called while a frame is in flight.
    pub fn bind_tlas(&mut self, tlas: vk::AccelerationStructureKHR, generation: u64) {
        if self.bound_generation == generation && self.bound_tlas == tlas {
            return;
        }
        let handles = [tlas];
        let mut as_write =
            vk::WriteDescriptorSetAccelerationStructureKHR::builder().acceleration_structures(&handles);
        let mut write = vk::WriteDescriptorSet::builder()
            .dst_set(self.set)
            .dst_binding(0)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .push_next(&mut as_write)
            .build();
        write.descriptor_count = 1;
        unsafe { self.gpu.device.update_descriptor_sets(&[write], &[]) };
        self.bound_tlas = tlas;
        self.bound_generation = generation;
        self.tlas_writes += 1;
    }

    /// Descriptor writes of the TLAS binding so far.
    pub fn tlas_writes(&self) -> u64 {
        self.tlas_writes
    }

    fn pipeline(&self, pass: Pass) -> vk::Pipeline {
        self.pipelines
            .iter()
            .find(|(p, _)| *p == pass)
            .map(|(_, p)| *p)
            .unwrap()
    }
}

impl Drop for PassSet {
    fn drop(&mut self) {
        unsafe {
            let d = &self.gpu.device;
            for (_, p) in self.pipelines.drain(..) {
                d.destroy_pipeline(p, None);
            }
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Records passes into one command buffer.
pub struct Recorder<'a> {
    pub gpu: &'a Gpu,
    pub cmd: vk::CommandBuffer,
    passes: &'a PassSet,
    timer: Option<&'a mut GpuTimer>,
}

impl<'a> Recorder<'a> {
    pub fn new(
        gpu: &'a Gpu,
        cmd: vk::CommandBuffer,
        passes: &'a PassSet,
        mut timer: Option<&'a mut GpuTimer>,
    ) -> Self {
        if let Some(t) = timer.as_deref_mut() {
            t.reset(cmd);
        }
        unsafe {
            gpu.device.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                passes.layout,
                0,
                &[passes.set],
                &[],
            );
        }
        Recorder {
            gpu,
            cmd,
            passes,
            timer,
        }
    }

    /// Dispatches `pass` over a `width` x `height` grid of threads (one per pixel), with push constants `push`,
    /// then a barrier so the next pass sees its writes.
    pub fn dispatch(&mut self, pass: Pass, width: u32, height: u32, push: [u32; 4]) {
        let groups = (width.div_ceil(WORKGROUP_SIZE), height.div_ceil(WORKGROUP_SIZE));
        self.record(pass, push, |d, cmd| unsafe {
            d.cmd_dispatch(cmd, groups.0, groups.1, 1)
        });
    }

    /// Dispatches `pass` with the work-group counts a previous pass wrote into `args` (VkDispatchIndirectCommand).
    /// Dispatches `pass` with the group counts at word `offset` of `args` (queue_args.comp writes them).
    pub fn dispatch_indirect(&mut self, pass: Pass, args: vk::Buffer, offset: u32, push: [u32; 4]) {
        self.record(pass, push, |d, cmd| unsafe {
            d.cmd_dispatch_indirect(cmd, args, offset as u64 * 4)
        });
    }

    /// Records commands that are not a compute pass (the rasterised visibility) under the timing section
    /// `section`, then the barrier after them.
    pub fn commands(&mut self, section: &'static str, record: impl FnOnce(&ash::Device, vk::CommandBuffer)) {
        if let Some(t) = self.timer.as_deref_mut() {
            t.begin(self.cmd, section);
        }
        record(&self.gpu.device, self.cmd);
        if let Some(t) = self.timer.as_deref_mut() {
            t.end(self.cmd);
        }
        full_barrier(self.gpu, self.cmd);
    }

    /// Binds `pass`, pushes its constants, records the dispatch under its timing section, then the barrier.
    fn record(&mut self, pass: Pass, push: [u32; 4], dispatch: impl FnOnce(&ash::Device, vk::CommandBuffer)) {
        let d = &self.gpu.device;
        if let Some(t) = self.timer.as_deref_mut() {
            t.begin(self.cmd, pass.section());
        }
        unsafe {
            d.cmd_bind_pipeline(
                self.cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.passes.pipeline(pass),
            );
            d.cmd_push_constants(
                self.cmd,
                self.passes.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::cast_slice(&push),
            );
        }
        dispatch(d, self.cmd);
        if let Some(t) = self.timer.as_deref_mut() {
            t.end(self.cmd);
        }
        full_barrier(self.gpu, self.cmd);
    }
}
