//! The frame: per-resolution targets, the world-space hash map (owned by `hash_map.rs`), and the pass sequence
//! primary visibility → (per-pixel RTAO | cell finder → ray-tracing update → per-pixel AO → filter) → composite.
use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::accel::SceneGpu;
use crate::additions;
use crate::barrier::{Event, Stage, Use};
use crate::buffer::{host_read_barrier, record_update, Buffer};
use crate::camera::{Camera, Projection};
use crate::context::Gpu;
use crate::dispatch_plan;
use crate::error::{CoreError, Result};
use crate::frame::{Change, FrameDesc, FrameKey, MapChange};
use crate::gpu::{
    self, FilterGuide, FrameGlobals, FrameStats, GPixel, HashCell, HashTestCase, PixelAccum, PixelCells,
    PixelRays,
};
use crate::hash_map::WorldHashMap;
use crate::in_flight::{InFlight, Recorded};
use crate::pass::{Pass, PassSet, Resource};
use crate::raster::{Primary, Rasterizer};
use crate::recorder::Recorder;
use crate::settings::{AoSettings, Mode};
use crate::sky::SkyLight;
use crate::slice_order;

/// Buffers whose size follows the image resolution.
struct Targets {
    width: u32,
    height: u32,
    /// Pixels the buffers hold: a smaller frame reuses them (indexed y · width + x from the start), so the
    /// viewer's switches between the moving scale and the still image's full size allocate nothing.
    capacity: u64,
    gbuffer: Buffer,
    ao: Buffer,
    lod_used: Buffer,
    filter_plan: Buffer,
    filter_guide: Buffer,
    filter_tmp: Buffer,
    pixel_rays: Buffer,
    accum: Buffer,
    bias_evidence: Buffer,
    output: Buffer,
    pixel_cells: Buffer,
    ray_queue: Buffer,
    filter_queue: Buffer,
    /// Our additions' own buffers (`crate::additions`).
    additions: additions::Targets,
    slice_prior: Buffer,
}

impl Targets {
    fn new(gpu: &Arc<Gpu>, width: u32, height: u32) -> Result<Targets> {
        let n = width as u64 * height as u64;
        let b = |name: &str, bytes: u64| {
            Buffer::new(
                gpu,
                name,
                bytes,
                MemoryLocation::GpuOnly,
                vk::BufferUsageFlags::empty(),
            )
        };
        Ok(Targets {
            width,
            height,
            capacity: n,
            gbuffer: b("G-buffer", n * std::mem::size_of::<GPixel>() as u64)?,
            ao: b("AO", n * 4)?,
            lod_used: b("LOD used", n * 4)?,
            filter_plan: b("filter plan", n * 4)?,
            filter_guide: b("filter guide", n * std::mem::size_of::<FilterGuide>() as u64)?,
            filter_tmp: b("filter ping-pong", n * 4)?,
            pixel_rays: b("pixel rays", n * std::mem::size_of::<PixelRays>() as u64)?,
            accum: b("still accumulation", n * std::mem::size_of::<PixelAccum>() as u64)?,
            bias_evidence: b("still refinement slots", 3 * n * 16)?,
            output: b("output RGBA8", n * 4)?,
            pixel_cells: b("pixel cells", n * std::mem::size_of::<PixelCells>() as u64)?,
            ray_queue: b("ray queue", n * 4)?,
            filter_queue: b("filter queue", n * 4)?,
            additions: additions::Targets::new(gpu, n)?,
            slice_prior: b("slice prior", n * std::mem::size_of::<gpu::SlicePrior>() as u64)?,
        })
    }
}

/// Scenes drawing more instanced triangles than this keep ray queries without a raster trial in
/// `Renderer::pick_primary`: rasterising costs in proportion to the triangles (hundreds of millions in massive
/// instanced scenes), while ray queries scale with the pixels.
pub const RASTER_TRIAL_TRIANGLES: u64 = 20_000_000;

/// The side of `Renderer::warm_up`'s image (pixels).
const WARM_UP_SIZE: u32 = 32;

/// Feature-edge line width in view pixels: lines keep it at any internal resolution (render scale, screenshots
/// larger than the view).
pub const EDGE_WIDTH: f32 = 1.0;

/// Still frames with jitter before an image counts as anti-aliased.
pub const AA_FRAMES: u32 = 8;

/// The own rays per pixel a still image in slices holds its preview for (`Renderer::level_spacing`): those of
/// its first two rounds at the rays per visit that complete its own rays with its anti-aliasing (16 at the
/// defaults). With fewer, the rounds after the held ones showed grain: the bundled scene at 4 rays per visit
/// and two held rounds, 1.40x the final image's roughness (1.08x at 8).
pub fn held_own_rays(still_samples: u32) -> u32 {
    2 * still_samples.div_ceil(AA_FRAMES).max(1)
}

/// A still image's frame: its round (`still_index`), slice within the round and lattice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SlicePosition {
    still_index: u32,
    slice: u32,
    lattice: u32,
}

/// What one frame did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct FrameReport {
    /// GPU milliseconds per section (Table 2 names); empty when the device has no timestamps or they do not
    /// measure the passes (`Renderer::timestamps_measure`).
    pub gpu_ms: Vec<(String, f64)>,
    /// The sum of `gpu_ms` (0 when it is empty).
    pub gpu_total_ms: f64,
    pub wall_ms: f64,
    pub rays: u64,
    pub cells_inserted: u32,
    pub failed_inserts: u32,
    pub longest_probe: u32,
    pub reclaimed: u32,
    pub bounds_violations: u32,
    /// Values found non-finite (NaN, infinite) and replaced before they entered the map or the accumulation
    /// (`gpu::STAT_NON_FINITE`): 0 on a sound device.
    pub non_finite: u32,
    pub capped_pixels: u32,
    pub occupied_cells: u32,
    pub load_factor: f64,
    /// F the frame hashed with (eq. 6): the scene's, plus its section plane changes (`Renderer::effective_f`).
    pub scene_f: u32,
    /// The F cells were keyed with this frame: the scene's after a global edit, plus the settings changes that
    /// invalidated the whole map (`AoSettings::invalidates`); local edits leave it.
    pub map_f: u32,
    /// Frames accumulated for the current view (1 = a new view).
    pub accumulated_frames: u32,
    /// Rays of the still-camera refinement (included in `rays`).
    pub refine_rays: u64,
    /// Rays the target cells took (see `RAYS_CELL`).
    pub cell_rays: u64,
    /// Pixels queued for rays (`STAT_RAY_QUEUE`) and for the filter (`STAT_FILTER_QUEUE`).
    pub ray_pixels: u32,
    pub filtered_pixels: u32,
    /// The image of this view is final: rendering more frames would not change it (see `Renderer::converged`).
    pub converged: bool,
    /// Slices (`FrameDesc::lattice`): this frame drew slice `slice` of `slices` (0 of 1: a whole frame); a
    /// still image's round ends with the last.
    pub slice: u32,
    pub slices: u32,
    /// The hits of the frame's probe rays (`FrameDesc::probes`), in their order.
    #[serde(skip)]
    pub probe_hits: Vec<crate::gpu::ProbeHit>,
}

/// A frame of the held rounds that shows the grid over the whole image (`Renderer::level_spacing`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct LevelShow {
    /// Every pixel has this view's G-buffer: the feature edges are drawn over the grid.
    edges: bool,
}

pub struct Renderer {
    gpu: Arc<Gpu>,
    passes: PassSet,
    /// The frame's `FrameGlobals`, in device memory: written by each frame's own commands (`record_update`).
    globals: Buffer,
    /// `FrameStats` in device memory (the shaders' atomics stay on the GPU); each frame copies it at its end
    /// into the host-visible buffer of its slot (`in_flight`), with its timestamps.
    stats: Buffer,
    /// Frames recorded and not finished, and each one's readback and timer.
    in_flight: InFlight,
    /// VkDispatchIndirectCommands of the ray-tracing update and the filter, written by the last work group of the
    /// cell finder and of the resolve (queue_args.glsl).
    dispatch_args: Buffer,
    /// 1 x 1 until the first frame, then the size of every frame (reallocated when it differs).
    targets: Targets,
    /// The world-space hash map and what its keys mean (F, region epochs).
    map: WorldHashMap,
    /// What the last frame depended on (`FrameDesc::key`): the next frame's change is decided against it.
    prev: Option<FrameKey>,
    /// Monotonic count of rendered frames (a hash cell's "last used" stamp).
    frame_index: u32,
    /// `frame_index` of the current still image's first frame (`FrameGlobals::still_start_frame`).
    still_start_frame: u32,
    /// Rounds of slices (whole frames without slices) since the view last changed (0 = new view).
    still_index: u32,
    /// The slice this frame draws of the round's `lattice`² (`FrameDesc::lattice`, taken at a round's start).
    slice: u32,
    lattice: u32,
    /// `frame_index` of the last local edit: for a round of slices after it, the pixels drawn see it.
    edit_frame: Option<u32>,
    /// Pixels on cells that still take rays in this round's slices so far (`converged`).
    round_young_pixels: u64,
    /// `still_index` at the last local edit: pixels near it restarted their refinement then.
    edit_still_index: u32,
    /// The last finished frame reported `converged`.
    last_converged: bool,
    /// Shaders check buffer bounds and count violations (`FrameReport::bounds_violations`; tests).
    check_bounds: bool,
    /// Test hook: the sky basis takes the pole's azimuth as NaN (`gpu::FLAG_INJECT_POLE_NAN`).
    inject_pole_nan: bool,
    /// The next frame starts a new still image (`restart_still_image`).
    restart: bool,
    /// How primary visibility is found (ray queries by default; `pick_primary` measures).
    primary: Primary,
    /// Created on the first rasterised frame.
    raster: Option<Rasterizer>,
    /// The commands and barriers the last `record_frame` recorded.
    last_events: Vec<Event>,
    /// The most rays one dispatch of a ray-tracing pass traces (`set_max_rays_per_dispatch`).
    max_rays_per_dispatch: u64,
    /// Sky light (`LightSettings::sky_light`): the environment's projection, loaded when first named, and the
    /// per-pixel buffer (`FrameGlobals::sky_pixels`, `gpu::SKY_PIXEL_FLOATS` floats per pixel) with the pixels
    /// it holds, made while the sky light is on. The cells' sums are the map's (`WorldHashMap::ensure_sky`).
    sky: Option<SkyLight>,
    sky_pixels: Option<(u64, Buffer)>,
}

impl Renderer {
    /// A renderer; its image size, hash map and settings come with each frame (`FrameDesc`).
    pub fn new(gpu: &Arc<Gpu>) -> Result<Renderer> {
        let globals = Buffer::new(
            gpu,
            "frame globals",
            std::mem::size_of::<FrameGlobals>() as u64,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        let stats = Buffer::new(
            gpu,
            "frame stats",
            std::mem::size_of::<FrameStats>() as u64,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        let dispatch_args = Buffer::new(
            gpu,
            "dispatch args",
            gpu::DISPATCH_ARGS_WORDS as u64 * 4,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::INDIRECT_BUFFER,
        )?;
        let passes = PassSet::new(gpu, &globals, &crate::passes::ALL)?;
        let r = Renderer {
            gpu: gpu.clone(),
            passes,
            globals,
            stats,
            in_flight: InFlight::new(gpu)?,
            dispatch_args,
            targets: Targets::new(gpu, 1, 1)?,
            map: WorldHashMap::new(gpu)?,
            prev: None,
            frame_index: 0,
            still_start_frame: 0,
            still_index: 0,
            slice: 0,
            lattice: 1,
            edit_frame: None,
            round_young_pixels: 0,
            edit_still_index: 0,
            last_converged: false,
            check_bounds: false,
            inject_pole_nan: false,
            restart: false,
            primary: Primary::default(),
            raster: None,
            last_events: Vec::new(),
            max_rays_per_dispatch: dispatch_plan::MAX_RAYS_PER_DISPATCH,
            sky: None,
            sky_pixels: None,
        };
        gpu.run_commands(|cmd| unsafe {
            gpu.device.cmd_fill_buffer(cmd, r.stats.raw, 0, vk::WHOLE_SIZE, 0);
            for readback in r.in_flight.readbacks() {
                gpu.device.cmd_fill_buffer(cmd, readback, 0, vk::WHOLE_SIZE, 0);
            }
        })?;
        Ok(r)
    }

    /// The next frame starts a new still image whatever it shares with the last one (a benchmark's runs).
    pub fn restart_still_image(&mut self) {
        self.restart = true;
    }

    /// Shaders check buffer bounds and count violations in `FrameReport::bounds_violations` (tests).
    pub fn set_check_bounds(&mut self, on: bool) {
        self.check_bounds = on;
    }

    /// Test hook: the sky basis takes the azimuth at its pole as NaN, as a GPU's atan(0, 0) may
    /// (`gpu::FLAG_INJECT_POLE_NAN`); the non-finite guard must keep the image finite and count it.
    pub fn set_inject_pole_nan(&mut self, on: bool) {
        self.inject_pole_nan = on;
    }

    /// How primary visibility is found (`pick_primary` measures which is faster).
    pub fn primary(&self) -> Primary {
        self.primary
    }

    pub fn set_primary(&mut self, primary: Primary) {
        self.primary = primary;
    }

    /// The LOD setting the grids of the local-edit region table (`RegionTable::region_lod`).
    pub fn region_lod(&self) -> i32 {
        self.map.regions.region_lod
    }

    pub fn gpu(&self) -> &Arc<Gpu> {
        &self.gpu
    }

    /// The size of the last frame (1 x 1 before the first).
    pub fn size(&self) -> (u32, u32) {
        (self.targets.width, self.targets.height)
    }

    /// Forgets all cached AO: empties the hash map and restarts the still image (whose pixels' own rays are
    /// cached AO too), so the next frame is a first frame from an empty map, as after opening a scene.
    pub fn clear_cache(&mut self) -> Result<()> {
        self.map.clear(&self.stats)?;
        self.restart_still_image();
        Ok(())
    }

    /// Makes the renderer ready for `frame`: targets of its size, a map of its capacity, and what its change
    /// from the previous frame invalidates (`Change::between`) applied: the still image restarts, the regions
    /// of a local edit get new epochs, or every cell gets a new key F (eq. 6).
    fn prepare(&mut self, frame: &FrameDesc) -> Result<()> {
        frame.validate().map_err(CoreError::Invalid)?;
        // Before anything moves on: an environment that cannot be read changes nothing.
        let light = &frame.settings.light;
        if light.sky_light && self.sky.as_ref().map(SkyLight::environment) != Some(light.environment.as_str())
        {
            self.sky =
                Some(SkyLight::load(&light.environment).map_err(|e| CoreError::Invalid(format!("{e:#}")))?);
        }
        let (w, h) = frame.size();
        if (w, h) != self.size() {
            if w as u64 * h as u64 <= self.targets.capacity {
                (self.targets.width, self.targets.height) = (w, h);
            } else {
                self.gpu.wait_idle();
                self.targets = Targets::new(&self.gpu, w, h)?;
            }
        }
        self.map.ensure(frame.settings.map.hash_capacity, &self.stats)?;
        if light.sky_light {
            self.ensure_sky_pixels()?;
            self.map.ensure_sky()?;
        }
        self.map
            .begin_frame(self.frame_index, frame.time, frame.settings.map.cache_lifetime_s);
        let key = frame.key(self.primary);
        let change = self.change_to(frame, &key);
        let mut map = change.map;
        if let MapChange::Regions(boxes) = &map {
            let reach = frame.settings.map.ao_radius;
            if !self.map.invalidate_regions(boxes, reach, self.frame_index) {
                map = MapChange::Whole;
            }
        }
        if map == MapChange::Whole {
            self.map.rekey(
                frame.effective_f(),
                change.settings_invalidate_map,
                self.frame_index,
                frame.settings,
            );
        }
        let restart = std::mem::take(&mut self.restart);
        let next = self.next_position(
            change.still_image || map == MapChange::Whole || restart,
            frame.lattice,
        );
        (self.still_index, self.slice, self.lattice) = (next.still_index, next.slice, next.lattice);
        if self.still_index == 0 && self.slice == 0 {
            self.edit_still_index = 0;
            self.still_start_frame = self.frame_index;
        }
        if matches!(map, MapChange::Regions(_)) {
            self.edit_frame = Some(self.frame_index);
            // The pixels of the slices before this one see the edit in the next round.
            self.edit_still_index = self.still_index + (self.slice > 0) as u32;
        }
        self.prev = Some(key);
        Ok(())
    }

    /// Sky light: the per-pixel buffer, for as many pixels as the targets hold.
    fn ensure_sky_pixels(&mut self) -> Result<()> {
        let pixels = self.targets.capacity;
        if self.sky_pixels.as_ref().is_some_and(|(n, _)| *n >= pixels) {
            return Ok(());
        }
        // Frames in flight may read the old one.
        self.gpu.wait_idle();
        self.sky_pixels = None;
        let bytes = pixels * gpu::SKY_PIXEL_FLOATS as u64 * 4;
        let buffer = Buffer::new(
            &self.gpu,
            "sky pixels",
            bytes,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        // Zeroed: no pixel holds rays of a frame yet (sky.glsl `SKY_OWN_FRAME`).
        let device = &self.gpu.device;
        self.gpu
            .run_commands(|cmd| unsafe { device.cmd_fill_buffer(cmd, buffer.raw, 0, vk::WHOLE_SIZE, 0) })?;
        self.sky_pixels = Some((pixels, buffer));
        Ok(())
    }

    /// What the change from the last frame to `frame` (of key `key`) invalidates (`Change::between`), with the
    /// located edits and plane moves between them.
    fn change_to(&self, frame: &FrameDesc, key: &FrameKey) -> Change {
        match &self.prev {
            None => Change::first(),
            Some(prev) => Change::between(prev, key, |p, n| {
                // Located edits and plane moves: only the regions within reach of them.
                let mut boxes = frame.scene.changes_between(p.scene_f, n.scene_f)?;
                boxes.extend(
                    frame
                        .scene
                        .section_changes_between(p.section_changes, n.section_changes)?,
                );
                Some(boxes)
            }),
        }
    }

    /// Where the next frame of the still image falls (`prepare` moves there; `record_visibility` predicts it):
    /// a new image's first slice when `restarts`, else the next slice of the round, or the next round's first.
    /// The first round may still grow its lattice to `frame_lattice`: its slices are the still image's first
    /// visit of each pixel and hold nothing a restart loses, and a view much costlier than the last (a young
    /// map, closer geometry) would otherwise keep frames over the target for a whole round (16 frames of 550 ms
    /// at L = 4 on san_francisco after a drag). A local edit's pixels see it within a round of slices from it:
    /// the lattice holds until then.
    fn next_position(&self, restarts: bool, frame_lattice: u32) -> SlicePosition {
        let slices = self.lattice * self.lattice;
        let edit_open = self
            .edit_frame
            .is_some_and(|e| self.frame_index.wrapping_sub(e) < slices);
        let grow_first_round = self.still_index == 0 && frame_lattice > self.lattice && !edit_open;
        if restarts || grow_first_round {
            SlicePosition {
                still_index: 0,
                slice: 0,
                lattice: frame_lattice,
            }
        } else if self.slice + 1 < slices {
            SlicePosition {
                still_index: self.still_index,
                slice: self.slice + 1,
                lattice: self.lattice,
            }
        } else {
            // A new round: every pixel has been drawn once more.
            SlicePosition {
                still_index: self.still_index.saturating_add(1),
                slice: 0,
                lattice: if edit_open { self.lattice } else { frame_lattice },
            }
        }
    }

    /// The frame's GPU parameters: its camera, tile and output, each settings group's share
    /// (`AoSettings::write_gpu`), and the renderer's own state (map, clock, buffers).
    fn globals_for(&self, frame: &FrameDesc, key_f: u32) -> FrameGlobals {
        let s = frame.settings;
        let t = &self.targets;
        let camera = &frame.camera;
        let (width, height) = frame.size();
        let cam = Camera {
            width,
            height,
            ..*camera
        };
        let (top, bottom) = frame.output.background;
        let (f, view_height, (top, bottom)) = match frame.tile {
            // A tile: the full image's rays, cells sized for the full image's pixels.
            Some(tile) => (
                tile.frame(
                    &Camera {
                        width: tile.full.0,
                        height: tile.full.1,
                        ..*camera
                    }
                    .frame(),
                    (width, height),
                    camera.is_orthographic(),
                ),
                tile.full.1,
                tile.gradient(top, bottom, height),
            ),
            None => (cam.frame(), height, (top, bottom)),
        };
        let view_height = if frame.view_height > 0 {
            frame.view_height
        } else {
            view_height
        };
        let feature_size = crate::hash::FeatureSize::for_camera(&cam, view_height, s.map.s_p);
        let jitter = Self::jitter(frame, self.still_index);
        let v4 = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        let c4 = |c: [f32; 3]| [c[0], c[1], c[2], 1.0];
        let slice_offset = slice_order::offset(self.slice, self.lattice);
        let (level_spacing, _) = self.level_spacing();
        let mut g = FrameGlobals {
            eye: v4(f.eye),
            cam_u: v4(f.u),
            cam_v: v4(f.v),
            cam_w: v4(f.w),
            jitter,
            width,
            height,
            still_index: self.still_index,
            scene_f: key_f,
            frame_index: self.frame_index,
            f_start_frame: self.map.f_start_frame(),
            lifetime_frames: self.map.lifetime_frames(),
            s_w_per_distance: feature_size.per_distance,
            s_w_base: feature_size.base,
            hash_capacity: self.map.capacity(),
            region_lod: self.map.regions.region_lod,
            background_top: c4(top),
            background_bottom: c4(bottom),
            gbuffer: t.gbuffer.address,
            ao: t.ao.address,
            lod_used: t.lod_used.address,
            filter_plan: t.filter_plan.address,
            filter_guide: t.filter_guide.address,
            filter_tmp: t.filter_tmp.address,
            pixel_rays: t.pixel_rays.address,
            accum: t.accum.address,
            output_rgba: t.output.address,
            hash_cells: self.map.address(),
            pixel_cells: t.pixel_cells.address,
            stats: self.stats.address,
            ray_queue: t.ray_queue.address,
            filter_queue: t.filter_queue.address,
            dispatch_args: self.dispatch_args.address,
            regions: self.map.regions.address(),
            slice_prior: t.slice_prior.address,
            bias_evidence: t.bias_evidence.address,
            projection: match cam.projection {
                Projection::Perspective => gpu::PROJECTION_PERSPECTIVE,
                Projection::Orthographic => gpu::PROJECTION_ORTHOGRAPHIC,
            },
            view_height,
            edge_width: EDGE_WIDTH,
            lattice: self.lattice,
            lattice_x: slice_offset.0,
            lattice_y: slice_offset.1,
            level_spacing,
            still_start_frame: self.still_start_frame,
            edit_window: self.lattice * self.lattice,
            ..bytemuck::Zeroable::zeroed()
        };
        s.write_gpu(&mut g);
        let budget = frame.budget();
        g.rays_per_pixel = budget.rays_per_pixel;
        g.trace_fraction = budget.trace_fraction;
        if self.lattice > 1 {
            // Slices: a round visits each pixel once with all its rays; the smoothing counts them (per ray).
            g.still_smoothing = crate::settings::frame_smoothing(budget.rays_per_pixel);
        }
        if frame.output.bgra {
            g.flags |= gpu::FLAG_OUTPUT_BGRA;
        }
        if self.check_bounds {
            g.flags |= gpu::FLAG_CHECK_BOUNDS;
        }
        if self.inject_pole_nan {
            g.flags |= gpu::FLAG_INJECT_POLE_NAN;
        }
        if self.map.regions.any_edit() {
            g.flags |= gpu::FLAG_REGION_EPOCHS;
        }
        if self.map.young(self.frame_index) {
            g.flags |= gpu::FLAG_YOUNG_MAP;
        }
        if self.map.has_room() {
            g.flags |= gpu::FLAG_MAP_HAS_ROOM;
        }
        g.flags |= additions::flags(&self.young_frame(frame));
        if s.light.sky_light {
            // `prepare` made both.
            if let (Some(sky), Some((_, pixels))) = (&self.sky, &self.sky_pixels) {
                sky.write_gpu(&s.light, &mut g);
                g.sky_cells = self.map.sky_address();
                g.sky_pixels = pixels.address;
            }
        }
        g
    }

    /// What the young map's additions (`crate::additions`) need to know of `frame`.
    fn young_frame<'a>(&self, frame: &FrameDesc<'a>) -> additions::YoungFrame<'a> {
        additions::YoungFrame {
            settings: frame.settings,
            young: frame.settings.display.mode.uses_hash() && self.map.young(self.frame_index),
        }
    }

    /// The sub-pixel offset of a still image's frame `still_index` (a round of slices: all its slices): R2 points
    /// in the pixel, frame after frame, the centre first (none when `frame` does not accumulate).
    fn jitter(frame: &FrameDesc, still_index: u32) -> [f32; 2] {
        if frame.jitter && frame.settings.accumulates() && still_index > 0 {
            let i = still_index as f64;
            [
                ((0.7548776662466927 * i).fract() - 0.5) as f32,
                ((0.5698402909980532 * i).fract() - 0.5) as f32,
            ]
        } else {
            [0.0, 0.0]
        }
    }

    /// True when the output buffer already holds the final image of `frame`: the last frame converged and
    /// nothing it depends on (camera, size, settings, scene, instances, output) has changed since. A viewer can
    /// then present the output again instead of rendering (expose events, UI repaints).
    pub fn shows_final(&self, frame: &FrameDesc) -> bool {
        self.last_converged && self.prev.as_ref() == Some(&frame.key(self.primary))
    }

    /// True when the output buffer holds an image of `frame` (converged or not): nothing it depends on has
    /// changed since the last frame; rendering it again would only refine it.
    pub fn shows(&self, frame: &FrameDesc) -> bool {
        self.prev.as_ref() == Some(&frame.key(self.primary))
    }

    /// Records all passes of `frame` into `cmd` (the caller submits and then calls `finish_frame`). The output
    /// is left in `output_buffer()`.
    pub fn record_frame(&mut self, cmd: vk::CommandBuffer, frame: &FrameDesc) -> Result<()> {
        // Before `prepare` moves the renderer on: a frame that cannot be recorded changes nothing.
        self.in_flight.free_slot()?;
        self.prepare(frame)?;
        self.record_prepared(cmd, frame)
    }

    /// `record_frame` after `prepare`: records only (preparing may submit work of its own, a new map's clear,
    /// so it runs before the caller's command buffer is taken).
    fn record_prepared(&mut self, cmd: vk::CommandBuffer, frame: &FrameDesc) -> Result<()> {
        let (scene, camera, settings) = (frame.scene, &frame.camera, frame.settings);
        let slot = self.in_flight.free_slot()?;
        if self.map.regions.dirty() && !self.in_flight.is_empty() {
            // A local edit's epochs are host-written: frames in flight read the table.
            self.gpu.wait_idle();
        }
        self.map.regions.upload()?;
        let globals = self.frame_globals(frame);
        record_update(&self.gpu, cmd, self.globals.raw, bytemuck::bytes_of(&globals));
        self.passes.bind_tlas(scene.tlas.raw, scene.tlas_generation());

        let (w, h) = self.size();
        // Passes over the image run over this frame's slice: every lattice-th pixel (common.glsl).
        let (gw, gh) = self.slice_grid();
        let (_, new_level) = self.level_spacing();
        let primary = self.primary;
        if primary == Primary::Raster {
            let raster = match &mut self.raster {
                Some(r) => r,
                None => self.raster.insert(Rasterizer::new(&self.gpu)?),
            };
            // The whole frame's visibility, drawn once per round of slices.
            raster.prepare(w, h)?;
        }
        let mode = settings.display.mode;
        let cell_levels = self
            .map
            .cell_levels(self.frame_index, self.pixel_count() as u32, settings.map.s_p);
        let young_frame = self.young_frame(frame);
        let readback = self.in_flight.slot(slot).readback.raw;
        let probe_push = self.in_flight.slot_mut(slot).probes.write(frame.probes)?;
        let timer = self.in_flight.slot_mut(slot).timer.as_mut();
        let mut rec = Recorder::new(&self.gpu, cmd, &self.passes, timer);
        scene.record_uploads(&mut rec);
        match (primary, &mut self.raster) {
            (Primary::Raster, Some(raster)) => {
                // A perspective tile is an off-axis part of the full image's frustum: the full image's axis,
                // moved by the tile's centre (an orthographic tile moves its eye instead, as its rays do).
                let off_axis = match frame.tile {
                    Some(tile) if !camera.is_orthographic() => Some((
                        Camera {
                            width: tile.full.0,
                            height: tile.full.1,
                            ..*camera
                        }
                        .frame()
                        .w,
                        tile.ndc_offset((w, h)),
                    )),
                    _ => None,
                };
                raster.record(
                    &mut rec,
                    &scene.raster,
                    &globals,
                    self.globals.address,
                    camera.distance(),
                    off_axis,
                    (scene.tlas_generation(), scene.version()),
                    Some((gw, gh)),
                );
            }
            _ => {
                // One ray per pixel, in bands of rows where the image holds more than a dispatch may trace.
                for c in dispatch_plan::plan(gw, gh, 1, self.max_rays_per_dispatch) {
                    rec.dispatch(Pass::PRIMARY, gw, c.rows, [0, 0, c.first_row, c.rows]);
                }
            }
        }
        additions::record_after_primary(&mut rec, &young_frame, &self.targets.additions, gw, gh);
        // The frame's probe rays (the walk's), on the TLAS the frame traces.
        crate::probes::record(&mut rec, probe_push);
        // Ray-tracing passes in dispatches of at most `max_rays_per_dispatch` rays (dispatch_plan.rs).
        let rpp = settings.map.rays_per_pixel;
        // The bound counts traversals: with the sky light, a ray open within R is traced on to infinity.
        let bound = self.max_rays_per_dispatch / dispatch_plan::traversals_per_ray(settings.light.sky_light);
        if mode == Mode::Rtao {
            for c in dispatch_plan::plan(gw, gh, rpp, bound) {
                rec.dispatch(Pass::RTAO, gw, c.rows, [0, c.rays_word(), c.first_row, c.rows]);
            }
            if rpp == 0 {
                // No ray: the pass still clears the pixels' counts.
                rec.dispatch(Pass::RTAO, gw, gh, [0, 0, 0, gh]);
            }
        } else if mode.uses_hash() {
            // The last cell-finder dispatch also queues the pixels whose cell still takes rays, packed densely
            // (the update then runs no idle lanes), and its last work group writes the update's dispatch size.
            for &(top, bottom) in &cell_levels {
                rec.dispatch(Pass::CELL_FINDER, gw, gh, [top, bottom, 0, 0]);
            }
            let rays = gpu::RAY_ARGS_OFFSET;
            let args = &self.dispatch_args;
            // One dispatch, or three with adaptive sampling (ours) in a young map.
            // Each cut into chunks over the queue's bands of gw pixels (at most gw x gh pixels are queued).
            for &phase in additions::update_phases(&young_frame) {
                for c in dispatch_plan::plan(gw, gh, additions::update_rays(phase, rpp), bound) {
                    let push = [phase, c.rays_word(), c.first_row * gw, c.rows * gw];
                    rec.dispatch_indirect(Pass::AO_UPDATE, args, rays, push);
                }
            }
            rec.dispatch(Pass::RESOLVE, gw, gh, [0; 4]);
            let iterations = settings.filter.filter_iterations;
            if iterations > 0 {
                // Over the pixels the resolve queued (those whose plan takes an iteration). Ping-pong:
                // iteration i reads one buffer and writes the other; an even count ends in `ao`. The resolve's
                // last work group wrote the queue's dispatch size.
                let filter = gpu::FILTER_ARGS_OFFSET;
                for i in 0..iterations {
                    rec.dispatch_indirect(Pass::FILTER, args, filter, [i, iterations, 0, 0]);
                }
            }
            // A young map's corrections (ours, `crate::additions`).
            additions::record_corrections(&mut rec, &young_frame, &self.targets.additions, args);
        }
        // The frame's counters, once, for `finish_frame`: composite.comp counts nothing (its declaration
        // writes no `Stats`), so the copy is recorded before it and shares its barrier.
        let bytes = std::mem::size_of::<FrameStats>() as u64;
        let stats = self.stats.raw;
        let uses = vec![
            Use::read(Resource::Stats, Stage::Transfer),
            Use::write(Resource::StatsReadback, Stage::Transfer),
        ];
        rec.commands("statistics copy", None, uses, |d, cmd| unsafe {
            d.cmd_copy_buffer(
                cmd,
                stats,
                readback,
                &[vk::BufferCopy {
                    src_offset: 0,
                    dst_offset: 0,
                    size: bytes,
                }],
            );
        });
        rec.dispatch(Pass::COMPOSITE, gw, gh, [0; 4]);
        if let Some(show) = new_level {
            // The first round of slices shows the finest grid of pixels drawn so far, interpolated over the
            // whole image (composite.comp `show_level`).
            rec.dispatch(Pass::COMPOSITE, w, h, [1, show.edges as u32, 0, 0]);
        }
        self.last_events = rec.finish();
        self.frame_index = self.frame_index.wrapping_add(1);
        self.in_flight.push(Recorded {
            slot,
            key: self.prev.clone().expect("prepare keeps the frame's key"),
            frame_index: self.frame_index,
            still_index: self.still_index,
            slice: self.slice,
            lattice: self.lattice,
            pixels: self.pixel_count(),
        });
        Ok(())
    }

    /// Draws the whole view's visibility of `frame` ahead of a round of slices, in a command buffer of its own:
    /// when `frame` would start a round of a still image in slices (`lattice` > 1: a change from the last frame
    /// restarts the image, or the last frame ended a round; each round has its own jitter) and raster primary
    /// visibility draws it. The round's first slice then resolves its pixels from that draw instead of drawing
    /// every triangle itself: on a software device the draw of a large scene is most of that slice
    /// (san_francisco: 77 of 110-160 ms at 800x800), and input that comes meanwhile waits for the frame in
    /// flight. Nothing else changes: the output keeps the last frame's image (of `size()`), which a viewer
    /// presents again, and no frame is counted (no `finish_frame`). Returns whether it recorded the draw; false
    /// when the draw is not needed or already done (then `record_frame` as usual).
    pub fn record_visibility(&mut self, cmd: vk::CommandBuffer, frame: &FrameDesc) -> Result<bool> {
        if self.primary != Primary::Raster || frame.lattice <= 1 || frame.tile.is_some() {
            return Ok(false);
        }
        frame.validate().map_err(CoreError::Invalid)?;
        // The still image's frame the next `record_frame` draws (`prepare`'s `next_position`): drawn ahead when
        // it starts a round. A located edit is taken to keep the image, as `prepare` keeps it unless the regions
        // overflow (then its slice draws again: the draw's key differs).
        let key = frame.key(self.primary);
        let change = self.change_to(frame, &key);
        let restarts = self.restart || change.still_image || change.map == MapChange::Whole;
        let next = self.next_position(restarts, frame.lattice);
        if next.slice != 0 {
            return Ok(false);
        }
        let still_index = next.still_index;
        let mut globals = self.frame_globals(frame);
        globals.jitter = Self::jitter(frame, still_index);
        let (w, h) = frame.size();
        let raster = match &mut self.raster {
            Some(r) => r,
            None => self.raster.insert(Rasterizer::new(&self.gpu)?),
        };
        raster.prepare(w, h)?;
        record_update(&self.gpu, cmd, self.globals.raw, bytemuck::bytes_of(&globals));
        let scene = frame.scene;
        let mut rec = Recorder::new(&self.gpu, cmd, &self.passes, None);
        let drew = raster.record(
            &mut rec,
            &scene.raster,
            &globals,
            self.globals.address,
            frame.camera.distance(),
            None,
            (scene.tlas_generation(), scene.version()),
            None,
        );
        rec.finish();
        Ok(drew)
    }

    /// The frame's GPU parameters as `record_prepared` uploads them: `globals_for`, the orthographic ray start,
    /// the scene's tables and section planes.
    fn frame_globals(&self, frame: &FrameDesc) -> FrameGlobals {
        let (scene, camera) = (frame.scene, &frame.camera);
        let mut globals = self.globals_for(frame, self.map.key_f());
        if camera.is_orthographic() {
            // Orthographic rays start in front of the whole scene: nothing is clipped by the eye plane.
            let b = scene.raster.bounds();
            let corners = if b.is_empty() {
                Vec::new()
            } else {
                b.corners().to_vec()
            };
            // A tile's eye is moved across the image plane (`Tile::frame`): keep that offset.
            let offset = glam::Vec3::from_slice(&globals.eye[..3]) - glam::Vec3::from(camera.eye);
            let start = camera.ortho_ray_plane(&corners) + offset;
            globals.eye = [start.x, start.y, start.z, 0.0];
        }
        globals.instances = scene.instance_info.address;
        globals.geometries = scene.geometries.address;
        let ([s0, s1, s2], count) = scene.sections().gpu();
        (globals.section0, globals.section1, globals.section2) = (s0, s1, s2);
        globals.section_count = count;
        globals
    }

    /// The first rounds of a still image in slices hold what the view shows (composite.comp `held_round`): the
    /// spacing of the grid of pixels shown interpolated (`slice_order::level`; 0: not held), and whether this
    /// frame completes it. Round 0 shows each grid as it completes (for L = 8 the spacings 8, 4 and 2); the
    /// later held rounds keep round 0's finest until the last of them ends and shows all its pixels (spacing 1):
    /// their pixels come in beside round 0's cell estimates, and one at a time they would speckle. The rounds
    /// held are those that leave fewer than `held_own_rays` own rays per pixel, at least two: an image that
    /// traces fewer rays per visit (a viewer cutting its slices' rays) shows its pixels with as many own rays
    /// as one that does not.
    /// A round whose end can make the image final is never held: the final image is its pixels as they are,
    /// not the grid's reconstruction (a B-spline approximates, it does not interpolate).
    /// The grid shows no feature edges until every pixel has this view's G-buffer (a line sampled on a grid is a
    /// row of dots): round 0's last slice shows its finest grid again, with the edges drawn per pixel.
    fn level_spacing(&self) -> (u32, Option<LevelShow>) {
        let (l, slice) = (self.lattice, self.slice);
        let held_rounds = self.prev.as_ref().map_or(2, |key| {
            let rpp = key.budget.rays_per_pixel.max(1);
            held_own_rays(key.settings.still.still_samples)
                .div_ceil(rpp)
                .max(2)
        });
        if self.still_index >= held_rounds || l == 1 {
            return (0, None);
        }
        if let Some(key) = &self.prev {
            if self.converged(key, self.still_index, 0) {
                return (0, None);
            }
        }
        let last = slice + 1 == l * l;
        if self.still_index >= 1 {
            if last && self.still_index + 1 == held_rounds {
                return (1, Some(LevelShow { edges: true }));
            }
            return (slice_order::finest_grid(l * l - 1, l).unwrap_or(l), None);
        }
        let completes = slice_order::level(slice, l).is_some_and(|s| s > 1);
        let show = (completes || last).then_some(LevelShow { edges: last });
        (slice_order::finest_grid(slice, l).unwrap_or(0), show)
    }

    /// The invocations of a pass over the image this frame: the pixels of its slice's lattice.
    fn slice_grid(&self) -> (u32, u32) {
        let (w, h) = self.size();
        let a = self.lattice.max(1);
        let (x, y) = slice_order::offset(self.slice, a);
        (w.saturating_sub(x).div_ceil(a), h.saturating_sub(y).div_ceil(a))
    }

    /// Whether this frame's GPU timestamps measure its passes. Lavapipe writes the timestamps recorded after a
    /// raster pass only when the submission ends, so there every pass after raster primary visibility read about
    /// 0.1 ms in a 950 ms frame (862×800, `examples/orbit_profile`); such frames report no per-pass times.
    pub fn timestamps_measure(&self) -> bool {
        !(self.gpu.info.is_software && self.primary == Primary::Raster)
    }

    /// Reads the statistics of the oldest frame recorded and not finished, which the caller waited for (with
    /// one frame in flight: the frame just recorded and completed).
    pub fn finish_frame(&mut self, wall_ms: f64) -> Result<FrameReport> {
        let Some(done) = self.in_flight.pop() else {
            return Err(CoreError::Invalid(
                "finish_frame before any recorded frame".into(),
            ));
        };
        let key = done.key;
        let probe_hits = self.in_flight.slot_mut(done.slot).probes.take_hits()?;
        let slot = self.in_flight.slot(done.slot);
        let stats: FrameStats = slot.readback.read(1)?[0];
        let c = stats.counters;
        let rays = |i: u32| stats.rays[i as usize];
        let gpu_ms = match &slot.timer {
            Some(t) if self.timestamps_measure() => t.read()?,
            _ => Vec::new(),
        };
        let occupied = c[gpu::STAT_OCCUPIED as usize];
        let young_pixels =
            c[gpu::STAT_RAY_QUEUE as usize] as u64 + c[gpu::STAT_UNPICKED_PIXELS as usize] as u64;
        // A still image is final only at the end of a round of slices, and from the whole round's pixels.
        let slices = done.lattice * done.lattice;
        self.round_young_pixels = if done.slice == 0 {
            young_pixels
        } else {
            self.round_young_pixels + young_pixels
        };
        self.last_converged =
            done.slice + 1 == slices && self.converged(&key, done.still_index, self.round_young_pixels);
        let budget = done.pixels as f64
            * key.budget.rays_per_pixel as f64
            * key.budget.trace_fraction.clamp(0.0, 1.0) as f64;
        self.map.finish_frame(
            done.frame_index,
            rays(gpu::RAYS_CELL),
            budget.ceil() as u64,
            occupied,
            c[gpu::STAT_MAX_PROBE as usize],
            c[gpu::STAT_FAILED_INSERTS as usize] > 0,
        );
        let capacity = self.map.capacity().max(1);
        Ok(FrameReport {
            gpu_total_ms: gpu_ms.iter().fold(0.0, |sum, (_, ms)| sum + ms),
            gpu_ms,
            wall_ms,
            rays: rays(gpu::RAYS_ALL),
            cells_inserted: c[gpu::STAT_CELLS_INSERTED as usize],
            failed_inserts: c[gpu::STAT_FAILED_INSERTS as usize],
            longest_probe: c[gpu::STAT_MAX_PROBE as usize],
            reclaimed: c[gpu::STAT_RECLAIMED as usize],
            bounds_violations: c[gpu::STAT_BOUNDS_VIOLATIONS as usize],
            non_finite: c[gpu::STAT_NON_FINITE as usize],
            capped_pixels: c[gpu::STAT_CAPPED_PIXELS as usize],
            occupied_cells: occupied,
            load_factor: occupied as f64 / capacity as f64,
            scene_f: key.scene_f.wrapping_add(key.section_changes),
            map_f: self.map.key_f(),
            accumulated_frames: done.still_index + 1,
            refine_rays: rays(gpu::RAYS_REFINE),
            cell_rays: rays(gpu::RAYS_CELL),
            ray_pixels: c[gpu::STAT_RAY_QUEUE as usize],
            filtered_pixels: c[gpu::STAT_FILTER_QUEUE as usize],
            converged: self.last_converged,
            slice: done.slice,
            slices,
            probe_hits,
        })
    }

    /// Renders one frame headless and waits for it. Frames recorded and not finished must be finished first
    /// (their reports come first).
    pub fn render(&mut self, frame: &FrameDesc) -> Result<FrameReport> {
        if !self.in_flight.is_empty() {
            return Err(CoreError::Invalid(format!(
                "render with {} frame(s) recorded and not finished",
                self.in_flight.len()
            )));
        }
        let t0 = Instant::now();
        let gpu = self.gpu.clone();
        self.prepare(frame)?;
        let mut recorded = Ok(());
        gpu.run_commands(|cmd| recorded = self.record_prepared(cmd, frame))?;
        recorded?;
        self.finish_frame(t0.elapsed().as_secs_f64() * 1e3)
    }

    /// Chooses the faster primary visibility for `frame`'s scene by measurement: a frame without AO with each,
    /// after a warm-up frame each (the first dispatch compiles pipelines), timed by the GPU timestamps where
    /// both frames' timestamps measure their passes (on a GPU the wall clock of a frame this small measures the
    /// submission's latency, not the passes), else both on the wall clock (timestamps after a render pass are
    /// unreliable on lavapipe, `timestamps_measure`). Keeps the choice (`primary()`) and returns it with the
    /// two times in ms (ray queries, raster; NaN when a scene above `RASTER_TRIAL_TRIANGLES`, or a device that
    /// cannot rasterise it, is not tried). The trial frames are forgotten, as `warm_up`'s: the next frame is a
    /// first frame (a new map, young, and a new still image), not the fifth of a view whose map took no rays.
    pub fn pick_primary(&mut self, frame: &FrameDesc) -> Result<(Primary, f64, f64)> {
        if let Err(e) = Rasterizer::available(&self.gpu) {
            log::info!("{e}");
            self.primary = Primary::RayQuery;
            return Ok((self.primary, f64::NAN, f64::NAN));
        }
        if frame.scene.raster.triangles() > RASTER_TRIAL_TRIANGLES {
            self.primary = Primary::RayQuery;
            return Ok((self.primary, f64::NAN, f64::NAN));
        }
        let mut no_ao = frame.settings.clone();
        no_ao.display.mode = Mode::NoAo;
        let probe = FrameDesc {
            settings: &no_ao,
            ..*frame
        };
        let time = |r: &mut Renderer, primary| -> Result<(f64, Option<f64>)> {
            r.primary = primary;
            r.render(&probe)?;
            let report = r.render(&probe)?;
            let gpu = (!report.gpu_ms.is_empty() && report.gpu_total_ms > 0.0).then_some(report.gpu_total_ms);
            Ok((report.wall_ms, gpu))
        };
        let ray_query = time(self, Primary::RayQuery);
        let raster = time(self, Primary::Raster);
        let (ray_query, raster) = match (ray_query?, raster?) {
            ((_, Some(rq)), (_, Some(ra))) => (rq, ra),
            ((rq, _), (ra, _)) => (rq, ra),
        };
        self.primary = if raster < ray_query {
            Primary::Raster
        } else {
            Primary::RayQuery
        };
        self.prev = None;
        Ok((self.primary, ray_query, raster))
    }

    /// Runs the passes a view's frames use once, on a tiny image of `frame`'s scene and settings (a young map's
    /// first frames, a still image's frames and a round of slices), then forgets what they cached. Lavapipe
    /// compiles a pipeline at its first dispatch: without this, the first moving and still frames after a scene
    /// opens pay the compilations (~0.1-0.3 s), and input that comes meanwhile waits for them. On a GPU it costs
    /// a few tiny frames.
    pub fn warm_up(&mut self, frame: &FrameDesc) -> Result<()> {
        let camera = Camera {
            width: WARM_UP_SIZE,
            height: WARM_UP_SIZE,
            ..frame.camera
        };
        for lattice in [1, 1, 2, 2, 2, 2] {
            self.render(&FrameDesc {
                camera,
                lattice,
                ..*frame
            })?;
        }
        self.clear_cache()?;
        self.prev = None;
        Ok(())
    }

    /// Whether the frame just rendered (`key`, `still_index` frames into its view, `young_pixels` of it on
    /// cells that still take rays, traced this frame or not) is final: per-pixel RTAO and HRTAO with refinement
    /// once each pixel has `still_samples` of its own rays (and, with jitter, `AA_FRAMES` samples); the paper's
    /// HRTAO once no pixel on screen has a cell that takes rays; other modes once anti-aliased.
    fn converged(&self, key: &FrameKey, still_index: u32, young_pixels: u64) -> bool {
        let s = &key.settings;
        let rpp = key.budget.rays_per_pixel as u64;
        let frames = still_index + 1;
        let aa = !key.jitter || frames >= AA_FRAMES;
        let own_rays = |frames: u32| frames as u64 * rpp >= s.still.still_samples as u64;
        match s.display.mode {
            Mode::Rtao => aa && (rpp == 0 || own_rays(frames)),
            // Pixels near a local edit restarted their own rays then.
            Mode::Hrtao if s.still.refine => {
                aa && (rpp == 0 || own_rays(still_index.saturating_sub(self.edit_still_index)))
            }
            Mode::Hrtao => young_pixels == 0 && frames > 1,
            _ => aa,
        }
    }

    /// The RGBA8 output buffer (for copying to a swapchain image).
    pub fn output_buffer(&self) -> &Buffer {
        &self.targets.output
    }

    fn read_buffer<T: bytemuck::Pod>(&self, src: &Buffer, count: usize) -> Result<Vec<T>> {
        let bytes = (count * std::mem::size_of::<T>()) as u64;
        let staging = Buffer::new(
            &self.gpu,
            "readback",
            bytes,
            MemoryLocation::GpuToCpu,
            vk::BufferUsageFlags::empty(),
        )?;
        self.gpu.run_commands(|cmd| unsafe {
            self.gpu.device.cmd_copy_buffer(
                cmd,
                src.raw,
                staging.raw,
                &[vk::BufferCopy {
                    src_offset: 0,
                    dst_offset: 0,
                    size: bytes,
                }],
            );
            host_read_barrier(&self.gpu, cmd);
        })?;
        staging.read(count)
    }

    fn pixel_count(&self) -> usize {
        self.targets.width as usize * self.targets.height as usize
    }

    /// The linear AO image of the last frame, row 0 at the top (background = 1).
    pub fn read_ao(&self) -> Result<Vec<f32>> {
        self.read_buffer(&self.targets.ao, self.pixel_count())
    }

    /// The sky light of the last frame (`--light-out`'s value: linear RGB, background 0), row 0 at the top; an
    /// error when it did not light with the sky.
    pub fn read_light(&self) -> Result<Vec<[f32; 3]>> {
        let on = self
            .prev
            .as_ref()
            .is_some_and(|k| k.settings.light.sky_light && k.settings.display.mode == Mode::Hrtao);
        let Some((_, buffer)) = self.sky_pixels.as_ref().filter(|_| on) else {
            return Err(CoreError::Invalid(
                "the last frame was not lit by the sky light (HRTAO with `sky_light`)".into(),
            ));
        };
        let stride = gpu::SKY_PIXEL_FLOATS as usize;
        let light = (5 * gpu::SKY_COEFFS) as usize;
        let floats: Vec<f32> = self.read_buffer(buffer, self.pixel_count() * stride)?;
        Ok(floats
            .chunks_exact(stride)
            .map(|p| [p[light], p[light + 1], p[light + 2]])
            .collect())
    }

    /// The composited sRGB RGBA8 image of the last frame, row 0 at the top.
    pub fn read_rgba(&self) -> Result<Vec<u8>> {
        let px: Vec<u32> = self.read_buffer(&self.targets.output, self.pixel_count())?;
        Ok(bytemuck::cast_slice(&px).to_vec())
    }

    /// Per pixel, the AO it kept aside when drawn in the held rounds of a still image in slices (composite.comp
    /// `keep_aside`): the grid values the view shows reconstructed (tests).
    pub fn read_held_ao(&self) -> Result<Vec<f32>> {
        let n = self.pixel_count();
        let slots: Vec<[f32; 4]> = self.read_buffer(&self.targets.bias_evidence, 3 * n)?;
        Ok(slots[2 * n..].iter().map(|v| v[0]).collect())
    }

    /// The G-buffer of the last frame (tests, picking).
    pub fn read_gbuffer(&self) -> Result<Vec<GPixel>> {
        self.read_buffer(&self.targets.gbuffer, self.pixel_count())
    }

    /// The LOD index used per pixel by the last HRTAO frame (0 = finest, LOD_COUNT = none).
    /// Each pixel's filter plan (filter_plan.glsl): `FILTER_PLAN_BITS` low bits of à-trous iterations, then
    /// the rays of the cell its AO came from.
    pub fn read_filter_plan(&self) -> Result<Vec<u32>> {
        self.read_buffer(&self.targets.filter_plan, self.pixel_count())
    }

    /// Per pixel, the rays it traced itself in the last frame (`PixelRays`).
    pub fn read_pixel_rays(&self) -> Result<Vec<PixelRays>> {
        self.read_buffer(&self.targets.pixel_rays, self.pixel_count())
    }

    pub fn read_lod_used(&self) -> Result<Vec<u32>> {
        self.read_buffer(&self.targets.lod_used, self.pixel_count())
    }

    pub fn read_pixel_cells(&self) -> Result<Vec<PixelCells>> {
        self.read_buffer(&self.targets.pixel_cells, self.pixel_count())
    }

    /// The G-buffer sample at pixel (x, y) of the last frame (row 0 at the top): what a click picks.
    /// None outside the image or on the background.
    pub fn pick(&self, x: u32, y: u32) -> Result<Option<GPixel>> {
        let (w, h) = self.size();
        if x >= w || y >= h {
            return Ok(None);
        }
        let size = std::mem::size_of::<GPixel>() as u64;
        let offset = (y as u64 * w as u64 + x as u64) * size;
        let staging = Buffer::new(
            &self.gpu,
            "pick",
            size,
            MemoryLocation::GpuToCpu,
            vk::BufferUsageFlags::empty(),
        )?;
        let src = self.targets.gbuffer.raw;
        self.gpu.run_commands(|cmd| unsafe {
            self.gpu.device.cmd_copy_buffer(
                cmd,
                src,
                staging.raw,
                &[vk::BufferCopy {
                    src_offset: offset,
                    dst_offset: 0,
                    size,
                }],
            );
            host_read_barrier(&self.gpu, cmd);
        })?;
        let px: GPixel = staging.read(1)?[0];
        Ok((px.t >= 0.0 && px.instance != gpu::NO_INSTANCE).then_some(px))
    }

    pub fn read_hash_cells(&self) -> Result<Vec<HashCell>> {
        match self.map.cells() {
            Some(cells) => self.read_buffer(cells, self.map.capacity() as usize),
            None => Ok(Vec::new()),
        }
    }

    /// Evaluates the shaders' hash on `cases` (for the CPU-mirror test), with the s_min, s_nd and capacity of
    /// `settings`. Needs a scene only for the descriptor set's TLAS binding.
    pub fn hash_on_gpu(
        &mut self,
        scene: &SceneGpu,
        settings: &AoSettings,
        cases: &[HashTestCase],
    ) -> Result<Vec<HashTestCase>> {
        self.map.ensure(settings.map.hash_capacity, &self.stats)?;
        let buf = Buffer::from_slice(&self.gpu, "hash test cases", cases, vk::BufferUsageFlags::empty())?;
        let mut globals = self.globals_for(&FrameDesc::new(scene, 0, Camera::default(), settings), 0);
        const ROW: u32 = 256;
        globals.width = ROW;
        globals.height = (cases.len() as u32).div_ceil(ROW).max(1);
        self.passes.bind_tlas(scene.tlas.raw, scene.tlas_generation());
        let [lo, hi] = buf.address_words();
        let push = [lo, hi, cases.len() as u32, 0];
        self.gpu.run_commands(|cmd| {
            record_update(&self.gpu, cmd, self.globals.raw, bytemuck::bytes_of(&globals));
            let mut rec = Recorder::new(&self.gpu, cmd, &self.passes, None);
            rec.dispatch(Pass::HASH_TEST, ROW, globals.height, push);
            rec.finish();
        })?;
        buf.read(cases.len())
    }

    /// The keys of the cells the cell finder gives a G-buffer sample at each level (a CPU mirror of
    /// cell_finder.comp for tests of the map).
    pub fn pixel_cell_keys(&self, frame: &FrameDesc, px: &GPixel) -> [crate::hash::CellKey; 4] {
        // The F cells are keyed with: the renderer's for the last frame's F (after a local edit too), else the
        // frame's.
        let key_f = match &self.prev {
            Some(k) if (k.scene_f, k.section_changes) == (frame.scene_f, frame.scene.section_changes()) => {
                self.map.key_f()
            }
            _ => self.map.key_f_after_change(frame.effective_f()),
        };
        let mut g = self.globals_for(frame, key_f);
        g.hash_capacity = frame.settings.map.hash_capacity;
        let size = crate::hash::FeatureSize {
            base: g.s_w_base,
            per_distance: g.s_w_per_distance,
        };
        let lod = crate::hash::pixel_lod(px.t, size, g.s_w_max, g.log2_s_min);
        std::array::from_fn(|level| {
            let l = lod + level as i32;
            let c = crate::hash::cell_coord(px.position.into(), l);
            let epoch = self
                .map
                .regions
                .epoch(crate::hash::region_index(c, l, g.region_lod));
            crate::hash::cell_key_at(
                c,
                l,
                crate::hash::normal_coord(
                    px.normal.into(),
                    crate::hash::NormalBins {
                        s_nd: g.s_nd,
                        offset: g.normal_offset,
                    },
                ),
                key_f,
                epoch,
                g.hash_capacity,
            )
        })
    }

    /// Descriptor writes of the TLAS binding so far (one per TLAS build a frame used).
    pub fn tlas_descriptor_writes(&self) -> u64 {
        self.passes.tlas_writes()
    }

    /// Bounds the rays one dispatch of a ray-tracing pass traces (default `dispatch_plan::MAX_RAYS_PER_DISPATCH`,
    /// at least 1): the per-pixel RTAO and the ray-tracing update are cut into as many dispatches as it takes.
    /// A per-pixel RTAO image does not depend on it; HRTAO's only through which pixel of a cell claims which of
    /// its sequence's rays, as any run's atomics decide. Takes effect with the next recorded frame.
    pub fn set_max_rays_per_dispatch(&mut self, rays: u64) {
        self.max_rays_per_dispatch = rays.max(1);
    }

    /// The dispatches, other commands and barriers the last recorded frame consists of, in order.
    pub fn last_frame_events(&self) -> &[Event] {
        &self.last_events
    }

    /// Frames rendered so far (the hash map's clock).
    pub fn frame_index(&self) -> u32 {
        self.frame_index
    }

    /// The last frame's cache lifetime in frames: a cell it did not use and last used more than this many
    /// frames before it was older than `cache_lifetime_s` (`hash_map::FrameClock`).
    pub fn lifetime_frames(&self) -> u32 {
        self.map.lifetime_frames()
    }
}
