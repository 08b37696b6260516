//! Probe rays: a handful of rays a frame asks besides its image (the viewer's walk: gravity onto the floor,
//! collision with walls), traced on the device in the frame's own command buffer by the frame's ray backend
//! (shaders/probe.comp, through trace.glsl as the AO's rays: ray queries or a ray-tracing pipeline), clipped to
//! the region the section planes keep, against the TLAS (which holds no hidden instance). Their hits come back
//! with the frame's report when the frame is finished (`FrameReport::probe_hits`): nothing waits for them.
//!
//! Each frame in flight has its own host-visible buffer (`in_flight::Slot::probes`): the host writes the rays
//! into the free slot before the frame is submitted and reads the hits once it completed.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::Result;
use crate::gpu::{ProbeHit, ProbeRay, MAX_PROBE_RAYS};
use crate::pass::{Pass, Resource};
use crate::recorder::Recorder;

/// The probe pass: the rays → their closest hits (the instance and geometry tables give the hit's normal).
pub const PROBE: Pass = Pass::new(
    "probe",
    "probes",
    &[Resource::Probes, Resource::Instances, Resource::Geometries],
    &[Resource::Probes],
);

const HIT_BYTES: u64 = std::mem::size_of::<ProbeHit>() as u64;
const RAY_BYTES: u64 = std::mem::size_of::<ProbeRay>() as u64;

/// One frame's probe buffer (`Resource::Probes`): `MAX_PROBE_RAYS` hits, then as many rays (probe.comp
/// `ProbeRef`).
pub struct ProbeBuffer {
    buffer: Buffer,
    /// Rays the frame recorded in it traces.
    count: u32,
}

impl ProbeBuffer {
    pub fn new(gpu: &Arc<Gpu>, name: &str) -> Result<ProbeBuffer> {
        let buffer = Buffer::new(
            gpu,
            name,
            MAX_PROBE_RAYS as u64 * (HIT_BYTES + RAY_BYTES),
            MemoryLocation::CpuToGpu,
            vk::BufferUsageFlags::empty(),
        )?;
        Ok(ProbeBuffer { buffer, count: 0 })
    }

    /// Writes the frame's rays (those past `MAX_PROBE_RAYS` are dropped, with a warning): the buffer's slot is
    /// free, no frame in flight reads it. Returns the probe pass's push constants ([`record`]), None when there
    /// is no ray to trace.
    pub fn write(&mut self, rays: &[ProbeRay]) -> Result<Option<[u32; 4]>> {
        if rays.len() > MAX_PROBE_RAYS as usize {
            log::warn!("{} probe rays asked, {MAX_PROBE_RAYS} traced", rays.len());
        }
        let rays = &rays[..rays.len().min(MAX_PROBE_RAYS as usize)];
        self.buffer
            .write_bytes(MAX_PROBE_RAYS as u64 * HIT_BYTES, bytemuck::cast_slice(rays))?;
        self.count = rays.len() as u32;
        let [lo, hi] = self.buffer.address_words();
        Ok((self.count > 0).then_some([lo, hi, self.count, 0]))
    }

    /// The hits of the rays the finished frame traced, in their order; then the buffer holds none.
    pub fn take_hits(&mut self) -> Result<Vec<ProbeHit>> {
        let hits = self.buffer.read(self.count as usize)?;
        self.count = 0;
        Ok(hits)
    }
}

/// Records the probe pass over the rays [`ProbeBuffer::write`] wrote (nothing when there are none).
pub fn record(rec: &mut Recorder, push: Option<[u32; 4]>) {
    if let Some(push) = push {
        rec.dispatch(PROBE, push[2], 1, push);
    }
}

impl ProbeRay {
    /// The ray from `origin` along `dir` (normalised; a zero direction traces nothing) up to `length`, tagged
    /// `tag`.
    pub fn new(origin: glam::Vec3, dir: glam::Vec3, length: f32, tag: u32) -> ProbeRay {
        let d = dir.normalize_or_zero();
        ProbeRay {
            origin: origin.to_array(),
            tmin: 0.0,
            dir: d.to_array(),
            tmax: if d == glam::Vec3::ZERO { -1.0 } else { length },
            tag,
            ..Default::default()
        }
    }
}

impl ProbeHit {
    /// The distance of the hit, or None when the ray hit nothing.
    pub fn distance(&self) -> Option<f32> {
        (self.t >= 0.0).then_some(self.t)
    }
}
