//! Two frames in flight (`in_flight.rs`): the host records and submits frame N+1 before the device completes
//! frame N, and `finish_frame` reads each frame's own statistics from its slot. The validation layer, with
//! synchronization validation, sees the frames overlap on the queue.
mod common;

use ash::vk;
use common::*;
use hrtao_core::{FrameReport, Gpu};
use hrtao_scene::glam::{Quat, Vec3};

/// Command buffers and fences of its own: frames submitted without waiting, waited for oldest first.
struct Queue<'a> {
    gpu: &'a Gpu,
    pool: vk::CommandPool,
    slots: Vec<(vk::CommandBuffer, vk::Fence)>,
}

impl<'a> Queue<'a> {
    fn new(gpu: &'a Gpu) -> Queue<'a> {
        let d = &gpu.device;
        unsafe {
            let pool = d
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(gpu.queue_family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )
                .unwrap();
            let cmds = d
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(pool)
                        .command_buffer_count(2),
                )
                .unwrap();
            let slots = cmds
                .into_iter()
                .map(|c| (c, d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap()))
                .collect();
            Queue { gpu, pool, slots }
        }
    }

    fn begin(&self, slot: usize) -> vk::CommandBuffer {
        let cmd = self.slots[slot].0;
        unsafe {
            self.gpu
                .device
                .reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .unwrap();
            self.gpu
                .device
                .begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())
                .unwrap();
        }
        cmd
    }

    fn submit(&self, slot: usize) {
        let (cmd, fence) = self.slots[slot];
        unsafe {
            self.gpu.device.end_command_buffer(cmd).unwrap();
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            self.gpu
                .device
                .queue_submit(self.gpu.queue, &submit, fence)
                .unwrap();
        }
    }

    fn wait(&self, slot: usize) {
        let fence = self.slots[slot].1;
        unsafe {
            self.gpu.device.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            self.gpu.device.reset_fences(&[fence]).unwrap();
        }
    }
}

impl Drop for Queue<'_> {
    fn drop(&mut self) {
        self.gpu.wait_idle();
        unsafe {
            for &(_, fence) in &self.slots {
                self.gpu.device.destroy_fence(fence, None);
            }
            self.gpu.device.destroy_command_pool(self.pool, None);
        }
    }
}

/// The bundled scene's camera turned by `step` degrees about the vertical through its target, `i` times.
fn turned(cam: &hrtao_core::Camera, i: usize, step: f32) -> hrtao_core::Camera {
    let eye = Vec3::from(cam.eye);
    let target = Vec3::from(cam.target);
    let q = Quat::from_axis_angle(Vec3::from(cam.up), (i as f32 * step).to_radians());
    hrtao_core::Camera {
        eye: (target + q * (eye - target)).to_array(),
        ..*cam
    }
}

/// A drag of 8 frames then a still image of slices (lattice 2), each frame recorded and submitted before the
/// last one is finished: every report is its own frame's (the slices come in order, each still round's last
/// slice is the one that can end the image, and the rays each frame traced agree with the same frames rendered
/// one at a time within the frames' own spread), the final AO matches the one-at-a-time image, and the
/// validation layer (synchronization validation on) stays silent. Fails when `InFlight::free_slot` hands out
/// a slot an unfinished frame holds (the third frame is recorded instead of refused).
#[test]
fn two_frames_in_flight_report_their_own_frames_and_match_one_at_a_time() {
    let (gpu, scene, cam, sg) = on_gpu(bundled(160, 90));
    let settings = hrtao(4, scene.bounds().diagonal().length() * 0.1);
    let frames = 8 + 24;
    let frame_cam = |i: usize| turned(&cam, i.min(8), 3.0);
    let lattice = |i: usize| if i < 8 { 1 } else { 2 };

    // One at a time.
    let mut one = Headless::new(&gpu, 160, 90, settings.clone()).unwrap();
    let mut sequential: Vec<FrameReport> = Vec::new();
    for i in 0..frames {
        one.lattice = lattice(i);
        sequential.push(one.render(&sg, scene.f(), &frame_cam(i)).unwrap());
    }
    let ao_one = one.read_ao().unwrap();

    // Two in flight.
    let q = Queue::new(&gpu);
    let mut two = Headless::new(&gpu, 160, 90, settings.clone()).unwrap();
    let mut overlapped: Vec<FrameReport> = Vec::new();
    let mut in_flight: std::collections::VecDeque<usize> = Default::default();
    for i in 0..frames {
        let slot = i % 2;
        if in_flight.len() == 2 {
            let s = in_flight.pop_front().unwrap();
            q.wait(s);
            overlapped.push(two.r.finish_frame(0.0).unwrap());
        }
        two.lattice = lattice(i);
        let cmd = q.begin(slot);
        let frame = two.frame_with(&sg, scene.f(), &frame_cam(i), &settings);
        two.r.record_frame(cmd, &frame).unwrap();
        q.submit(slot);
        in_flight.push_back(slot);
        if i == 3 {
            // A third frame cannot be recorded while two are unfinished, nor a headless one rendered.
            let cmd = vk::CommandBuffer::null();
            assert!(two.r.record_frame(cmd, &frame).is_err());
            assert!(two.r.render(&frame).is_err());
        }
    }
    while let Some(s) = in_flight.pop_front() {
        q.wait(s);
        overlapped.push(two.r.finish_frame(0.0).unwrap());
    }
    let ao_two = two.read_ao().unwrap();
    drop(q);

    assert_eq!(overlapped.len(), sequential.len());
    for (i, (a, b)) in sequential.iter().zip(&overlapped).enumerate() {
        assert_eq!(
            (a.slice, a.slices),
            (b.slice, b.slices),
            "frame {i}: its own slice"
        );
        assert_eq!(a.accumulated_frames, b.accumulated_frames, "frame {i}");
        // The map's load (and so the cell finder's levels) reaches the next frame one frame later: the rays
        // differ by the frames' young cells only.
        let (ra, rb) = (a.rays as f64, b.rays as f64);
        assert!(
            (ra - rb).abs() <= 0.25 * ra.max(rb) + 64.0,
            "frame {i}: {ra} rays one at a time, {rb} in flight"
        );
    }
    let m = mae(&ao_one, &ao_two);
    assert!(m < 0.01, "AO of the two runs differs by MAE {m}");
    assert_clean(&gpu);
}
