//! Records a frame's passes into one command buffer (`Recorder::dispatch`): binds each pass, inserts the barrier
//! its declared accesses call for (`barrier::Tracker`), dispatches over pixels and times it under its Table-2
//! section. Above `pass.rs` (the declarations and pipelines) and `barrier.rs` (which reads the declarations).
//! A pass that runs as a ray-tracing pipeline (`RayBackend::Pipeline`) is launched over the threads its compute
//! dispatch would run (groups x WORKGROUP_SIZE in x and y), directly or from the queue's indirect launch size
//! (queue_args.glsl, `QUEUE_TRACE_ARGS`), its accesses made in the ray-tracing stage.
use ash::vk;

use crate::barrier::{pass_uses, Barrier, Event, Stage, Tracker, Use};
use crate::buffer::Buffer;
use crate::context::{Gpu, RayBackend};
use crate::gpu::{QUEUE_TRACE_ARGS, WORKGROUP_SIZE};
use crate::pass::{Pass, PassPipeline, PassSet, Resource};
use crate::timer::GpuTimer;

/// Records passes into one command buffer, each after the barrier its declared accesses call for.
pub struct Recorder<'a> {
    pub gpu: &'a Gpu,
    pub cmd: vk::CommandBuffer,
    passes: &'a PassSet,
    timer: Option<&'a mut GpuTimer>,
    tracker: Tracker,
}

fn record_barrier(gpu: &Gpu, cmd: vk::CommandBuffer, b: &Barrier) {
    let barrier = [vk::MemoryBarrier::default()
        .src_access_mask(b.src_access)
        .dst_access_mask(b.dst_access)];
    unsafe {
        gpu.device.cmd_pipeline_barrier(
            cmd,
            b.src_stages,
            b.dst_stages,
            vk::DependencyFlags::empty(),
            &barrier,
            &[],
            &[],
        );
    }
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
        let ray_tracing = passes.ray_backend() == RayBackend::Pipeline;
        let mut bind_points = vec![vk::PipelineBindPoint::COMPUTE];
        if ray_tracing {
            bind_points.push(vk::PipelineBindPoint::RAY_TRACING_KHR);
        }
        for bind_point in bind_points {
            unsafe {
                gpu.device
                    .cmd_bind_descriptor_sets(cmd, bind_point, passes.layout, 0, &[passes.set], &[]);
            }
        }
        Recorder {
            gpu,
            cmd,
            passes,
            timer,
            tracker: Tracker::new(ray_tracing),
        }
    }

    /// Records the barrier `uses` call for (see `barrier::Tracker`) before a command.
    fn sync(&mut self, label: &'static str, pass: Option<Pass>, indirect: bool, uses: Vec<Use>) {
        if let Some(b) = self.tracker.command(label, pass, indirect, uses) {
            record_barrier(self.gpu, self.cmd, &b);
        }
    }

    /// The stage `pass`'s shaders run in.
    fn stage(&self, pass: Pass) -> Stage {
        match self.passes.pipeline(pass) {
            PassPipeline::Compute(_) => Stage::Compute,
            PassPipeline::Ray(_) => Stage::RayTracing,
        }
    }

    /// Dispatches `pass` over a `width` x `height` grid of threads (one per pixel), with push constants `push`.
    pub fn dispatch(&mut self, pass: Pass, width: u32, height: u32, push: [u32; 4]) {
        self.sync(
            pass.shader(),
            Some(pass),
            false,
            pass_uses(pass, self.stage(pass)),
        );
        let groups = (width.div_ceil(WORKGROUP_SIZE), height.div_ceil(WORKGROUP_SIZE));
        self.record(pass, push, |d, cmd, pipeline| match pipeline {
            PassPipeline::Compute(_) => unsafe { d.cmd_dispatch(cmd, groups.0, groups.1, 1) },
            PassPipeline::Ray(rt) => rt.trace(cmd, groups.0 * WORKGROUP_SIZE, groups.1 * WORKGROUP_SIZE),
        });
    }

    /// Dispatches `pass` with the group counts at word `offset` of `args` (the `DispatchArgs` buffer:
    /// queue_args.glsl writes them), or launches it with the launch size that follows them.
    pub fn dispatch_indirect(&mut self, pass: Pass, args: &Buffer, offset: u32, push: [u32; 4]) {
        let mut uses = pass_uses(pass, self.stage(pass));
        uses.push(Use::read(Resource::DispatchArgs, Stage::Indirect));
        self.sync(pass.shader(), Some(pass), true, uses);
        let (raw, address) = (args.raw, args.address);
        self.record(pass, push, |d, cmd, pipeline| match pipeline {
            PassPipeline::Compute(_) => unsafe { d.cmd_dispatch_indirect(cmd, raw, offset as u64 * 4) },
            PassPipeline::Ray(rt) => rt.trace_indirect(cmd, address + (offset + QUEUE_TRACE_ARGS) as u64 * 4),
        });
    }

    /// Records commands that are not a compute pass (the rasterised visibility, copies) with their accesses
    /// `uses`, after the barrier they call for, timed under `section` when given.
    pub fn commands(
        &mut self,
        label: &'static str,
        section: Option<&'static str>,
        uses: Vec<Use>,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) {
        self.sync(label, None, false, uses);
        if let (Some(t), Some(section)) = (self.timer.as_deref_mut(), section) {
            t.begin(self.cmd, section);
        }
        record(&self.gpu.device, self.cmd);
        if let (Some(t), Some(_)) = (self.timer.as_deref_mut(), section) {
            t.end(self.cmd);
        }
    }

    /// Ends the recording with a barrier that makes every write visible to the host and to later copies and
    /// shaders; returns what was recorded.
    pub fn finish(mut self) -> Vec<Event> {
        if let Some(t) = self.timer.as_deref_mut() {
            t.finish(self.cmd);
        }
        let b = self.tracker.finish();
        record_barrier(self.gpu, self.cmd, &b);
        self.tracker.take_events()
    }

    /// Binds `pass`, pushes its constants and records the dispatch under its timing section.
    fn record(
        &mut self,
        pass: Pass,
        push: [u32; 4],
        dispatch: impl FnOnce(&ash::Device, vk::CommandBuffer, &PassPipeline),
    ) {
        let d = &self.gpu.device;
        if let Some(t) = self.timer.as_deref_mut() {
            t.begin(self.cmd, pass.section());
        }
        let pipeline = self.passes.pipeline(pass);
        let (bind_point, raw) = match pipeline {
            PassPipeline::Compute(p) => (vk::PipelineBindPoint::COMPUTE, *p),
            PassPipeline::Ray(rt) => (vk::PipelineBindPoint::RAY_TRACING_KHR, rt.pipeline),
        };
        unsafe {
            d.cmd_bind_pipeline(self.cmd, bind_point, raw);
            d.cmd_push_constants(
                self.cmd,
                self.passes.layout,
                self.passes.stages,
                0,
                bytemuck::cast_slice(&push),
            );
        }
        dispatch(d, self.cmd, pipeline);
        if let Some(t) = self.timer.as_deref_mut() {
            t.end(self.cmd);
        }
    }
}
