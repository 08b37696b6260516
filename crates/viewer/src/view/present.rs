//! The window's swapchain and the per-frame copy of the renderer's output into it: output buffer → internal
//! image (render-scale resolution) → scaled blit into the swapchain image's 3D-view rectangle → egui on top.
//! Frames in flight: each of `MAX_FRAMES_IN_FLIGHT` slots has its command buffer, its acquire semaphore and
//! its fence; the viewer waits for a frame's fence before it reuses the slot or reads the frame's results
//! (`submit`, `wait`), and every frame starts with a barrier after all work before it (`begin_frame`).
use std::sync::Arc;

use anyhow::{anyhow, bail, Context, Result};
use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;
use hrtao_core::barrier::{color_image_barrier, memory_barrier, record, COLOR_LAYERS, COLOR_RANGE};
use hrtao_core::Gpu;
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use super::ui_layer::UiLayer;

/// The most frames submitted and not yet waited for (`Prefs::frames_in_flight` chooses 1 or 2).
pub const MAX_FRAMES_IN_FLIGHT: usize = 2;

/// A frame slot's command buffer and synchronisation.
struct FrameSync {
    cmd: vk::CommandBuffer,
    /// Signalled by the acquire of the slot's swapchain image, waited by its submission.
    acquire: vk::Semaphore,
    /// Signalled when the slot's submission completes; unsignalled between `wait` and the next `submit`.
    fence: vk::Fence,
}

/// The internal (render-resolution) image the output buffer is copied into before the scaled blit.
struct Internal {
    image: vk::Image,
    allocation: Option<Allocation>,
    width: u32,
    height: u32,
}

pub struct Presenter {
    gpu: Arc<Gpu>,
    surface_loader: ash::khr::surface::Instance,
    swapchain_loader: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    swapchain: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    /// The swapchain must be recreated before the next frame (resize, out of date, suboptimal).
    pub dirty: bool,
    /// Swapchain images support blits (else the output is copied 1:1 and the render scale is forced to 1).
    pub blit_ok: bool,
    pub linear_filter: bool,
    pub readback_ok: bool,
    render_done: Vec<vk::Semaphore>,
    /// One per frame in flight, used in turn.
    slots: Vec<FrameSync>,
    /// The slot of the frame being drawn.
    current: usize,
    pub pool: vk::CommandPool,
    internal: Option<Internal>,
    /// egui over the view, with a framebuffer per swapchain image.
    pub ui: UiLayer,
}

impl Presenter {
    /// A view rectangle (x, y, width, height in pixels) clamped to the swapchain's extent, at least 1×1.
    pub fn clamp(&self, mut rect: [i32; 4]) -> [i32; 4] {
        let ext = self.extent;
        rect[0] = rect[0].clamp(0, ext.width as i32 - 1);
        rect[1] = rect[1].clamp(0, ext.height as i32 - 1);
        rect[2] = rect[2].clamp(1, ext.width as i32 - rect[0]);
        rect[3] = rect[3].clamp(1, ext.height as i32 - rect[1]);
        rect
    }

    pub fn new(gpu: &Arc<Gpu>, window: &winit::window::Window) -> Result<Presenter> {
        let display = window
            .display_handle()
            .context("the window has no display handle")?
            .as_raw();
        let handle = window
            .window_handle()
            .context("the window has no handle")?
            .as_raw();
        unsafe {
            let surface = ash_window::create_surface(&gpu.entry, &gpu.instance, display, handle, None)
                .context("cannot create the window surface")?;
            let surface_loader = ash::khr::surface::Instance::new(&gpu.entry, &gpu.instance);
            let supported = surface_loader
                .get_physical_device_surface_support(gpu.physical, gpu.queue_family, surface)
                .unwrap_or(false);
            if !supported {
                surface_loader.destroy_surface(surface, None);
                bail!("the device's queue cannot present to this window");
            }
            let format = match surface_format(&surface_loader, gpu.physical, surface) {
                Ok(f) => f.format,
                Err(e) => {
                    surface_loader.destroy_surface(surface, None);
                    return Err(e);
                }
            };
            let ui = match UiLayer::new(gpu, format) {
                Ok(ui) => ui,
                Err(e) => {
                    surface_loader.destroy_surface(surface, None);
                    return Err(e);
                }
            };
            let swapchain_loader = ash::khr::swapchain::Device::new(&gpu.instance, &gpu.device);
            let pool = gpu.device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(gpu.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )?;
            let cmds = gpu.device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .command_buffer_count(MAX_FRAMES_IN_FLIGHT as u32),
            )?;
            let mut slots = Vec::new();
            for cmd in cmds {
                let acquire = gpu
                    .device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
                let fence = gpu.device.create_fence(&vk::FenceCreateInfo::default(), None)?;
                slots.push(FrameSync { cmd, acquire, fence });
            }
            Ok(Presenter {
                gpu: gpu.clone(),
                surface_loader,
                swapchain_loader,
                surface,
                swapchain: vk::SwapchainKHR::null(),
                images: Vec::new(),
                format: vk::Format::UNDEFINED,
                extent: vk::Extent2D::default(),
                dirty: true,
                blit_ok: false,
                linear_filter: false,
                readback_ok: false,
                render_done: Vec::new(),
                slots,
                current: 0,
                pool,
                internal: None,
                ui,
            })
        }
    }

    /// (Re)creates the swapchain for a window of `width`×`height`. Returns false when the surface has a zero
    /// extent (minimised): nothing can be presented then.
    pub fn recreate(&mut self, width: u32, height: u32) -> Result<bool> {
        let gpu = self.gpu.clone();
        unsafe {
            gpu.wait_idle();
            let caps = self
                .surface_loader
                .get_physical_device_surface_capabilities(gpu.physical, self.surface)?;
            let extent = if caps.current_extent.width != u32::MAX {
                caps.current_extent
            } else {
                vk::Extent2D {
                    width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                    height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
                }
            };
            if extent.width == 0 || extent.height == 0 {
                return Ok(false);
            }
            let chosen = surface_format(&self.surface_loader, gpu.physical, self.surface)?;
            let props = gpu
                .instance
                .get_physical_device_format_properties(gpu.physical, chosen.format);
            let feats = props.optimal_tiling_features;
            let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_DST;
            self.readback_ok = caps
                .supported_usage_flags
                .contains(vk::ImageUsageFlags::TRANSFER_SRC);
            if self.readback_ok {
                usage |= vk::ImageUsageFlags::TRANSFER_SRC;
            }
            if !caps
                .supported_usage_flags
                .contains(vk::ImageUsageFlags::TRANSFER_DST)
            {
                bail!("the surface does not support transfer destinations");
            }
            if self.format != chosen.format {
                // The internal image's format follows the swapchain's.
                self.destroy_internal();
            }
            self.format = chosen.format;
            self.blit_ok = feats.contains(vk::FormatFeatureFlags::BLIT_DST);
            if !self.blit_ok && !is_copy_format(chosen.format) {
                bail!(
                    "the swapchain's format {:?} takes neither blits nor 8-bit copies",
                    chosen.format
                );
            }
            let rgba_props = gpu
                .instance
                .get_physical_device_format_properties(gpu.physical, self.internal_format());
            self.linear_filter = rgba_props
                .optimal_tiling_features
                .contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
            let modes = self
                .surface_loader
                .get_physical_device_surface_present_modes(gpu.physical, self.surface)?;
            let mode = [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::FIFO]
                .into_iter()
                .find(|m| modes.contains(m))
                .unwrap_or(vk::PresentModeKHR::FIFO);
            let mut count = caps.min_image_count + 1;
            if caps.max_image_count != 0 {
                count = count.min(caps.max_image_count);
            }
            let old = self.swapchain;
            let info = vk::SwapchainCreateInfoKHR::default()
                .surface(self.surface)
                .min_image_count(count)
                .image_format(chosen.format)
                .image_color_space(chosen.color_space)
                .image_extent(extent)
                .image_array_layers(1)
                .image_usage(usage)
                .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
                .pre_transform(caps.current_transform)
                .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
                .present_mode(mode)
                .clipped(true)
                .old_swapchain(old);
            let swapchain = self.swapchain_loader.create_swapchain(&info, None)?;
            if old != vk::SwapchainKHR::null() {
                self.swapchain_loader.destroy_swapchain(old, None);
            }
            self.swapchain = swapchain;
            self.images = self.swapchain_loader.get_swapchain_images(swapchain)?;
            self.format = chosen.format;
            self.extent = extent;
            self.ui.resize(&self.images, self.format, extent)?;
            for s in self.render_done.drain(..) {
                gpu.device.destroy_semaphore(s, None);
            }
            for _ in 0..self.images.len() {
                self.render_done.push(
                    gpu.device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?,
                );
            }
            self.dirty = false;
            log::debug!(
                "swapchain {}x{} {:?}, {} images, {mode:?}, blit {}",
                extent.width,
                extent.height,
                chosen.format,
                self.images.len(),
                self.blit_ok
            );
            Ok(true)
        }
    }

    /// True when the swapchain stores blue first (the renderer can write BGRA directly for 1:1 copies).
    /// The internal image's format: the composite's bytes, read by the blit as the swapchain reads its own (an
    /// `_SRGB` swapchain gets an `_SRGB` image, so the blit decodes and encodes again: the values pass unchanged).
    fn internal_format(&self) -> vk::Format {
        if is_srgb_format(self.format) {
            vk::Format::R8G8B8A8_SRGB
        } else {
            vk::Format::R8G8B8A8_UNORM
        }
    }

    pub fn is_bgra(&self) -> bool {
        matches!(
            self.format,
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
        )
    }

    /// Acquires the next image; None when the swapchain is out of date (marked dirty).
    pub fn acquire(&mut self) -> Result<Option<u32>> {
        unsafe {
            match self.swapchain_loader.acquire_next_image(
                self.swapchain,
                u64::MAX,
                self.slots[self.current].acquire,
                vk::Fence::null(),
            ) {
                Ok((i, suboptimal)) => {
                    if suboptimal {
                        self.dirty = true;
                    }
                    Ok(Some(i))
                }
                Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                    self.dirty = true;
                    Ok(None)
                }
                Err(e) => Err(anyhow!("vkAcquireNextImageKHR: {e}")),
            }
        }
    }

    /// Makes sure the internal image holds the renderer's size.
    pub fn ensure_internal(&mut self, width: u32, height: u32) -> Result<()> {
        // Kept while it holds the frame (copied to and blitted from its top-left corner): the switches between
        // the moving scale and the still image's full size allocate nothing.
        let (width, height) = match &self.internal {
            Some(i) if i.width >= width && i.height >= height => return Ok(()),
            Some(i) => (i.width.max(width), i.height.max(height)),
            None => (width, height),
        };
        self.destroy_internal();
        let gpu = self.gpu.clone();
        unsafe {
            let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC;
            let info = hrtao_core::buffer::image_2d_info(self.internal_format(), usage, (width, height));
            let image = gpu.device.create_image(&info, None)?;
            let requirements = gpu.device.get_image_memory_requirements(image);
            let name = "viewer internal image";
            let allocation =
                hrtao_core::buffer::allocate(&gpu, name, requirements, MemoryLocation::GpuOnly, false);
            let allocation = match allocation {
                Ok(a) => a,
                Err(e) => {
                    gpu.device.destroy_image(image, None);
                    bail!("allocating the internal image: {e}");
                }
            };
            gpu.device
                .bind_image_memory(image, allocation.memory(), allocation.offset())?;
            self.internal = Some(Internal {
                image,
                allocation: Some(allocation),
                width,
                height,
            });
        }
        Ok(())
    }

    fn destroy_internal(&mut self) {
        if let Some(mut i) = self.internal.take() {
            unsafe {
                self.gpu.wait_idle();
                self.gpu.device.destroy_image(i.image, None);
            }
            if let Some(a) = i.allocation.take() {
                let _ = self.gpu.allocator().free(a);
            }
        }
    }

    /// Records: output buffer → internal image → blit into `dst` (x, y, w, h) of swapchain image `index`,
    /// cleared to `clear` first; leaves the image in COLOR_ATTACHMENT_OPTIMAL for egui. `src` is None when there
    /// is nothing to show yet (loading).
    pub fn record_view(
        &self,
        cmd: vk::CommandBuffer,
        index: u32,
        src: Option<(vk::Buffer, u32, u32)>,
        dst: [i32; 4],
        clear: [f32; 4],
    ) {
        let d = &self.gpu.device;
        let target = self.images[index as usize];
        let layers = COLOR_LAYERS;
        let transfer = (vk::PipelineStageFlags::TRANSFER, vk::PipelineStageFlags::TRANSFER);
        let to_transfer_dst = (vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        unsafe {
            // The renderer's compute writes → transfer reads of the output buffer.
            let mem = [memory_barrier(
                vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE,
                vk::AccessFlags::TRANSFER_READ | vk::AccessFlags::TRANSFER_WRITE,
            )];
            let mut images = vec![color_image_barrier(
                target,
                to_transfer_dst,
                vk::AccessFlags::empty(),
                vk::AccessFlags::TRANSFER_WRITE,
            )];
            let internal = self.internal.as_ref().filter(|_| self.blit_ok);
            if let (Some(_), Some(i)) = (src, internal) {
                images.push(color_image_barrier(
                    i.image,
                    to_transfer_dst,
                    vk::AccessFlags::TRANSFER_READ,
                    vk::AccessFlags::TRANSFER_WRITE,
                ));
            }
            let after_compute = vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER;
            record(
                d,
                cmd,
                (after_compute, vk::PipelineStageFlags::TRANSFER),
                &mem,
                &images,
            );
            let color = vk::ClearColorValue { float32: clear };
            d.cmd_clear_color_image(
                cmd,
                target,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &color,
                &[COLOR_RANGE],
            );
            let after_clear = [memory_barrier(
                vk::AccessFlags::TRANSFER_WRITE,
                vk::AccessFlags::TRANSFER_WRITE | vk::AccessFlags::TRANSFER_READ,
            )];
            record(d, cmd, transfer, &after_clear, &[]);
            if let Some((buffer, w, h)) = src {
                let copy = || vk::BufferImageCopy {
                    buffer_offset: 0,
                    buffer_row_length: 0,
                    buffer_image_height: 0,
                    image_subresource: layers,
                    image_offset: vk::Offset3D::default(),
                    image_extent: vk::Extent3D {
                        width: w,
                        height: h,
                        depth: 1,
                    },
                };
                match internal {
                    Some(i) => {
                        d.cmd_copy_buffer_to_image(
                            cmd,
                            buffer,
                            i.image,
                            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                            &[copy()],
                        );
                        let b = [color_image_barrier(
                            i.image,
                            (
                                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                            ),
                            vk::AccessFlags::TRANSFER_WRITE,
                            vk::AccessFlags::TRANSFER_READ,
                        )];
                        record(d, cmd, transfer, &[], &b);
                        let blit = vk::ImageBlit {
                            src_subresource: layers,
                            src_offsets: [
                                vk::Offset3D::default(),
                                vk::Offset3D {
                                    x: w as i32,
                                    y: h as i32,
                                    z: 1,
                                },
                            ],
                            dst_subresource: layers,
                            dst_offsets: [
                                vk::Offset3D {
                                    x: dst[0],
                                    y: dst[1],
                                    z: 0,
                                },
                                vk::Offset3D {
                                    x: dst[0] + dst[2],
                                    y: dst[1] + dst[3],
                                    z: 1,
                                },
                            ],
                        };
                        let filter = if self.linear_filter {
                            vk::Filter::LINEAR
                        } else {
                            vk::Filter::NEAREST
                        };
                        d.cmd_blit_image(
                            cmd,
                            i.image,
                            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                            target,
                            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                            &[blit],
                            filter,
                        );
                    }
                    None => {
                        // 1:1 copy (no blit support): the renderer wrote the swapchain's channel order.
                        let mut c = copy();
                        c.image_offset = vk::Offset3D {
                            x: dst[0],
                            y: dst[1],
                            z: 0,
                        };
                        c.image_extent.width = w.min(self.extent.width.saturating_sub(dst[0] as u32));
                        c.image_extent.height = h.min(self.extent.height.saturating_sub(dst[1] as u32));
                        c.buffer_row_length = w;
                        if c.image_extent.width > 0 && c.image_extent.height > 0 {
                            d.cmd_copy_buffer_to_image(
                                cmd,
                                buffer,
                                target,
                                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                                &[c],
                            );
                        }
                    }
                }
            }
            let b = [color_image_barrier(
                target,
                (
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                ),
                vk::AccessFlags::TRANSFER_WRITE,
                vk::AccessFlags::COLOR_ATTACHMENT_READ | vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            )];
            let to_egui = (
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            );
            record(d, cmd, to_egui, &[], &b);
        }
    }

    /// Records a copy of the presented image (after egui, in PRESENT_SRC) into `buffer` (tightly packed).
    pub fn record_readback(&self, cmd: vk::CommandBuffer, index: u32, buffer: vk::Buffer) {
        let d = &self.gpu.device;
        let image = self.images[index as usize];
        let present_to_copy = (
            vk::ImageLayout::PRESENT_SRC_KHR,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        );
        unsafe {
            let b = [color_image_barrier(
                image,
                present_to_copy,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                vk::AccessFlags::TRANSFER_READ,
            )];
            let stages = (
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::PipelineStageFlags::TRANSFER,
            );
            record(d, cmd, stages, &[], &b);
            d.cmd_copy_image_to_buffer(
                cmd,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer,
                &[hrtao_core::buffer::whole_image_copy(
                    self.extent.width,
                    self.extent.height,
                )],
            );
            let (old, new) = present_to_copy;
            let b = [color_image_barrier(
                image,
                (new, old),
                vk::AccessFlags::empty(),
                vk::AccessFlags::empty(),
            )];
            let stages = (
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
            );
            record(d, cmd, stages, &[], &b);
            hrtao_core::buffer::host_read_barrier(&self.gpu, cmd);
        }
    }

    /// The command buffer of the frame being drawn, reset and begun, its first command a barrier after all
    /// work submitted before it (frames still in flight write the images and buffers this one reuses).
    pub fn begin_frame(&mut self) -> Result<vk::CommandBuffer> {
        let cmd = self.slots[self.current].cmd;
        let d = &self.gpu.device;
        unsafe {
            d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())?;
            let info =
                vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            d.begin_command_buffer(cmd, &info)?;
            let barrier = [memory_barrier(
                vk::AccessFlags::MEMORY_WRITE,
                vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE,
            )];
            let all = vk::PipelineStageFlags::ALL_COMMANDS;
            record(d, cmd, (all, all), &barrier, &[]);
        }
        Ok(cmd)
    }

    /// Submits the frame being drawn (waiting for its acquired image; `present` shows image `index` next) and
    /// moves to the next slot. Returns the submitted slot, for `wait`. The next slot must have been waited for.
    pub fn submit(&mut self, index: u32) -> Result<usize> {
        let d = &self.gpu.device;
        let slot = self.current;
        let f = &self.slots[slot];
        unsafe {
            let waits = [f.acquire];
            let stages = [vk::PipelineStageFlags::TRANSFER];
            let signals = [self.render_done[index as usize]];
            let cmds = [f.cmd];
            let submit = [vk::SubmitInfo::default()
                .wait_semaphores(&waits)
                .wait_dst_stage_mask(&stages)
                .command_buffers(&cmds)
                .signal_semaphores(&signals)];
            d.queue_submit(self.gpu.queue, &submit, f.fence)
                .map_err(|e| anyhow!("vkQueueSubmit: {e}"))?;
        }
        self.current = (self.current + 1) % self.slots.len();
        Ok(slot)
    }

    /// Whether the frame submitted from `slot` has completed (without waiting).
    pub fn done(&self, slot: usize) -> bool {
        unsafe { self.gpu.device.get_fence_status(self.slots[slot].fence) }.unwrap_or(false)
    }

    /// Waits for the frame submitted from `slot` to complete (its results may be read, its slot reused).
    pub fn wait(&mut self, slot: usize) -> Result<()> {
        let d = &self.gpu.device;
        let fence = self.slots[slot].fence;
        unsafe {
            d.wait_for_fences(&[fence], true, 600_000_000_000)
                .map_err(|e| anyhow!("vkWaitForFences: {e}"))?;
            d.reset_fences(&[fence])?;
        }
        Ok(())
    }

    /// Presents image `index` once the frame submitted by `submit_and_wait` signals its semaphore.
    pub fn present(&mut self, index: u32) -> Result<()> {
        unsafe {
            let signals = [self.render_done[index as usize]];
            let swapchains = [self.swapchain];
            let indices = [index];
            let present = vk::PresentInfoKHR::default()
                .wait_semaphores(&signals)
                .swapchains(&swapchains)
                .image_indices(&indices);
            match self.swapchain_loader.queue_present(self.gpu.queue, &present) {
                Ok(false) => {}
                Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.dirty = true,
                Err(e) => bail!("vkQueuePresentKHR: {e}"),
            }
        }
        Ok(())
    }

    /// Destroys the swapchain and surface (before the window goes away).
    pub fn destroy(&mut self) {
        let gpu = self.gpu.clone();
        gpu.wait_idle();
        self.destroy_internal();
        self.ui.destroy();
        unsafe {
            for s in self.render_done.drain(..) {
                gpu.device.destroy_semaphore(s, None);
            }
            if self.swapchain != vk::SwapchainKHR::null() {
                self.swapchain_loader.destroy_swapchain(self.swapchain, None);
                self.swapchain = vk::SwapchainKHR::null();
            }
            if self.surface != vk::SurfaceKHR::null() {
                self.surface_loader.destroy_surface(self.surface, None);
                self.surface = vk::SurfaceKHR::null();
            }
            for f in self.slots.drain(..) {
                gpu.device.destroy_semaphore(f.acquire, None);
                gpu.device.destroy_fence(f.fence, None);
            }
            if self.pool != vk::CommandPool::null() {
                gpu.device.destroy_command_pool(self.pool, None);
                self.pool = vk::CommandPool::null();
            }
        }
    }
}

/// The swapchain's format, by [`choose_surface_format`] over what the surface offers (`HRTAO_SWAPCHAIN_FORMAT`
/// = `unorm` or `srgb` keeps only that kind, for tests of both paths).
fn surface_format(
    loader: &ash::khr::surface::Instance,
    physical: vk::PhysicalDevice,
    surface: vk::SurfaceKHR,
) -> Result<vk::SurfaceFormatKHR> {
    let mut formats = unsafe { loader.get_physical_device_surface_formats(physical, surface)? };
    match std::env::var("HRTAO_SWAPCHAIN_FORMAT").as_deref() {
        Ok("srgb") => formats.retain(|f| is_srgb_format(f.format)),
        Ok("unorm") => formats.retain(|f| !is_srgb_format(f.format)),
        _ => {}
    }
    let chosen = choose_surface_format(&formats).ok_or_else(|| anyhow!("the surface reports no formats"))?;
    if chosen.color_space != vk::ColorSpaceKHR::SRGB_NONLINEAR || !is_copy_format(chosen.format) {
        log::info!("swapchain format {:?} in {:?}", chosen.format, chosen.color_space);
    }
    Ok(chosen)
}

/// The swapchain format for the composite's sRGB-encoded 8-bit colours, from the formats a surface offers. In
/// the sRGB colour space: an 8-bit UNORM format first (it stores the composite's bytes as they are); then an
/// 8-bit `_SRGB` one, written as such (the view's internal image is `_SRGB` too, so the blit decodes and
/// encodes again, and egui draws in linear light); then any other UNORM format (10 bits: the blit converts the
/// values); only then whatever the surface lists first. None when it offers nothing.
pub fn choose_surface_format(offered: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let srgb_space = |f: &&vk::SurfaceFormatKHR| f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR;
    let rules: [&dyn Fn(vk::Format) -> bool; 3] = [
        &|f| is_copy_format(f) && !is_srgb_format(f),
        &|f| is_copy_format(f) && is_srgb_format(f),
        &|f| is_unorm_format(f),
    ];
    rules
        .iter()
        .find_map(|rule| offered.iter().filter(srgb_space).find(|f| rule(f.format)))
        .or(offered.first())
        .copied()
}

/// 8-bit RGBA or BGRA: the renderer's bytes can be copied into it 1:1 (no blit).
pub fn is_copy_format(f: vk::Format) -> bool {
    matches!(
        f,
        vk::Format::B8G8R8A8_UNORM
            | vk::Format::R8G8B8A8_UNORM
            | vk::Format::B8G8R8A8_SRGB
            | vk::Format::R8G8B8A8_SRGB
    )
}

/// The device encodes what is written to it (and decodes what is read) by the sRGB curve.
pub fn is_srgb_format(f: vk::Format) -> bool {
    matches!(
        f,
        vk::Format::B8G8R8A8_SRGB
            | vk::Format::R8G8B8A8_SRGB
            | vk::Format::A8B8G8R8_SRGB_PACK32
            | vk::Format::R8G8B8_SRGB
            | vk::Format::B8G8R8_SRGB
    )
}

/// Unsigned normalised colour formats a blit writes values into.
fn is_unorm_format(f: vk::Format) -> bool {
    matches!(
        f,
        vk::Format::B8G8R8A8_UNORM
            | vk::Format::R8G8B8A8_UNORM
            | vk::Format::A8B8G8R8_UNORM_PACK32
            | vk::Format::A2B10G10R10_UNORM_PACK32
            | vk::Format::A2R10G10B10_UNORM_PACK32
            | vk::Format::R16G16B16A16_UNORM
            | vk::Format::R5G6B5_UNORM_PACK16
    )
}

impl Drop for Presenter {
    fn drop(&mut self) {
        self.destroy();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vk::ColorSpaceKHR as Cs;
    use vk::Format as F;

    fn offered(list: &[(F, Cs)]) -> Vec<vk::SurfaceFormatKHR> {
        list.iter()
            .map(|&(format, color_space)| vk::SurfaceFormatKHR { format, color_space })
            .collect()
    }

    fn chosen(list: &[(F, Cs)]) -> Option<(F, Cs)> {
        choose_surface_format(&offered(list)).map(|f| (f.format, f.color_space))
    }

    const SRGB: Cs = Cs::SRGB_NONLINEAR;

    /// The rule over offered lists: 8-bit UNORM wherever it is listed, an `_SRGB` one written as such, a 10-bit
    /// UNORM one, formats outside the sRGB colour space last, the first offered when nothing fits.
    #[test]
    fn the_swapchain_format_follows_the_rule() {
        // An `_SRGB` format first (Mesa, NVIDIA on X11): the UNORM one after it is taken.
        assert_eq!(
            chosen(&[(F::B8G8R8A8_SRGB, SRGB), (F::B8G8R8A8_UNORM, SRGB)]),
            Some((F::B8G8R8A8_UNORM, SRGB))
        );
        // Only `_SRGB`: taken, written as such.
        assert_eq!(
            chosen(&[(F::B8G8R8A8_SRGB, SRGB)]),
            Some((F::B8G8R8A8_SRGB, SRGB))
        );
        // 10-bit only: a UNORM format the blit converts into, before an HDR one listed first.
        assert_eq!(
            chosen(&[
                (F::R16G16B16A16_SFLOAT, Cs::EXTENDED_SRGB_LINEAR_EXT),
                (F::A2B10G10R10_UNORM_PACK32, SRGB)
            ]),
            Some((F::A2B10G10R10_UNORM_PACK32, SRGB))
        );
        // 8-bit `_SRGB` before 10-bit UNORM; UNORM in another colour space after both.
        assert_eq!(
            chosen(&[
                (F::B8G8R8A8_UNORM, Cs::DISPLAY_P3_NONLINEAR_EXT),
                (F::A2R10G10B10_UNORM_PACK32, SRGB),
                (F::R8G8B8A8_SRGB, SRGB)
            ]),
            Some((F::R8G8B8A8_SRGB, SRGB))
        );
        // Nothing fits: the first offered; nothing offered: none.
        assert_eq!(
            chosen(&[(F::R16G16B16A16_SFLOAT, Cs::EXTENDED_SRGB_LINEAR_EXT)]),
            Some((F::R16G16B16A16_SFLOAT, Cs::EXTENDED_SRGB_LINEAR_EXT))
        );
        assert_eq!(chosen(&[]), None);
    }
}
