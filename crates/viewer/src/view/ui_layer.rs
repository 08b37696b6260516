//! egui drawn over the 3D view in the swapchain image: egui-ash-renderer's pipeline and textures, the render
//! pass that keeps the blitted view (load) and leaves the image ready to present, and one framebuffer per
//! swapchain image. Owned by the `Presenter`, which rebuilds the framebuffers with its swapchain.
use std::sync::Arc;

use anyhow::{Context, Result};
use ash::vk;
use egui_ash_renderer::allocator::GpuAllocator;
use egui_ash_renderer::{Options, RenderMode, Renderer};
use hrtao_core::Gpu;

use super::ui_colors;

pub struct UiLayer {
    gpu: Arc<Gpu>,
    format: vk::Format,
    render_pass: vk::RenderPass,
    views: Vec<vk::ImageView>,
    framebuffers: Vec<vk::Framebuffer>,
    extent: vk::Extent2D,
    /// None only after `destroy`.
    renderer: Option<Renderer<GpuAllocator>>,
    /// Textures egui released in the frame being drawn: freed once it has completed.
    to_free: Vec<egui::TextureId>,
}

/// The pass after the view's blit: the image arrives in COLOR_ATTACHMENT_OPTIMAL (present.rs `record_view`),
/// egui blends over it, and it leaves in PRESENT_SRC_KHR.
fn create_render_pass(device: &ash::Device, format: vk::Format) -> Result<vk::RenderPass> {
    let attachment = [vk::AttachmentDescription::default()
        .format(format)
        .samples(vk::SampleCountFlags::TYPE_1)
        .load_op(vk::AttachmentLoadOp::LOAD)
        .store_op(vk::AttachmentStoreOp::STORE)
        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
        .initial_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .final_layout(vk::ImageLayout::PRESENT_SRC_KHR)];
    let color = [vk::AttachmentReference::default()
        .attachment(0)
        .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
    let subpass = [vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&color)];
    let dependency = [vk::SubpassDependency::default()
        .src_subpass(vk::SUBPASS_EXTERNAL)
        .dst_subpass(0)
        .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
        .dst_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
        .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
        .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_READ | vk::AccessFlags::COLOR_ATTACHMENT_WRITE)];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachment)
        .subpasses(&subpass)
        .dependencies(&dependency);
    unsafe { device.create_render_pass(&info, None) }.context("cannot create the UI render pass")
}

impl UiLayer {
    /// The layer for swapchain images of `format` (framebuffers come with the swapchain, `resize`).
    pub fn new(gpu: &Arc<Gpu>, format: vk::Format) -> Result<UiLayer> {
        let render_pass = create_render_pass(&gpu.device, format)?;
        let renderer = Renderer::with_gpu_allocator(
            gpu.allocator_arc(),
            gpu.device.clone(),
            RenderMode::RenderPass(render_pass),
            // A UNORM swapchain's images hold sRGB-encoded values: `prepare` hands the renderer colours that
            // its decoding turns back into egui's, so its fragments need no encoding (ui_colors.rs). An `_SRGB`
            // swapchain encodes the renderer's linear output itself.
            // Its vertex buffers, one set per frame in flight (present.rs).
            Options {
                in_flight_frames: super::present::MAX_FRAMES_IN_FLIGHT,
                srgb_framebuffer: true,
                ..Options::default()
            },
        );
        let renderer = match renderer {
            Ok(r) => r,
            Err(e) => {
                unsafe { gpu.device.destroy_render_pass(render_pass, None) };
                return Err(e).context("cannot create egui's renderer");
            }
        };
        Ok(UiLayer {
            gpu: gpu.clone(),
            format,
            render_pass,
            views: Vec::new(),
            framebuffers: Vec::new(),
            extent: vk::Extent2D::default(),
            renderer: Some(renderer),
            to_free: Vec::new(),
        })
    }

    /// Framebuffers for a new swapchain (the device is idle: `Presenter::recreate` waited).
    pub fn resize(&mut self, images: &[vk::Image], format: vk::Format, extent: vk::Extent2D) -> Result<()> {
        self.destroy_framebuffers();
        let d = &self.gpu.device;
        if format != self.format {
            let pass = create_render_pass(d, format)?;
            if let Some(r) = self.renderer.as_mut() {
                r.set_render_mode(RenderMode::RenderPass(pass))
                    .context("cannot rebuild egui's pipeline")?;
            }
            unsafe { d.destroy_render_pass(self.render_pass, None) };
            self.render_pass = pass;
            self.format = format;
        }
        self.extent = extent;
        for &image in images {
            let view = unsafe {
                d.create_image_view(
                    &vk::ImageViewCreateInfo::default()
                        .image(image)
                        .view_type(vk::ImageViewType::TYPE_2D)
                        .format(format)
                        .subresource_range(vk::ImageSubresourceRange {
                            aspect_mask: vk::ImageAspectFlags::COLOR,
                            base_mip_level: 0,
                            level_count: 1,
                            base_array_layer: 0,
                            layer_count: 1,
                        }),
                    None,
                )
            }?;
            self.views.push(view);
            let attachments = [view];
            let fb = unsafe {
                d.create_framebuffer(
                    &vk::FramebufferCreateInfo::default()
                        .render_pass(self.render_pass)
                        .attachments(&attachments)
                        .width(extent.width)
                        .height(extent.height)
                        .layers(1),
                    None,
                )
            }?;
            self.framebuffers.push(fb);
        }
        Ok(())
    }

    /// Before recording a frame: encodes its vertex colours for the renderer (ui_colors.rs), uploads the
    /// textures egui changed, and remembers those it released, freed by `frame_done`. Takes everything out of
    /// `delta` (egui checks that it was applied).
    pub fn prepare(
        &mut self,
        pool: vk::CommandPool,
        delta: &mut egui::TexturesDelta,
        primitives: &mut [egui::ClippedPrimitive],
    ) -> Result<()> {
        // A UNORM swapchain takes egui's values; an `_SRGB` one encodes the renderer's linear output itself.
        let srgb_target = super::present::is_srgb_format(self.format);
        ui_colors::encode_vertices(primitives, srgb_target);
        let Some(r) = self.renderer.as_mut() else {
            delta.clear();
            return Ok(());
        };
        self.to_free.extend(delta.free.drain());
        for (id, deltas) in delta.set.drain() {
            for d in deltas {
                let d = if srgb_target {
                    d
                } else {
                    ui_colors::encode_texture(&d)
                };
                r.set_texture(self.gpu.queue, pool, id, &d)
                    .context("cannot upload an egui texture")?;
            }
        }
        Ok(())
    }

    /// The frame that last used the released textures has completed.
    pub fn frame_done(&mut self) {
        if let Some(r) = self.renderer.as_mut() {
            for id in self.to_free.drain(..) {
                if let Err(e) = r.free_texture(id) {
                    log::warn!("cannot free an egui texture: {e}");
                }
            }
        }
    }

    /// Records egui's `primitives` over swapchain image `index` (in COLOR_ATTACHMENT_OPTIMAL; it leaves in
    /// PRESENT_SRC_KHR, also when there is nothing to draw).
    pub fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        index: u32,
        pixels_per_point: f32,
        primitives: &[egui::ClippedPrimitive],
    ) -> Result<()> {
        let Some(&framebuffer) = self.framebuffers.get(index as usize) else {
            anyhow::bail!("no UI framebuffer for swapchain image {index}");
        };
        let d = &self.gpu.device;
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(self.render_pass)
            .framebuffer(framebuffer)
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent: self.extent,
            });
        unsafe { d.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE) };
        let drawn = match self.renderer.as_mut() {
            Some(r) => r.cmd_draw(cmd, self.extent, pixels_per_point, primitives),
            None => Ok(()),
        };
        unsafe { d.cmd_end_render_pass(cmd) };
        drawn.context("cannot record egui")
    }

    fn destroy_framebuffers(&mut self) {
        let d = &self.gpu.device;
        unsafe {
            for fb in self.framebuffers.drain(..) {
                d.destroy_framebuffer(fb, None);
            }
            for v in self.views.drain(..) {
                d.destroy_image_view(v, None);
            }
        }
    }

    /// Destroys everything (the device is idle). Idempotent.
    pub fn destroy(&mut self) {
        self.destroy_framebuffers();
        self.renderer = None;
        if self.render_pass != vk::RenderPass::null() {
            unsafe { self.gpu.device.destroy_render_pass(self.render_pass, None) };
            self.render_pass = vk::RenderPass::null();
        }
    }
}

impl Drop for UiLayer {
    fn drop(&mut self) {
        self.destroy();
    }
}
