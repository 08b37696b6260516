//! The one way to declare and record a compute pass.
//!
//! Every pass shares one pipeline layout: set 0 = { binding 0: the TLAS, binding 1: `FrameGlobals` },
//! plus 16 bytes of push constants. Buffers are reached through device addresses stored in `FrameGlobals` (or,
//! for a buffer of one pass or one addition, in its push constants: `Resource::push_type`), so a pass is its
//! shader and the buffers it reads and writes (`Pass::reads`, `Pass::writes`: the validation layer cannot see
//! accesses through device addresses, so these declarations are the one source of truth, checked against the
//! shaders by `tests/pass_declarations.rs`). `PassSet` builds all pipelines; `recorder::Recorder` records them.
//!
//! A pass that traces rays (its shader `#define`s HRTAO_TRACES: `Pass::traces`) runs by the device's
//! `RayBackend`: a compute pipeline whose shader traces with ray queries, or a ray-tracing pipeline
//! (`rt_pipeline::RtPipeline`) whose ray-generation shader build.rs compiles from the same source and which the
//! recorder launches over the same threads. Its declaration is the same either way.
use std::sync::Arc;

use ash::vk;

use crate::buffer::Buffer;
use crate::context::{Gpu, RayBackend};
use crate::error::{CoreError, Result};
use crate::rt_pipeline::RtPipeline;
use Resource::*;

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// A compute pass, declared once where it belongs (the paper's passes below, each addition's in its own file of
/// `crate::additions`; `crate::passes::ALL` lists them): its shader, the timing section it belongs to (the
/// paper's Table 2 columns, plus ours) and the buffers its shader reads and writes (`tests/pass_declarations.rs` checks them against the shader;
/// atomics count as reads and writes, and an indirect dispatch also reads `DispatchArgs`, which the recorder
/// adds). The barriers of a frame and the pass table of docs/architecture.md follow from these declarations.
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    shader: &'static str,
    section: &'static str,
    reads: &'static [Resource],
    writes: &'static [Resource],
}

impl PartialEq for Pass {
    fn eq(&self, other: &Pass) -> bool {
        self.shader == other.shader
    }
}

impl Eq for Pass {}

impl std::hash::Hash for Pass {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.shader.hash(state)
    }
}

impl Pass {
    /// The pass of `shaders/<shader>.comp`.
    pub const fn new(
        shader: &'static str,
        section: &'static str,
        reads: &'static [Resource],
        writes: &'static [Resource],
    ) -> Pass {
        Pass {
            shader,
            section,
            reads,
            writes,
        }
    }

    // One thread of primary visibility also resets the frame's counters (clear.glsl).
    pub const PRIMARY: Pass = Pass::new(
        "primary",
        "primary visibility",
        &[Instances, Geometries],
        &[GBuffer, Stats, DispatchArgs],
    );
    pub const GBUFFER_FROM_VIS: Pass = Pass::new(
        "gbuffer_from_vis",
        "primary visibility",
        &[Visibility, Geometries],
        &[GBuffer, Stats, DispatchArgs],
    );
    pub const RTAO: Pass = Pass::new(
        "rtao",
        "per-pixel RTAO",
        &[GBuffer, PixelRays, Stats],
        &[PixelRays, Stats],
    );
    pub const CELL_FINDER: Pass = Pass::new(
        "cell_finder",
        "cell finder",
        &[
            GBuffer,
            PixelCells,
            Regions,
            HashCells,
            SkyCells,
            Stats,
            DispatchArgs,
        ],
        &[
            HashCells,
            SkyCells,
            PixelCells,
            PixelRays,
            RayQueue,
            Stats,
            DispatchArgs,
        ],
    );
    pub const AO_UPDATE: Pass = Pass::new(
        "ao_update",
        "ray-tracing update",
        &[
            Stats, RayQueue, GBuffer, PixelCells, HashCells, FilterTmp, PixelRays, SkyCells, SkyPixels,
        ],
        &[HashCells, FilterTmp, PixelRays, Stats, SkyCells, SkyPixels],
    );
    pub const RESOLVE: Pass = Pass::new(
        "resolve",
        "per-pixel AO",
        &[
            GBuffer,
            PixelCells,
            HashCells,
            PixelRays,
            Regions,
            Stats,
            DispatchArgs,
            SkyCells,
        ],
        &[
            FilterGuide,
            SlicePrior,
            LodUsed,
            FilterPlan,
            Ao,
            FilterTmp,
            FilterQueue,
            Stats,
            DispatchArgs,
            SkyPixels,
        ],
    );
    pub const FILTER: Pass = Pass::new(
        "filter",
        "filtering",
        &[
            Stats,
            FilterQueue,
            FilterPlan,
            GBuffer,
            LodUsed,
            FilterGuide,
            Ao,
            FilterTmp,
            SlicePrior,
            Regions,
            SkyPixels,
        ],
        &[Ao, FilterTmp, SkyPixels],
    );
    pub const COMPOSITE: Pass = Pass::new(
        "composite",
        "composite",
        &[
            PixelCells,
            LodUsed,
            HashCells,
            Instances,
            GBuffer,
            BiasEvidence,
            Ao,
            PixelRays,
            Accum,
            Regions,
            SkyPixels,
        ],
        &[BiasEvidence, Ao, Accum, Output, SkyPixels],
    );
    pub const HASH_TEST: Pass = Pass::new("hash_test", "hash test", &[HashTestCases], &[HashTestCases]);

    /// The shader file (`shaders/<name>.comp`).
    pub fn shader(self) -> &'static str {
        self.shader
    }

    /// The timing section it belongs to.
    pub fn section(self) -> &'static str {
        self.section
    }

    /// The buffers its shader reads.
    pub fn reads(self) -> &'static [Resource] {
        self.reads
    }

    /// The buffers its shader writes.
    pub fn writes(self) -> &'static [Resource] {
        self.writes
    }

    /// Whether its shader traces rays (`#define HRTAO_TRACES`): build.rs then compiled its ray-generation variant
    /// too, and it runs as a ray-tracing pipeline under `RayBackend::Pipeline`.
    pub fn traces(self) -> bool {
        SHADERS
            .iter()
            .any(|(n, _)| n.strip_suffix(".rgen") == Some(self.shader))
    }
}

/// The GPU buffers the passes read and write (each reached in the shaders through its `FrameGlobals` address,
/// `Resource::field`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Resource {
    /// The scene's instance table (`InstanceInfo`; the selection flags).
    Instances,
    /// The scene's geometry table (vertex and index addresses).
    Geometries,
    /// The rasterised visibility copied to a buffer (raster primary visibility only).
    Visibility,
    /// The G-buffer (`GPixel` per pixel).
    GBuffer,
    /// The local-edit region epochs.
    Regions,
    /// The world-space hash map's cells (paper §1).
    HashCells,
    /// Per pixel, the cells the cell finder found (`PixelCells`).
    PixelCells,
    /// The pixels whose cell takes rays this frame.
    RayQueue,
    /// The pixels the filter runs over.
    FilterQueue,
    /// The indirect dispatch arguments the last work group of the cell finder and of the resolve writes
    /// (queue_args.glsl).
    DispatchArgs,
    /// The frame's statistics counters (`FrameStats`, device memory).
    Stats,
    /// Its host-visible copy, made once at the end of the frame.
    StatsReadback,
    /// Per pixel, the rays it traced itself (`PixelRays`).
    PixelRays,
    /// The AO image (the filter's ping).
    Ao,
    /// The filter's pong (and adaptive sampling's scratch weights).
    FilterTmp,
    /// Per pixel, the filter plan (filter_plan.glsl).
    FilterPlan,
    /// Per pixel, the filter's guide (`FilterGuide`).
    FilterGuide,
    /// Per pixel, the LOD its AO came from.
    LodUsed,
    /// Contact detail's buffer (`additions::contact_detail::Target`: its fit sums, its per-pixel obscurance).
    ContactDetail,
    /// Per pixel, the cell estimate it resolved when last drawn (`SlicePrior`).
    SlicePrior,
    /// Still refinement's own-ray residuals.
    BiasEvidence,
    /// Still refinement's accumulation (`PixelAccum`).
    Accum,
    /// The composited RGBA8 image.
    Output,
    /// Sky light: the cells' transfer sums (beside `HashCells`, slot for slot).
    SkyCells,
    /// Sky light: per pixel, its transfer vectors, their accumulation and its light.
    SkyPixels,
    /// The cases of the hash test pass (tests only).
    HashTestCases,
    /// The frame's probe rays and their hits (`probes.rs`: the walk's gravity and collision), host-visible.
    Probes,
}

impl Resource {
    pub const ALL: [Resource; 27] = [
        Resource::Instances,
        Resource::Geometries,
        Resource::Visibility,
        Resource::GBuffer,
        Resource::Regions,
        Resource::HashCells,
        Resource::PixelCells,
        Resource::RayQueue,
        Resource::FilterQueue,
        Resource::DispatchArgs,
        Resource::Stats,
        Resource::StatsReadback,
        Resource::PixelRays,
        Resource::Ao,
        Resource::FilterTmp,
        Resource::FilterPlan,
        Resource::FilterGuide,
        Resource::LodUsed,
        Resource::ContactDetail,
        Resource::SlicePrior,
        Resource::BiasEvidence,
        Resource::Accum,
        Resource::Output,
        Resource::SkyCells,
        Resource::SkyPixels,
        Resource::HashTestCases,
        Resource::Probes,
    ];

    /// The `FrameGlobals` field holding its device address, which is how shaders reach it; None for a buffer
    /// a pass gets through its push constants (the visibility, contact detail's buffer, the hash test cases) or
    /// no shader reads.
    pub fn field(self) -> Option<&'static str> {
        Some(match self {
            Resource::Instances => "instances",
            Resource::Geometries => "geometries",
            Resource::GBuffer => "gbuffer",
            Resource::Regions => "regions",
            Resource::HashCells => "hash_cells",
            Resource::PixelCells => "pixel_cells",
            Resource::RayQueue => "ray_queue",
            Resource::FilterQueue => "filter_queue",
            Resource::DispatchArgs => "dispatch_args",
            Resource::Stats => "stats",
            Resource::PixelRays => "pixel_rays",
            Resource::Ao => "ao",
            Resource::FilterTmp => "filter_tmp",
            Resource::FilterPlan => "filter_plan",
            Resource::FilterGuide => "filter_guide",
            Resource::LodUsed => "lod_used",
            Resource::SlicePrior => "slice_prior",
            Resource::BiasEvidence => "bias_evidence",
            Resource::Accum => "accum",
            Resource::Output => "output_rgba",
            Resource::SkyCells => "sky_cells",
            Resource::SkyPixels => "sky_pixels",
            Resource::Visibility
            | Resource::StatsReadback
            | Resource::HashTestCases
            | Resource::Probes
            | Resource::ContactDetail => return None,
        })
    }

    /// The buffer reference type a pass reaches it through when it comes in its push constants.
    pub fn push_type(self) -> Option<&'static str> {
        match self {
            Resource::Visibility => Some("VisRef"),
            Resource::HashTestCases => Some("HashTestRef"),
            Resource::ContactDetail => Some("ContactDetailRef"),
            Resource::Probes => Some("ProbeRef"),
            _ => None,
        }
    }
}

/// How a pass runs: a compute pipeline, or (a tracing pass under `RayBackend::Pipeline`) a ray-tracing pipeline.
pub(crate) enum PassPipeline {
    Compute(vk::Pipeline),
    Ray(Box<RtPipeline>),
}

/// Pipelines of all passes and their shared layout and descriptor set.
pub struct PassSet {
    gpu: Arc<Gpu>,
    set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pool: vk::DescriptorPool,
    pub(crate) set: vk::DescriptorSet,
    /// The shader stages of the layout's descriptor set and push constants: compute, and ray generation under
    /// the pipeline backend.
    pub(crate) stages: vk::ShaderStageFlags,
    pub(crate) backend: RayBackend,
    pipelines: Vec<(Pass, PassPipeline)>,
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
            .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
            .map_err(|e| CoreError::from_vk("vkCreateShaderModule", e))
    }
}

impl PassSet {
    /// The pipelines of the passes of `list` (`crate::passes::ALL`), those that trace by the device's backend.
    pub fn new(gpu: &Arc<Gpu>, globals: &Buffer, list: &[Pass]) -> Result<PassSet> {
        let device = &gpu.device;
        let backend = gpu.info.ray_backend;
        let stages = match backend {
            RayBackend::Query => vk::ShaderStageFlags::COMPUTE,
            RayBackend::Pipeline => vk::ShaderStageFlags::COMPUTE | vk::ShaderStageFlags::RAYGEN_KHR,
        };
        unsafe {
            let bindings = [
                vk::DescriptorSetLayoutBinding::default()
                    .binding(0)
                    .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1)
                    .stage_flags(stages),
                vk::DescriptorSetLayoutBinding::default()
                    .binding(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(stages),
            ];
            let set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateDescriptorSetLayout", e))?;
            let push = [vk::PushConstantRange {
                stage_flags: stages,
                offset: 0,
                size: 16,
            }];
            let set_layouts = [set_layout];
            let layout = device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default()
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
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(1)
                        .pool_sizes(&sizes),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateDescriptorPool", e))?;
            let set = device
                .allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(pool)
                        .set_layouts(&set_layouts),
                )
                .map_err(|e| CoreError::from_vk("vkAllocateDescriptorSets", e))?[0];
            let buffer_info = [vk::DescriptorBufferInfo {
                buffer: globals.raw,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }];
            let write = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&buffer_info);
            device.update_descriptor_sets(&[write], &[]);
            let mut passes = PassSet {
                gpu: gpu.clone(),
                set_layout,
                layout,
                pool,
                set,
                stages,
                backend,
                pipelines: Vec::new(),
                bound_tlas: vk::AccelerationStructureKHR::null(),
                bound_generation: 0,
                tlas_writes: 0,
            };
            for &pass in list {
                if backend == RayBackend::Pipeline && pass.traces() {
                    let rt = RtPipeline::new(gpu, layout, &format!("{}.rgen", pass.shader()))?;
                    passes.pipelines.push((pass, PassPipeline::Ray(Box::new(rt))));
                    continue;
                }
                let module = shader_module(gpu, pass.shader())?;
                let entry = c"main";
                let stage = vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::COMPUTE)
                    .module(module)
                    .name(entry);
                let info = [vk::ComputePipelineCreateInfo::default()
                    .stage(stage)
                    .layout(layout)];
                let result = device.create_compute_pipelines(vk::PipelineCache::null(), &info, None);
                device.destroy_shader_module(module, None);
                let pipeline = result.map_err(|(_, e)| CoreError::from_vk("vkCreateComputePipelines", e))?[0];
                passes.pipelines.push((pass, PassPipeline::Compute(pipeline)));
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
            vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(&handles);
        let mut write = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(0)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .push_next(&mut as_write);
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

    pub(crate) fn pipeline(&self, pass: Pass) -> &PassPipeline {
        self.pipelines
            .iter()
            .find(|(p, _)| *p == pass)
            .map(|(_, p)| p)
            .unwrap()
    }

    /// How the passes that trace rays trace them.
    pub fn ray_backend(&self) -> RayBackend {
        self.backend
    }
}

impl Drop for PassSet {
    fn drop(&mut self) {
        unsafe {
            let d = &self.gpu.device;
            for (_, p) in self.pipelines.drain(..) {
                match p {
                    PassPipeline::Compute(p) => d.destroy_pipeline(p, None),
                    // Destroys its pipeline and its shader binding table.
                    PassPipeline::Ray(rt) => drop(rt),
                }
            }
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
