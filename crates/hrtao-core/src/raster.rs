//! Rasterised primary visibility: the same G-buffer as the ray-query pass (`primary.comp`), found by drawing
//! every visible instance into a visibility buffer and intersecting each pixel's camera ray with the triangle
//! it holds.
//!
//! - `RasterScene` (owned by `SceneGpu`): per unique mesh, its geometries and the transforms of its visible
//!   instances; one instanced draw per geometry.
//! - `Rasterizer` (owned by `Renderer`): the render pass and pipeline, and `VisTargets`, the per-resolution
//!   visibility image (instance, geometry, primitive, instance slot per pixel), depth image and their copy in a
//!   buffer, which `gbuffer_from_vis.comp` turns into the G-buffer.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;
use hrtao_scene::Scene;

use crate::barrier::{Stage, Use};
use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::{CoreError, Result};
use crate::gpu::{FrameGlobals, RasterInstance, RasterPush, NO_INSTANCE, PROJECTION_ORTHOGRAPHIC};
use crate::pass::{shader_module, Pass, Resource};
use crate::recorder::Recorder;

/// How the renderer finds the surface seen through each pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Primary {
    /// One ray query per pixel (`primary.comp`): cost grows with pixels, barely with triangles.
    #[default]
    RayQuery,
    /// Instanced draws into a visibility buffer, then one ray-triangle test per pixel: cost grows with the
    /// drawn triangles.
    Raster,
}

const VIS_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// Bytes per pixel of the visibility buffer (one uvec4).
const VIS_TEXEL: u64 = 16;
/// Near plane as a fraction of the eye-target distance (depth is reversed and infinite: precision does not
/// depend on it; geometry nearer than this is clipped).
const NEAR_FRACTION: f32 = 1e-5;

/// One geometry (primitive) of a unique mesh, as drawn: its entry in the geometry table and its triangles in
/// the scene's index buffer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RasterGeometry {
    pub geometry: u32,
    pub triangles: u32,
    /// Its first index in the index buffer (indices count from its own first vertex).
    pub first_index: u64,
    /// Back faces may show (see `Primitive::double_sided`): never culled.
    pub double_sided: bool,
}

/// Which faces a draw keeps. Culling back faces halves the triangles llvmpipe sets up and bins (its
/// rasteriser is bound by that, not by pixels: 376k triangles of the bundled scene took 100 ms at 32×28).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Faces {
    Both,
    /// Front faces wound counter-clockwise as seen (glTF's rule for instances with a positive determinant).
    FrontCcw,
    /// Front faces clockwise: instances whose transform mirrors (negative determinant) flip the winding.
    FrontCw,
}

/// One instanced, indexed draw: the visible instances of a mesh sharing a handedness, one geometry of it.
/// Indexed, because llvmpipe skips culled triangles early only in indexed draws (measured: culling a
/// non-indexed draw saved nothing).
#[derive(Clone, Copy, Debug)]
struct Draw {
    geometry: RasterGeometry,
    faces: Faces,
    first_instance: u32,
    instance_count: u32,
}

/// The names of `RasterScene`'s host-written tables.
const INSTANCES: &str = "raster instances";
const COMMANDS: &str = "raster draw commands";
const GEOMETRIES: &str = "raster draw geometries";

/// `VkDrawIndexedIndirectCommand`: index count, instance count, first index, vertex offset, first instance.
type DrawCommand = [u32; 5];

impl Draw {
    fn command(&self) -> DrawCommand {
        let g = &self.geometry;
        [
            g.triangles * 3,
            self.instance_count,
            g.first_index as u32,
            0,
            self.first_instance,
        ]
    }
}

/// The scene's draw list and visible-instance transforms (rebuilt with the TLAS).
pub struct RasterScene {
    /// Per unique mesh: its geometries.
    mesh_geometries: Vec<Vec<RasterGeometry>>,
    /// The scene's index buffer (owned by `SceneGpu`, which owns this draw list too).
    index_buffer: vk::Buffer,
    instances: Buffer,
    /// Sorted by `faces`, so that each pipeline's draws are one run.
    draws: Vec<Draw>,
    /// `draws` as `VkDrawIndexedIndirectCommand`s (one indirect call per run on devices with
    /// `multiDrawIndirect`: llvmpipe spends ~6.5 µs on each separate draw call, 31 ms of san_francisco's 4,735).
    commands: Buffer,
    /// Per draw, its geometry (u32), which the vertex stage finds by `first_draw + gl_DrawID`: the instance
    /// rows stay one per visible instance whatever its mesh's geometry count.
    draw_geometries: Buffer,
    /// Conservative world bounds of the drawn instances: the far plane of orthographic views.
    bounds: hrtao_scene::Aabb,
}

impl RasterScene {
    pub(crate) fn new(
        gpu: &Arc<Gpu>,
        mesh_geometries: Vec<Vec<RasterGeometry>>,
        index_buffer: vk::Buffer,
    ) -> Result<RasterScene> {
        for (m, geos) in mesh_geometries.iter().enumerate() {
            // A draw addresses its indices with 32 bits.
            let fits = |g: &RasterGeometry| (g.triangles as u64 * 3 + g.first_index) <= u32::MAX as u64;
            if let Some(g) = geos.iter().find(|g| !fits(g)) {
                return Err(CoreError::Invalid(format!(
                    "mesh {m} has a primitive of {} triangles past index {}: at most {} indices can be drawn",
                    g.triangles,
                    g.first_index,
                    u32::MAX
                )));
            }
        }
        Ok(RasterScene {
            mesh_geometries,
            index_buffer,
            instances: Self::table::<RasterInstance>(gpu, INSTANCES, 1, vk::BufferUsageFlags::empty())?,
            draws: Vec::new(),
            commands: Self::table::<DrawCommand>(gpu, COMMANDS, 1, vk::BufferUsageFlags::INDIRECT_BUFFER)?,
            draw_geometries: Self::table::<u32>(gpu, GEOMETRIES, 1, vk::BufferUsageFlags::empty())?,
            bounds: hrtao_scene::Aabb::empty(),
        })
    }

    /// A host-written table of `count` values of `T` (at least one).
    fn table<T>(gpu: &Arc<Gpu>, name: &str, count: usize, usage: vk::BufferUsageFlags) -> Result<Buffer> {
        let bytes = count.max(1) * std::mem::size_of::<T>();
        Buffer::new(gpu, name, bytes as u64, MemoryLocation::CpuToGpu, usage)
    }

    /// Writes `values` into `buffer`, replaced by a larger one first if they do not fit.
    fn write_table<T: bytemuck::Pod>(
        gpu: &Arc<Gpu>,
        buffer: &mut Buffer,
        name: &str,
        values: &[T],
        usage: vk::BufferUsageFlags,
    ) -> Result<()> {
        if buffer.size < std::mem::size_of_val(values) as u64 {
            *buffer = Self::table::<T>(gpu, name, values.len(), usage)?;
        }
        buffer.write(values)
    }

    /// Collects the visible instances of meshes with triangles (those the TLAS holds), grouped by mesh.
    /// Must not be called while a frame using the scene is in flight.
    /// `drawn[i]` is false for instances left out (hidden, or cut away by a section plane).
    pub(crate) fn update(&mut self, gpu: &Arc<Gpu>, scene: &Scene, drawn: &[bool]) -> Result<()> {
        // Per mesh and handedness (mirroring instances wind their front faces the other way).
        let meshes = self.mesh_geometries.len();
        let mut by_mesh: Vec<Vec<u32>> = vec![Vec::new(); 2 * meshes];
        for (i, inst) in scene.instances.iter().enumerate() {
            let m = inst.mesh as usize;
            if drawn[i] && self.mesh_geometries.get(m).is_some_and(|g| !g.is_empty()) {
                let mirrored = glam::Mat3::from_mat4(inst.transform).determinant() < 0.0;
                by_mesh[m + meshes * mirrored as usize].push(i as u32);
            }
        }
        let mut table = Vec::new();
        self.draws.clear();
        for (k, ids) in by_mesh.iter().enumerate() {
            if ids.is_empty() {
                continue;
            }
            let (m, mirrored) = (k % meshes, k >= meshes);
            let first_instance = table.len() as u32;
            for &i in ids {
                let t = scene.instances[i as usize].transform;
                let row = |r: usize| [t.col(0)[r], t.col(1)[r], t.col(2)[r], t.col(3)[r]];
                table.push(RasterInstance {
                    row0: row(0),
                    row1: row(1),
                    row2: row(2),
                    instance: i,
                    _pad: [0; 3],
                });
            }
            for &geometry in &self.mesh_geometries[m] {
                self.draws.push(Draw {
                    geometry,
                    faces: match (geometry.double_sided, mirrored) {
                        (true, _) => Faces::Both,
                        (false, false) => Faces::FrontCcw,
                        (false, true) => Faces::FrontCw,
                    },
                    first_instance,
                    instance_count: ids.len() as u32,
                });
            }
        }
        self.draws.sort_by_key(|d| d.faces as u8);
        let commands: Vec<DrawCommand> = self.draws.iter().map(Draw::command).collect();
        let geometries: Vec<u32> = self.draws.iter().map(|d| d.geometry.geometry).collect();
        self.bounds = scene.bounds_conservative();
        let none = vk::BufferUsageFlags::empty();
        Self::write_table(gpu, &mut self.instances, INSTANCES, &table, none)?;
        Self::write_table(gpu, &mut self.draw_geometries, GEOMETRIES, &geometries, none)?;
        let indirect = vk::BufferUsageFlags::INDIRECT_BUFFER;
        Self::write_table(gpu, &mut self.commands, COMMANDS, &commands, indirect)
    }

    /// The runs of `draws` that share a pipeline: by handedness when back faces are culled, else all of them.
    fn runs(&self, cull: bool) -> Vec<(Faces, std::ops::Range<usize>)> {
        if !cull {
            return vec![(Faces::Both, 0..self.draws.len())];
        }
        let mut runs: Vec<(Faces, std::ops::Range<usize>)> = Vec::new();
        for (i, d) in self.draws.iter().enumerate() {
            match runs.last_mut() {
                Some((f, r)) if *f == d.faces => r.end = i + 1,
                _ => runs.push((d.faces, i..i + 1)),
            }
        }
        runs
    }

    /// Conservative world bounds of the drawn (visible) instances; empty when nothing is drawn.
    pub fn bounds(&self) -> hrtao_scene::Aabb {
        self.bounds
    }

    /// Triangles drawn per frame (every visible instance's).
    pub fn triangles(&self) -> u64 {
        self.draws
            .iter()
            .map(|d| d.geometry.triangles as u64 * d.instance_count as u64)
            .sum()
    }
}

/// A 2D image with its memory and one view, destroyed together.
struct Image {
    gpu: Arc<Gpu>,
    raw: vk::Image,
    allocation: Option<Allocation>,
    view: vk::ImageView,
}

impl Image {
    fn new(
        gpu: &Arc<Gpu>,
        name: &str,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        aspect: vk::ImageAspectFlags,
        (width, height): (u32, u32),
    ) -> Result<Image> {
        unsafe {
            let raw = gpu
                .device
                .create_image(
                    &crate::buffer::image_2d_info(format, usage, (width, height)),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateImage", e))?;
            // From here on, Drop releases whatever exists.
            let mut image = Image {
                gpu: gpu.clone(),
                raw,
                allocation: None,
                view: vk::ImageView::null(),
            };
            let requirements = gpu.device.get_image_memory_requirements(raw);
            let allocation = crate::buffer::allocate(gpu, name, requirements, MemoryLocation::GpuOnly, false)
                .map_err(|e| CoreError::Memory(format!("image `{name}` ({width}x{height}): {e}")))?;
            let (memory, offset) = (allocation.memory(), allocation.offset());
            gpu.device_bytes
                .fetch_add(allocation.size(), std::sync::atomic::Ordering::Relaxed);
            image.allocation = Some(allocation);
            gpu.device
                .bind_image_memory(raw, memory, offset)
                .map_err(|e| CoreError::from_vk("vkBindImageMemory", e))?;
            image.view = gpu
                .device
                .create_image_view(
                    &vk::ImageViewCreateInfo::default()
                        .image(raw)
                        .view_type(vk::ImageViewType::TYPE_2D)
                        .format(format)
                        .subresource_range(subresource_range(aspect)),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateImageView", e))?;
            Ok(image)
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            self.gpu.device.destroy_image_view(self.view, None);
            self.gpu.device.destroy_image(self.raw, None);
            if let Some(a) = self.allocation.take() {
                self.gpu
                    .device_bytes
                    .fetch_sub(a.size(), std::sync::atomic::Ordering::Relaxed);
                let _ = self.gpu.allocator().free(a);
            }
        }
    }
}

fn subresource_range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

/// The per-resolution visibility targets: images, their framebuffer and the visibility buffer.
struct VisTargets {
    gpu: Arc<Gpu>,
    /// The images' size: a frame draws its own size from the top-left corner (a smaller one reuses them).
    size: (u32, u32),
    vis: Image,
    _depth: Image,
    framebuffer: vk::Framebuffer,
    /// The visibility image copied out, read by gbuffer_from_vis.comp through its address.
    vis_buffer: Buffer,
}

impl VisTargets {
    fn new(gpu: &Arc<Gpu>, render_pass: vk::RenderPass, size: (u32, u32)) -> Result<VisTargets> {
        // The two attachments of the render pass: (name, format, usage, aspect).
        let color_usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let depth_usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
        let [vis, depth] = [
            ("visibility", VIS_FORMAT, color_usage, vk::ImageAspectFlags::COLOR),
            (
                "visibility depth",
                DEPTH_FORMAT,
                depth_usage,
                vk::ImageAspectFlags::DEPTH,
            ),
        ]
        .map(|(name, format, usage, aspect)| Image::new(gpu, name, format, usage, aspect, size));
        let (vis, depth) = (vis?, depth?);
        let vis_buffer = Buffer::new(
            gpu,
            "visibility buffer",
            size.0 as u64 * size.1 as u64 * VIS_TEXEL,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        let views = [vis.view, depth.view];
        let framebuffer = unsafe {
            gpu.device
                .create_framebuffer(
                    &vk::FramebufferCreateInfo::default()
                        .render_pass(render_pass)
                        .attachments(&views)
                        .width(size.0)
                        .height(size.1)
                        .layers(1),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateFramebuffer", e))?
        };
        Ok(VisTargets {
            gpu: gpu.clone(),
            size,
            vis,
            _depth: depth,
            framebuffer,
            vis_buffer,
        })
    }
}

impl Drop for VisTargets {
    fn drop(&mut self) {
        unsafe { self.gpu.device.destroy_framebuffer(self.framebuffer, None) }
    }
}

/// The visibility render pass and pipeline, and the targets of the current resolution.
pub struct Rasterizer {
    gpu: Arc<Gpu>,
    render_pass: vk::RenderPass,
    layout: vk::PipelineLayout,
    /// One pipeline per `Faces` (indexed by `Faces as usize`).
    pipelines: [vk::Pipeline; 3],
    targets: Option<VisTargets>,
    /// What the visibility image holds: the draw's push constants, section planes and scene generation (TLAS
    /// build, instance tables). None once the targets change.
    drawn: Option<DrawKey>,
}

/// Everything a visibility draw depends on: while it is unchanged (the frames of a round of slices share the
/// camera and the round's jitter), the image drawn is still right and is not drawn again.
#[derive(Clone, PartialEq)]
struct DrawKey {
    size: (u32, u32),
    push: Vec<u8>,
    sections: [[f32; 4]; 3],
    section_count: u32,
    generation: (u64, u64),
}

impl Rasterizer {
    /// Whether the device can rasterise the visibility (otherwise primary visibility stays with ray queries).
    pub fn available(gpu: &Gpu) -> Result<()> {
        let depth_features = unsafe {
            gpu.instance
                .get_physical_device_format_properties(gpu.physical, DEPTH_FORMAT)
                .optimal_tiling_features
        };
        if !gpu.info.primitive_id_in_fragment {
            return Err(CoreError::Invalid(format!(
                "{}: no geometryShader feature (gl_PrimitiveID in fragment shaders), rasterised primary \
                 visibility is unavailable",
                gpu.info.name
            )));
        }
        if !gpu.info.draw_parameters {
            return Err(CoreError::Invalid(format!(
                "{}: no shaderDrawParameters feature (gl_DrawID), rasterised primary visibility is unavailable",
                gpu.info.name
            )));
        }
        if !depth_features.contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT) {
            return Err(CoreError::Invalid(format!(
                "{}: no {DEPTH_FORMAT:?} depth attachment, rasterised primary visibility is unavailable",
                gpu.info.name
            )));
        }
        Ok(())
    }

    pub fn new(gpu: &Arc<Gpu>) -> Result<Rasterizer> {
        Self::available(gpu)?;
        let mut r = Rasterizer {
            gpu: gpu.clone(),
            render_pass: vk::RenderPass::null(),
            layout: vk::PipelineLayout::null(),
            pipelines: [vk::Pipeline::null(); 3],
            targets: None,
            drawn: None,
        };
        r.render_pass = create_render_pass(gpu)?;
        let push = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::VERTEX,
            offset: 0,
            size: std::mem::size_of::<RasterPush>() as u32,
        }];
        r.layout = unsafe {
            gpu.device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&push),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreatePipelineLayout", e))?
        };
        for faces in [Faces::Both, Faces::FrontCcw, Faces::FrontCw] {
            r.pipelines[faces as usize] = create_pipeline(gpu, r.render_pass, r.layout, faces)?;
        }
        Ok(r)
    }

    /// Makes the targets hold an image of this size (call outside a frame in flight): kept when they are at
    /// least as large, else made as large as both.
    pub fn prepare(&mut self, width: u32, height: u32) -> Result<()> {
        let held = self.targets.as_ref().map_or((0, 0), |t| t.size);
        if held.0 < width || held.1 < height {
            self.targets = None;
            self.drawn = None;
            let size = (held.0.max(width), held.1.max(height));
            self.targets = Some(VisTargets::new(&self.gpu, self.render_pass, size)?);
        }
        Ok(())
    }

    /// Records the visibility draws and the copy of the visibility image, unless the image already holds this
    /// very draw (`DrawKey`), then the G-buffer resolve of the frame's pixels, all timed as primary
    /// visibility. The image is always the whole frame's: a round of slices draws it at its first slice and
    /// each slice resolves its own pixels from it, so a slice does not pay for every triangle again (on a
    /// software device that is most of a small slice's cost). `globals` are the frame's (camera and size), at
    /// device address `globals_address` (the draws read the section planes there); `target_distance` is the
    /// camera's eye-target distance (it sets the perspective near plane); `generation` names the scene's
    /// geometry (`SceneGpu::tlas_generation`, `version`); `slice_grid` is the frame's invocations over the image
    /// (`Renderer::slice_grid`), None to draw only (`Renderer::record_visibility`). Returns whether it drew (the
    /// image did not hold this draw). Panics if `prepare` was not called for this size.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        rec: &mut Recorder,
        scene: &RasterScene,
        globals: &FrameGlobals,
        globals_address: u64,
        target_distance: f32,
        off_axis: Option<(glam::Vec3, [f32; 2])>,
        generation: (u64, u64),
        slice_grid: Option<(u32, u32)>,
    ) -> bool {
        let t = self.targets.as_ref().expect("Rasterizer::prepare before record");
        let gpu_multi_draw = self.gpu.info.multi_draw_indirect;
        let (w, h) = (globals.width, globals.height);
        assert!(
            t.size.0 >= w && t.size.1 >= h,
            "visibility targets smaller than the frame"
        );
        let scaled = |v: [f32; 4]| {
            let len2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            [v[0] / len2, v[1] / len2, v[2] / len2, 0.0]
        };
        let depth = if globals.projection == PROJECTION_ORTHOGRAPHIC {
            1.0 / Self::ortho_far_plane(globals, &scene.bounds)
        } else {
            Self::near_plane(target_distance)
        };
        let push = RasterPush {
            eye: [globals.eye[0], globals.eye[1], globals.eye[2], depth],
            cam_u: scaled(globals.cam_u),
            cam_v: scaled(globals.cam_v),
            cam_w: match off_axis {
                Some((axis, _)) => [axis.x, axis.y, axis.z, 0.0],
                None => globals.cam_w,
            },
            geometries: globals.geometries,
            instances: scene.instances.address,
            projection: globals.projection,
            _pad: 0,
            jitter_ndc: {
                let [ox, oy] = off_axis.map_or([0.0; 2], |(_, o)| o);
                let (fw, fh) = (globals.width as f32, globals.height as f32);
                [
                    2.0 * globals.jitter[0] / fw + ox,
                    2.0 * globals.jitter[1] / fh + oy,
                ]
            },
            globals: globals_address,
            draw_geometries: scene.draw_geometries.address,
            first_draw: 0,
            _pad1: 0,
        };
        let key = DrawKey {
            size: (w, h),
            push: bytemuck::bytes_of(&push).to_vec(),
            sections: [globals.section0, globals.section1, globals.section2],
            section_count: globals.section_count,
            generation,
        };
        let ([vis_lo, vis_hi], [inst_lo, inst_hi]) =
            (t.vis_buffer.address_words(), scene.instances.address_words());
        // Over the frame's pixels (its slice): each reads its own pixel of the whole frame's visibility.
        let resolve = |rec: &mut Recorder| {
            if let Some((gw, gh)) = slice_grid {
                rec.dispatch(Pass::GBUFFER_FROM_VIS, gw, gh, [vis_lo, vis_hi, inst_lo, inst_hi])
            }
        };
        if self.drawn.as_ref() == Some(&key) {
            resolve(rec);
            return false;
        }
        self.drawn = Some(key);
        let extent = vk::Extent2D { width: w, height: h };
        // The draws read the scene's geometry table; the visibility image is copied to a buffer that
        // gbuffer_from_vis.comp reads.
        let uses = vec![
            Use::read(Resource::Geometries, Stage::Graphics),
            Use::write(Resource::Visibility, Stage::Transfer),
        ];
        rec.commands(
            "raster visibility",
            Some(Pass::PRIMARY.section()),
            uses,
            |d, cmd| unsafe {
                let clear = [
                    vk::ClearValue {
                        color: vk::ClearColorValue {
                            uint32: [NO_INSTANCE, 0, 0, 0],
                        },
                    },
                    vk::ClearValue {
                        depth_stencil: vk::ClearDepthStencilValue {
                            depth: 0.0,
                            stencil: 0,
                        },
                    },
                ];
                d.cmd_begin_render_pass(
                    cmd,
                    &vk::RenderPassBeginInfo::default()
                        .render_pass(self.render_pass)
                        .framebuffer(t.framebuffer)
                        .render_area(vk::Rect2D {
                            offset: vk::Offset2D::default(),
                            extent,
                        })
                        .clear_values(&clear),
                    vk::SubpassContents::INLINE,
                );
                d.cmd_set_viewport(
                    cmd,
                    0,
                    &[vk::Viewport {
                        x: 0.0,
                        y: 0.0,
                        width: w as f32,
                        height: h as f32,
                        min_depth: 0.0,
                        max_depth: 1.0,
                    }],
                );
                d.cmd_set_scissor(
                    cmd,
                    0,
                    &[vk::Rect2D {
                        offset: vk::Offset2D::default(),
                        extent,
                    }],
                );
                // A section plane opens the solids: their back faces show through the cut.
                let cull = globals.section_count == 0;
                let multi_draw = gpu_multi_draw;
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::VERTEX,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.cmd_bind_index_buffer(cmd, scene.index_buffer, 0, vk::IndexType::UINT32);
                let stride = std::mem::size_of::<DrawCommand>();
                // Each call names its first draw: the vertex stage finds a draw's geometry at first_draw +
                // gl_DrawID (which counts the draws of one indirect call, and is 0 for a direct draw).
                let first_draw = |draw: usize| {
                    d.cmd_push_constants(
                        cmd,
                        self.layout,
                        vk::ShaderStageFlags::VERTEX,
                        std::mem::offset_of!(RasterPush, first_draw) as u32,
                        bytemuck::bytes_of(&(draw as u32)),
                    )
                };
                for (faces, run) in scene.runs(cull) {
                    d.cmd_bind_pipeline(
                        cmd,
                        vk::PipelineBindPoint::GRAPHICS,
                        self.pipelines[faces as usize],
                    );
                    if multi_draw {
                        // maxDrawIndirectCount is at least 2^16 - 1 where multiDrawIndirect is supported.
                        for start in run.clone().step_by(0xffff) {
                            let count = (run.end - start).min(0xffff);
                            first_draw(start);
                            d.cmd_draw_indexed_indirect(
                                cmd,
                                scene.commands.raw,
                                (start * stride) as u64,
                                count as u32,
                                stride as u32,
                            );
                        }
                    } else {
                        for (k, c) in scene.draws[run.clone()].iter().enumerate() {
                            let [count, instances, first_index, _, first_instance] = c.command();
                            first_draw(run.start + k);
                            d.cmd_draw_indexed(cmd, count, instances, first_index, 0, first_instance);
                        }
                    }
                }
                d.cmd_end_render_pass(cmd);
                d.cmd_copy_image_to_buffer(
                    cmd,
                    t.vis.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    t.vis_buffer.raw,
                    &[crate::buffer::whole_image_copy(w, h)],
                );
            },
        );
        resolve(rec);
        true
    }

    /// The far plane of an orthographic view (depth is linear there): just beyond the farthest corner of the
    /// scene bounds along the view direction, and never zero.
    fn ortho_far_plane(globals: &FrameGlobals, bounds: &hrtao_scene::Aabb) -> f32 {
        let eye = glam::Vec3::from_slice(&globals.eye[..3]);
        let w = glam::Vec3::from_slice(&globals.cam_w[..3]);
        let far = if bounds.is_empty() {
            1.0
        } else {
            bounds
                .corners()
                .iter()
                .map(|c| (*c - eye).dot(w))
                .fold(0.0f32, f32::max)
        };
        (far * 1.001).max(f32::MIN_POSITIVE.sqrt())
    }

    /// The near plane for a camera whose eye is `distance` from its target.
    pub fn near_plane(distance: f32) -> f32 {
        (distance * NEAR_FRACTION).max(f32::MIN_POSITIVE)
    }
}

impl Drop for Rasterizer {
    fn drop(&mut self) {
        self.targets = None;
        unsafe {
            let d = &self.gpu.device;
            for p in self.pipelines {
                d.destroy_pipeline(p, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_render_pass(self.render_pass, None);
        }
    }
}

/// One subpass writing the visibility and depth attachments; the visibility image ends ready to be copied.
/// The external dependencies order it after the previous frame's copy and resolve, and the copy after it.
fn create_render_pass(gpu: &Gpu) -> Result<vk::RenderPass> {
    // Both cleared at the start, no stencil; the visibility image is kept for the copy, the depth is not.
    let attachment = |format, store_op, final_layout| {
        vk::AttachmentDescription::default()
            .format(format)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(store_op)
            .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
            .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(final_layout)
    };
    let attachments = [
        attachment(
            VIS_FORMAT,
            vk::AttachmentStoreOp::STORE,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        ),
        attachment(
            DEPTH_FORMAT,
            vk::AttachmentStoreOp::DONT_CARE,
            vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        ),
    ];
    let color_ref = [vk::AttachmentReference {
        attachment: 0,
        layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    }];
    let depth_ref = vk::AttachmentReference {
        attachment: 1,
        layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    };
    let subpass = [vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&color_ref)
        .depth_stencil_attachment(&depth_ref)];
    let fragment_tests =
        vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
    let dependencies = [
        vk::SubpassDependency {
            src_subpass: vk::SUBPASS_EXTERNAL,
            dst_subpass: 0,
            src_stage_mask: vk::PipelineStageFlags::TRANSFER
                | vk::PipelineStageFlags::COMPUTE_SHADER
                | fragment_tests,
            dst_stage_mask: vk::PipelineStageFlags::VERTEX_SHADER
                | fragment_tests
                | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            src_access_mask: vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
            dst_access_mask: vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE
                | vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            dependency_flags: vk::DependencyFlags::empty(),
        },
        vk::SubpassDependency {
            src_subpass: 0,
            dst_subpass: vk::SUBPASS_EXTERNAL,
            src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            dst_stage_mask: vk::PipelineStageFlags::TRANSFER,
            src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            dst_access_mask: vk::AccessFlags::TRANSFER_READ,
            dependency_flags: vk::DependencyFlags::empty(),
        },
    ];
    unsafe {
        gpu.device
            .create_render_pass(
                &vk::RenderPassCreateInfo::default()
                    .attachments(&attachments)
                    .subpasses(&subpass)
                    .dependencies(&dependencies),
                None,
            )
            .map_err(|e| CoreError::from_vk("vkCreateRenderPass", e))
    }
}

/// Vertex pulling (no vertex input), the faces `faces` keeps, reversed depth (nearer = greater), viewport set
/// per frame.
fn create_pipeline(
    gpu: &Gpu,
    render_pass: vk::RenderPass,
    layout: vk::PipelineLayout,
    faces: Faces,
) -> Result<vk::Pipeline> {
    let vert = shader_module(gpu, "visibility.vert")?;
    let frag = match shader_module(gpu, "visibility.frag") {
        Ok(f) => f,
        Err(e) => {
            unsafe { gpu.device.destroy_shader_module(vert, None) };
            return Err(e);
        }
    };
    let entry = c"main";
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vert)
            .name(entry),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(frag)
            .name(entry),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let input_assembly =
        vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(match faces {
            Faces::Both => vk::CullModeFlags::NONE,
            _ => vk::CullModeFlags::BACK,
        })
        // The projection (visibility.vert) maps the view's up to the top row like Vulkan's y-down viewport,
        // which keeps the winding as seen: a front face counter-clockwise to the viewer is COUNTER_CLOCKWISE.
        .front_face(match faces {
            Faces::FrontCw => vk::FrontFace::CLOCKWISE,
            _ => vk::FrontFace::COUNTER_CLOCKWISE,
        })
        .line_width(1.0);
    let multisample =
        vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(true)
        .depth_write_enable(true)
        .depth_compare_op(vk::CompareOp::GREATER);
    let blend_attachment = [vk::PipelineColorBlendAttachmentState::default()
        .blend_enable(false)
        .color_write_mask(vk::ColorComponentFlags::RGBA)];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachment);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let info = [vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&input_assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .render_pass(render_pass)
        .subpass(0)];
    let result = unsafe {
        gpu.device
            .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
    };
    unsafe {
        gpu.device.destroy_shader_module(vert, None);
        gpu.device.destroy_shader_module(frag, None);
    }
    result
        .map(|p| p[0])
        .map_err(|(_, e)| CoreError::from_vk("vkCreateGraphicsPipelines", e))
}
