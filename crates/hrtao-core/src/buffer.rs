//! GPU buffers: each `Buffer` owns its `vk::Buffer` and its allocation and frees both on drop.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use crate::context::Gpu;
use crate::error::{CoreError, Result};

pub struct Buffer {
    gpu: Arc<Gpu>,
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
    /// Buffer device address (every buffer is addressable: the shaders reach buffers through addresses).
    pub address: u64,
    name: String,
}

impl Buffer {
    /// Its device address as two push-constant words (low, high), for a pass that gets it through its push
    /// constants (`Resource::push_type`; the shader rebuilds it with `packUint2x32`).
    pub fn address_words(&self) -> [u32; 2] {
        [self.address as u32, (self.address >> 32) as u32]
    }

    /// Creates a buffer of `size` bytes (at least 16) in `location`, usable as storage, transfer source/destination
    /// and by address, plus `extra` usages.
    pub fn new(
        gpu: &Arc<Gpu>,
        name: &str,
        size: u64,
        location: MemoryLocation,
        extra: vk::BufferUsageFlags,
    ) -> Result<Buffer> {
        let size = size.max(16);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
            | extra;
        if let Some(limit) = gpu.memory_limit {
            let used = gpu.device_bytes.load(std::sync::atomic::Ordering::Relaxed);
            if used.saturating_add(size) > limit {
                return Err(CoreError::Memory(format!(
                    "allocating {} for `{name}` would exceed the device memory limit of {} ({} in use)",
                    human_bytes(size),
                    human_bytes(limit),
                    human_bytes(used)
                )));
            }
        }
        unsafe {
            let raw = gpu
                .device
                .create_buffer(&vk::BufferCreateInfo::default().size(size).usage(usage), None)
                .map_err(|e| CoreError::from_vk("vkCreateBuffer", e))?;
            let requirements = gpu.device.get_buffer_memory_requirements(raw);
            let allocation = allocate(gpu, name, requirements, location, true);
            let allocation = match allocation {
                Ok(a) => a,
                Err(e) => {
                    gpu.device.destroy_buffer(raw, None);
                    return Err(CoreError::Memory(format!(
                        "allocating {size} bytes for `{name}`: {e}"
                    )));
                }
            };
            if let Err(e) = gpu
                .device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
            {
                let _ = gpu.allocator().free(allocation);
                gpu.device.destroy_buffer(raw, None);
                return Err(CoreError::from_vk("vkBindBufferMemory", e));
            }
            let address = gpu
                .device
                .get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(raw));
            // 64-bit atomics (the hash cells' stamps, the ray counters, the sky sums) need 8-byte aligned
            // addresses: the layouts put them at 8-byte offsets (gpu.rs `layouts_are_scalar_compatible`), and
            // the buffer's start must be aligned too.
            if !address.is_multiple_of(8) {
                let _ = gpu.allocator().free(allocation);
                gpu.device.destroy_buffer(raw, None);
                return Err(CoreError::Invalid(format!(
                    "buffer `{name}` got device address {address:#x}, not 8-byte aligned: 64-bit atomics need it"
                )));
            }
            gpu.device_bytes
                .fetch_add(allocation.size(), std::sync::atomic::Ordering::Relaxed);
            Ok(Buffer {
                gpu: gpu.clone(),
                raw,
                allocation: Some(allocation),
                size,
                address,
                name: name.into(),
            })
        }
    }

    /// A host-visible buffer initialised with `data`.
    pub fn from_slice<T: bytemuck::Pod>(
        gpu: &Arc<Gpu>,
        name: &str,
        data: &[T],
        extra: vk::BufferUsageFlags,
    ) -> Result<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut b = Buffer::new(gpu, name, bytes.len() as u64, MemoryLocation::CpuToGpu, extra)?;
        b.write_bytes(0, bytes)?;
        Ok(b)
    }

    /// A device-local buffer filled with `data` through a staging copy.
    pub fn device_local_from_slice<T: bytemuck::Pod>(
        gpu: &Arc<Gpu>,
        name: &str,
        data: &[T],
        extra: vk::BufferUsageFlags,
    ) -> Result<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let staging = Buffer::from_slice(
            gpu,
            &format!("{name} (staging)"),
            bytes,
            vk::BufferUsageFlags::empty(),
        )?;
        let b = Buffer::new(gpu, name, bytes.len() as u64, MemoryLocation::GpuOnly, extra)?;
        gpu.run_commands(|cmd| unsafe {
            let region = [vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size: bytes.len().max(1) as u64,
            }];
            if !bytes.is_empty() {
                gpu.device.cmd_copy_buffer(cmd, staging.raw, b.raw, &region);
            }
        })?;
        Ok(b)
    }

    fn mapped(&self) -> Result<&[u8]> {
        let a = self.allocation.as_ref().unwrap();
        a.mapped_slice()
            .ok_or_else(|| CoreError::Invalid(format!("buffer `{}` is not host visible", self.name)))
    }

    /// Writes bytes into a host-visible buffer at `offset`.
    pub fn write_bytes(&mut self, offset: u64, bytes: &[u8]) -> Result<()> {
        let name = self.name.clone();
        let a = self.allocation.as_mut().unwrap();
        let slice = a
            .mapped_slice_mut()
            .ok_or_else(|| CoreError::Invalid(format!("buffer `{name}` is not host visible")))?;
        let start = offset as usize;
        let end = start + bytes.len();
        if end > slice.len() {
            return Err(CoreError::Invalid(format!(
                "write of {end} bytes past the end of buffer `{name}`"
            )));
        }
        slice[start..end].copy_from_slice(bytes);
        Ok(())
    }

    pub fn write<T: bytemuck::Pod>(&mut self, data: &[T]) -> Result<()> {
        self.write_bytes(0, bytemuck::cast_slice(data))
    }

    /// Reads `count` values of a host-visible buffer.
    pub fn read<T: bytemuck::Pod>(&self, count: usize) -> Result<Vec<T>> {
        let bytes = self.mapped()?;
        let n = count * std::mem::size_of::<T>();
        if n > bytes.len() {
            return Err(CoreError::Invalid(format!(
                "read past the end of buffer `{}`",
                self.name
            )));
        }
        Ok(bytemuck::pod_collect_to_vec(&bytes[..n]))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        unsafe {
            if let Some(a) = self.allocation.take() {
                self.gpu
                    .device_bytes
                    .fetch_sub(a.size(), std::sync::atomic::Ordering::Relaxed);
                let _ = self.gpu.allocator().free(a);
            }
            self.gpu.device.destroy_buffer(self.raw, None);
        }
    }
}

/// "12.3 MiB" style sizes for messages.
pub fn human_bytes(b: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Device memory for a resource with `requirements` from the gpu-allocator, in its own-managed blocks; `linear`
/// for a buffer or a linearly tiled image.
pub fn allocate(
    gpu: &Gpu,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> std::result::Result<Allocation, gpu_allocator::AllocationError> {
    gpu.allocator().allocate(&AllocationCreateDesc {
        name,
        requirements,
        location,
        linear,
        allocation_scheme: AllocationScheme::GpuAllocatorManaged,
    })
}

/// Records a full memory barrier between shader/transfer/AS work (the passes form a simple linear chain).
pub fn full_barrier(gpu: &Gpu, cmd: vk::CommandBuffer) {
    let barrier = [crate::barrier::memory_barrier(
        vk::AccessFlags::SHADER_WRITE
            | vk::AccessFlags::TRANSFER_WRITE
            | vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR,
        vk::AccessFlags::SHADER_READ
            | vk::AccessFlags::SHADER_WRITE
            | vk::AccessFlags::TRANSFER_READ
            | vk::AccessFlags::TRANSFER_WRITE
            | vk::AccessFlags::ACCELERATION_STRUCTURE_READ_KHR
            | vk::AccessFlags::INDIRECT_COMMAND_READ,
    )];
    let stages = vk::PipelineStageFlags::COMPUTE_SHADER
        | vk::PipelineStageFlags::TRANSFER
        | vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR;
    unsafe {
        crate::barrier::record(
            &gpu.device,
            cmd,
            (stages, stages | vk::PipelineStageFlags::DRAW_INDIRECT),
            &barrier,
            &[],
        );
    }
}

/// Makes all device writes visible to the host (end of a command buffer whose results are read back).
pub fn host_read_barrier(gpu: &Gpu, cmd: vk::CommandBuffer) {
    let barrier = [crate::barrier::memory_barrier(
        vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE,
        vk::AccessFlags::HOST_READ,
    )];
    let stages = vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER;
    unsafe {
        crate::barrier::record(
            &gpu.device,
            cmd,
            (stages, vk::PipelineStageFlags::HOST),
            &barrier,
            &[],
        );
    }
}

/// The copy region of a whole single-layer colour image of `width` x `height` to or from a tightly packed buffer.
pub fn whole_image_copy(width: u32, height: u32) -> vk::BufferImageCopy {
    vk::BufferImageCopy {
        buffer_offset: 0,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: crate::barrier::COLOR_LAYERS,
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D {
            width,
            height,
            depth: 1,
        },
    }
}

/// The creation info of a single-level, single-sample 2D image of `format`, optimal tiling, starting UNDEFINED.
pub fn image_2d_info(
    format: vk::Format,
    usage: vk::ImageUsageFlags,
    (width, height): (u32, u32),
) -> vk::ImageCreateInfo<'static> {
    vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width,
            height,
            depth: 1,
        })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(usage)
        .initial_layout(vk::ImageLayout::UNDEFINED)
}

/// Records a write of `bytes` into the start of the device buffer `dst` by the command buffer itself
/// (vkCmdUpdateBuffer, in chunks of 64 KiB), ordered after every command before it (frames still in flight
/// read the old contents) and visible to every command after it: per-frame data (the frame's globals) written
/// in queue order, with no host-visible copy per frame in flight. `bytes.len()` must be a multiple of 4.
pub fn record_update(gpu: &Gpu, cmd: vk::CommandBuffer, dst: vk::Buffer, bytes: &[u8]) {
    const CHUNK: usize = 65536;
    let d = &gpu.device;
    let all = vk::PipelineStageFlags::ALL_COMMANDS;
    unsafe {
        // Reads by earlier commands (the frame before, maybe still running) come first.
        d.cmd_pipeline_barrier(
            cmd,
            all,
            vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[],
        );
        for (i, chunk) in bytes.chunks(CHUNK).enumerate() {
            d.cmd_update_buffer(cmd, dst, (i * CHUNK) as u64, chunk);
        }
        let barrier = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)];
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            all,
            vk::DependencyFlags::empty(),
            &barrier,
            &[],
            &[],
        );
    }
}
