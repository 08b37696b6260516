//! Barriers derived from declared accesses: the recorder tells a `Tracker` the buffers each command reads and
//! writes (`Pass::reads`/`Pass::writes`, plus the indirect arguments, copies and raster draws), and the tracker
//! answers whether a barrier must come first, and with which stages and access masks.
//!
//! The rule: a barrier before a command that has a read-after-write, write-after-read or write-after-write
//! hazard with a command recorded since the last barrier, or that reads a buffer whose last write has not yet
//! been made visible to the stage it reads in (an indirect-argument read after a barrier that served compute
//! reads only). Every barrier includes the compute stage (and, where passes trace with ray-tracing pipelines,
//! the ray-tracing stage: `Tracker::new`) and shader reads and writes on both sides, so its dependency chains
//! with the barriers before and after it and serves every later pass.
use ash::vk;

use crate::pass::{Pass, Resource};

/// The colour aspect of a single-level, single-layer image: what the barriers of the renderer's and the viewer's
/// 2D colour images cover.
pub const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// `COLOR_RANGE` as the layers of a copy or blit.
pub const COLOR_LAYERS: vk::ImageSubresourceLayers = vk::ImageSubresourceLayers {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    mip_level: 0,
    base_array_layer: 0,
    layer_count: 1,
};

/// A layout transition of the whole colour image `image` (`COLOR_RANGE`), with no queue family transfer.
pub fn color_image_barrier(
    image: vk::Image,
    (old, new): (vk::ImageLayout, vk::ImageLayout),
    src_access: vk::AccessFlags,
    dst_access: vk::AccessFlags,
) -> vk::ImageMemoryBarrier<'static> {
    vk::ImageMemoryBarrier::default()
        .image(image)
        .old_layout(old)
        .new_layout(new)
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .subresource_range(COLOR_RANGE)
}

/// A global memory barrier: `src` accesses made available and visible to `dst` accesses.
pub fn memory_barrier(src: vk::AccessFlags, dst: vk::AccessFlags) -> vk::MemoryBarrier<'static> {
    vk::MemoryBarrier::default()
        .src_access_mask(src)
        .dst_access_mask(dst)
}

/// Records `vkCmdPipelineBarrier` from the `src` to the `dst` stages with global `memory` barriers and `images`
/// barriers (no buffer barriers).
///
/// # Safety
/// `cmd` is a command buffer of `device` in the recording state, and the images are alive.
pub unsafe fn record(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    (src, dst): (vk::PipelineStageFlags, vk::PipelineStageFlags),
    memory: &[vk::MemoryBarrier],
    images: &[vk::ImageMemoryBarrier],
) {
    device.cmd_pipeline_barrier(cmd, src, dst, vk::DependencyFlags::empty(), memory, &[], images);
}

/// Where in the pipeline a buffer is accessed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// A compute shader (every pass under ray queries; every pass that does not trace).
    Compute,
    /// A ray-tracing pipeline's shaders (a pass that traces, under `RayBackend::Pipeline`).
    RayTracing,
    /// The work-group counts of an indirect dispatch.
    Indirect,
    /// A copy command.
    Transfer,
    /// The rasterised visibility draws (vertex and fragment shaders).
    Graphics,
}

impl Stage {
    pub fn flags(self) -> vk::PipelineStageFlags {
        match self {
            Stage::Compute => vk::PipelineStageFlags::COMPUTE_SHADER,
            Stage::RayTracing => vk::PipelineStageFlags::RAY_TRACING_SHADER_KHR,
            Stage::Indirect => vk::PipelineStageFlags::DRAW_INDIRECT,
            Stage::Transfer => vk::PipelineStageFlags::TRANSFER,
            Stage::Graphics => {
                vk::PipelineStageFlags::VERTEX_SHADER
                    | vk::PipelineStageFlags::FRAGMENT_SHADER
                    | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
            }
        }
    }

    pub fn access(self, write: bool) -> vk::AccessFlags {
        match (self, write) {
            (Stage::Compute | Stage::RayTracing | Stage::Graphics, false) => vk::AccessFlags::SHADER_READ,
            (Stage::Compute | Stage::RayTracing | Stage::Graphics, true) => vk::AccessFlags::SHADER_WRITE,
            (Stage::Indirect, _) => vk::AccessFlags::INDIRECT_COMMAND_READ,
            (Stage::Transfer, false) => vk::AccessFlags::TRANSFER_READ,
            (Stage::Transfer, true) => vk::AccessFlags::TRANSFER_WRITE,
        }
    }
}

/// One declared access of a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Use {
    pub resource: Resource,
    pub write: bool,
    pub stage: Stage,
}

impl Use {
    pub fn read(resource: Resource, stage: Stage) -> Use {
        Use {
            resource,
            write: false,
            stage,
        }
    }
    pub fn write(resource: Resource, stage: Stage) -> Use {
        Use {
            resource,
            write: true,
            stage,
        }
    }
}

/// The accesses of a pass, as declared next to its definition, made in `stage` (compute, or ray tracing for a
/// pass that runs as a ray-tracing pipeline).
pub fn pass_uses(pass: Pass, stage: Stage) -> Vec<Use> {
    let reads = pass.reads().iter().map(|&r| Use::read(r, stage));
    let writes = pass.writes().iter().map(|&r| Use::write(r, stage));
    reads.chain(writes).collect()
}

/// One `vkCmdPipelineBarrier` with a global memory barrier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Barrier {
    pub src_stages: vk::PipelineStageFlags,
    pub src_access: vk::AccessFlags,
    pub dst_stages: vk::PipelineStageFlags,
    pub dst_access: vk::AccessFlags,
}

/// What a frame recorded, in order (`Renderer::last_frame_events`).
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    Barrier(Barrier),
    /// A dispatch (`pass` set) or other commands (the raster draws, the statistics copy), with its accesses.
    Command {
        label: &'static str,
        pass: Option<Pass>,
        indirect: bool,
        uses: Vec<Use>,
    },
}

/// Follows the accesses recorded since the last barrier and the stages each buffer's last write is visible to.
#[derive(Default)]
pub struct Tracker {
    /// The stages every barrier includes on both sides: compute, plus ray tracing where passes trace with
    /// ray-tracing pipelines (a stage the device must have enabled).
    always: vk::PipelineStageFlags,
    /// Accesses since the last barrier.
    pending: Vec<Use>,
    /// Per buffer written so far: the stage of its last write and the stages it has been made visible to.
    written: Vec<(Resource, Stage, vk::PipelineStageFlags)>,
    events: Vec<Event>,
}

impl Tracker {
    /// A tracker for a frame whose tracing passes run as ray-tracing pipelines (`ray_tracing`) or compute.
    pub fn new(ray_tracing: bool) -> Tracker {
        Tracker {
            always: if ray_tracing {
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::RAY_TRACING_SHADER_KHR
            } else {
                vk::PipelineStageFlags::COMPUTE_SHADER
            },
            ..Default::default()
        }
    }

    /// The stages every barrier includes (`Tracker::default()`: compute).
    fn always(&self) -> vk::PipelineStageFlags {
        self.always | vk::PipelineStageFlags::COMPUTE_SHADER
    }

    /// The barrier `uses` need before their command, if any; records the command (and the barrier).
    pub fn command(
        &mut self,
        label: &'static str,
        pass: Option<Pass>,
        indirect: bool,
        uses: Vec<Use>,
    ) -> Option<Barrier> {
        let mut hazard = false;
        let mut src_stages = self.always();
        let mut src_access = vk::AccessFlags::empty();
        for u in &uses {
            if self
                .pending
                .iter()
                .any(|p| p.resource == u.resource && (p.write || u.write))
            {
                hazard = true;
            }
            // A write made visible to other stages only (or not yet at all, if pending).
            if let Some(&(_, stage, visible)) = self.written.iter().find(|w| w.0 == u.resource) {
                if !visible.contains(u.stage.flags()) {
                    hazard = true;
                    src_stages |= stage.flags();
                    src_access |= stage.access(true);
                }
            }
        }
        let barrier = hazard.then(|| {
            for p in &self.pending {
                src_stages |= p.stage.flags();
                if p.write {
                    src_access |= p.stage.access(true);
                }
            }
            // Compute (and ray tracing) on both sides always: writes made visible here serve every later pass.
            let mut dst_stages = self.always();
            let mut dst_access = vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE;
            for u in &uses {
                dst_stages |= u.stage.flags();
                dst_access |= u.stage.access(u.write);
                if u.write {
                    // A write after a write is ordered, and its resource may be read-modified.
                    dst_access |= u.stage.access(false);
                }
            }
            let b = Barrier {
                src_stages,
                src_access,
                dst_stages,
                dst_access,
            };
            self.pending.clear();
            for w in &mut self.written {
                w.2 |= dst_stages;
            }
            self.events.push(Event::Barrier(b));
            b
        });
        for u in &uses {
            if u.write {
                match self.written.iter_mut().find(|w| w.0 == u.resource) {
                    Some(w) => *w = (u.resource, u.stage, vk::PipelineStageFlags::empty()),
                    None => self
                        .written
                        .push((u.resource, u.stage, vk::PipelineStageFlags::empty())),
                }
            }
        }
        self.pending.extend(uses.iter().copied());
        self.events.push(Event::Command {
            label,
            pass,
            indirect,
            uses,
        });
        barrier
    }

    /// The barrier at the end of the command buffer: every access before it happens before every access after
    /// it, in this submission (the viewer copies the output image) or a later one (the next frame: its first
    /// passes need no barrier of their own), and every write is visible to the host (read-backs).
    pub fn finish(&mut self) -> Barrier {
        let all_stages = self.always()
            | vk::PipelineStageFlags::TRANSFER
            | vk::PipelineStageFlags::DRAW_INDIRECT
            | Stage::Graphics.flags();
        let b = Barrier {
            src_stages: all_stages,
            src_access: vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE,
            dst_stages: all_stages | vk::PipelineStageFlags::HOST,
            dst_access: vk::AccessFlags::HOST_READ
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::INDIRECT_COMMAND_READ,
        };
        self.pending.clear();
        self.events.push(Event::Barrier(b));
        b
    }

    pub fn events(&self) -> &[Event] {
        &self.events
    }

    pub fn take_events(&mut self) -> Vec<Event> {
        std::mem::take(&mut self.events)
    }
}

/// Checks a recorded sequence: every pair of commands with a hazard on a buffer (one writes it) has a barrier
/// between them whose source stages include the earlier access's stage, and a barrier between them (the same
/// or a later one, chained through the compute stage every barrier includes) whose destination stages include
/// the later access's stage, with its access mask for a read after a write. Returns the hazards not covered,
/// each as "pass A (writes X) → pass B (reads X)".
pub fn uncovered_hazards(events: &[Event]) -> Vec<String> {
    let mut problems = Vec::new();
    let commands: Vec<(usize, &'static str, &Vec<Use>)> = events
        .iter()
        .enumerate()
        .filter_map(|(i, e)| match e {
            Event::Command { label, uses, .. } => Some((i, *label, uses)),
            Event::Barrier(_) => None,
        })
        .collect();
    for (a, &(ia, la, ua)) in commands.iter().enumerate() {
        for &(ib, lb, ub) in &commands[a + 1..] {
            for x in ua {
                for y in ub
                    .iter()
                    .filter(|y| y.resource == x.resource && (x.write || y.write))
                {
                    let between = || {
                        events[ia + 1..ib].iter().filter_map(|e| match e {
                            Event::Barrier(b) => Some(b),
                            _ => None,
                        })
                    };
                    let src = between().any(|b| b.src_stages.contains(x.stage.flags()));
                    let dst = between().any(|b| {
                        b.dst_stages.contains(y.stage.flags())
                            && (!x.write || b.dst_access.contains(y.stage.access(y.write)))
                    });
                    if !(src && dst) {
                        let verb = |w: bool| if w { "writes" } else { "reads" };
                        problems.push(format!(
                            "{la} ({} {:?}) → {lb} ({} {:?}): no barrier between them",
                            verb(x.write),
                            x.resource,
                            verb(y.write),
                            y.resource
                        ));
                    }
                }
            }
        }
    }
    problems.sort();
    problems.dedup();
    problems
}
