//! The frame: per-resolution targets, the persistent world-space hash map, and the pass sequence
//! primary visibility → (per-pixel RTAO | cell finder → ray-tracing update → per-pixel AO → filter) → composite.
use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::accel::SceneGpu;
use crate::barrier::{Event, Stage, Use};
use crate::buffer::{host_read_barrier, Buffer};
use crate::camera::{Camera, Projection};
use crate::context::Gpu;
use crate::error::{CoreError, Result};
use crate::gpu::{
    self, FilterGuide, FrameGlobals, FrameStats, GPixel, HashCell, HashTestCase, PixelAccum, PixelCells,
    PixelRays,
};
use crate::pass::{Pass, PassSet, Recorder, Resource};
use crate::raster::{Primary, Rasterizer};
use crate::regions::RegionTable;
use crate::settings::{AoSettings, Invalidates, Mode};
use crate::tile::Tile;
use crate::timer::GpuTimer;

/// Buffers whose size follows the image resolution.
struct Targets {
    width: u32,
    height: u32,
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
    obscurance: Buffer,
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
            gbuffer: b("G-buffer", n * std::mem::size_of::<GPixel>() as u64)?,
            ao: b("AO", n * 4)?,
            lod_used: b("LOD used", n * 4)?,
            filter_plan: b("filter plan", n * 4)?,
            filter_guide: b("filter guide", n * std::mem::size_of::<FilterGuide>() as u64)?,
            filter_tmp: b("filter ping-pong", n * 4)?,
            pixel_rays: b("pixel rays", n * std::mem::size_of::<PixelRays>() as u64)?,
            accum: b("still accumulation", n * std::mem::size_of::<PixelAccum>() as u64)?,
            bias_evidence: b("own-ray residuals", 2 * n * 16)?,
            output: b("output RGBA8", n * 4)?,
            pixel_cells: b("pixel cells", n * std::mem::size_of::<PixelCells>() as u64)?,
            ray_queue: b("ray queue", n * 4)?,
            filter_queue: b("filter queue", n * 4)?,
            obscurance: b("obscurance", n * 4)?,
        })
    }
}

/// Scenes drawing more instanced triangles than this keep ray queries without a raster trial in
/// `Renderer::pick_primary`: rasterising costs in proportion to the triangles (hundreds of millions in massive
/// instanced scenes), while ray queries scale with the pixels.
pub const RASTER_TRIAL_TRIANGLES: u64 = 20_000_000;

/// Feature-edge line width in view pixels: lines keep it at any internal resolution (render scale, screenshots
/// larger than the view).
pub const EDGE_WIDTH: f32 = 1.0;

/// Frames the cell finder stays level by level after a failed insert (`Renderer::cell_levels`).
const LEVELWISE_FRAMES: u32 = 64;
/// The map counts as young in frames after one whose cells took at least 1/this of its budget (`young_map`).
const YOUNG_CELL_RAYS_DEN: u64 = 4;
/// `Renderer::last_cell_rays` of an empty map: its next frame is young.
const NEW_MAP: (u64, u64) = (u64::MAX, 0);

/// Still frames with jitter before an image counts as anti-aliased.
pub const AA_FRAMES: u32 = 16;

/// What must stay equal for frames to accumulate into one still image (settings: up to changes that invalidate
/// nothing, `AoSettings::invalidates`).
#[derive(Clone)]
struct StillKey {
    camera: Camera,
    settings: AoSettings,
    scene_f: u32,
    tlas: vk::AccelerationStructureKHR,
    scene_version: u64,
    view_height: u32,
    jitter: bool,
    primary: Primary,
    tile: Option<Tile>,
}

impl PartialEq for StillKey {
    fn eq(&self, o: &StillKey) -> bool {
        self.settings.invalidates(&o.settings) == Invalidates::Nothing
            && (self.camera, self.scene_f, self.tlas, self.scene_version)
                == (o.camera, o.scene_f, o.tlas, o.scene_version)
            && (self.view_height, self.jitter, self.primary, self.tile)
                == (o.view_height, o.jitter, o.primary, o.tile)
    }
}

/// The world-space hash map (paper §1), persistent across frames.
struct HashMapGpu {
    capacity: u32,
    cells: Buffer,
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
}

pub struct Renderer {
    gpu: Arc<Gpu>,
    pub settings: AoSettings,
    passes: PassSet,
    timer: Option<GpuTimer>,
    globals: Buffer,
    /// `FrameStats` in device memory (the shaders' atomics stay on the GPU), and its host-visible copy made once
    /// at the end of every frame.
    stats: Buffer,
    stats_readback: Buffer,
    /// VkDispatchIndirectCommands of the ray-tracing update and the filter, written by the last work group of the cell finder and of the resolve
    /// (queue_args.glsl).
    dispatch_args: Buffer,
    targets: Targets,
    hash: HashMapGpu,
    /// Monotonic count of rendered frames (a hash cell's "last used" stamp).
    frame_index: u32,
    /// Frames since the view last changed (0 = new view).
    still_index: u32,
    still_key: Option<StillKey>,
    /// F of the previous frame, and the frame_index of the first frame rendered with it (eq. 6).
    last_f: Option<(u32, u32)>,
    f_start_frame: u32,
    /// The F cells are keyed with (eq. 6): the scene's F after a global change; local edits leave it and
    /// bump region epochs instead (`regions`).
    key_f: u32,
    /// Settings changes that invalidated the whole map (`Invalidates::WholeMap`): added to the F cells are keyed
    /// with, so that key F values only ever grow and a key never reverts to one of before such a change.
    settings_f: u32,
    regions: RegionTable,
    /// `still_index` at the last local edit: pixels near it restarted their refinement then.
    edit_still_index: u32,
    /// The last finished frame reported `converged`.
    last_converged: bool,
    /// Until this frame the cell finder runs level by level (the map was full somewhere, see `cell_levels`).
    levelwise_until: u32,
    /// Rays the cells took in the last finished frame (u64::MAX before the first), and that frame's ray
    /// budget: see `young_map`.
    last_cell_rays: (u64, u64),
    /// Jitter the primary samples of still frames (anti-aliasing). `hrtao render` keeps pixel centres.
    pub jitter: bool,
    /// Height of the view in pixels when the renderer works at a reduced internal resolution (0 = the internal
    /// height): s_p is measured in view pixels, so cells do not change with the render scale.
    pub view_height: u32,
    pub background_top: [f32; 3],
    pub background_bottom: [f32; 3],
    pub output_bgra: bool,
    pub check_bounds: bool,
    /// How primary visibility is found (ray queries by default).
    pub primary: Primary,
    /// Created on the first rasterised frame.
    raster: Option<Rasterizer>,
    /// The commands and barriers the last `record_frame` recorded.
    last_events: Vec<Event>,
    /// Render this window of a larger image (large screenshots); None = the camera's whole image. Both primary
    /// visibilities draw tiles (the rasteriser as an off-axis frustum).
    pub tile: Option<Tile>,
}

impl Renderer {
    pub fn new(gpu: &Arc<Gpu>, width: u32, height: u32, settings: AoSettings) -> Result<Renderer> {
        settings.validate().map_err(CoreError::Invalid)?;
        let globals = Buffer::new(
            gpu,
            "frame globals",
            std::mem::size_of::<FrameGlobals>() as u64,
            MemoryLocation::CpuToGpu,
            vk::BufferUsageFlags::empty(),
        )?;
        let stats = Buffer::new(
            gpu,
            "frame stats",
            std::mem::size_of::<FrameStats>() as u64,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        let stats_readback = Buffer::new(
            gpu,
            "frame stats readback",
            std::mem::size_of::<FrameStats>() as u64,
            MemoryLocation::GpuToCpu,
            vk::BufferUsageFlags::empty(),
        )?;
        let dispatch_args = Buffer::new(
            gpu,
            "dispatch args",
            gpu::DISPATCH_ARGS_WORDS as u64 * 4,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::INDIRECT_BUFFER,
        )?;
        let passes = PassSet::new(gpu, &globals)?;
        let hash = Self::create_hash(gpu, settings.hash_capacity)?;
        let mut r = Renderer {
            gpu: gpu.clone(),
            timer: GpuTimer::new(gpu)?,
            passes,
            globals,
            stats,
            stats_readback,
            dispatch_args,
            targets: Targets::new(gpu, width.max(1), height.max(1))?,
            hash,
            settings,
            frame_index: 0,
            still_index: 0,
            still_key: None,
            last_f: None,
            f_start_frame: 0,
            key_f: 0,
            settings_f: 0,
            regions: RegionTable::new(gpu)?,
            edit_still_index: 0,
            last_converged: false,
            levelwise_until: 0,
            last_cell_rays: NEW_MAP,
            jitter: false,
            view_height: 0,
            background_top: [0.62, 0.68, 0.76],
            background_bottom: [0.93, 0.94, 0.95],
            output_bgra: false,
            check_bounds: false,
            primary: Primary::default(),
            raster: None,
            last_events: Vec::new(),
            tile: None,
        };
        gpu.run_commands(|cmd| unsafe {
            gpu.device.cmd_fill_buffer(cmd, r.stats.raw, 0, vk::WHOLE_SIZE, 0);
            gpu.device
                .cmd_fill_buffer(cmd, r.stats_readback.raw, 0, vk::WHOLE_SIZE, 0);
        })?;
        r.sync_region_size();
        Ok(r)
    }

    /// Region grids for the current settings (`RegionTable::region_lod`); new grids forget local edits. Only
    /// with a new F (`invalidate_map`, or before the first frame): epochs back at 0 under the same F would
    /// give cells their pre-edit keys back.
    fn sync_region_size(&mut self) {
        let s = &self.settings;
        let l = RegionTable::region_lod_for(
            s.ao_radius * s.max_cell_fraction,
            crate::hash::log2_s_min(s.s_min),
        );
        if l != self.regions.region_lod {
            self.regions.region_lod = l;
            self.regions.reset();
        }
    }

    /// Invalidates every cell of the map (eq. 6, as a global edit does): the next frame keys cells with a new
    /// F, never used before, and the old cells become reclaimable.
    fn invalidate_map(&mut self) {
        self.settings_f = self.settings_f.wrapping_add(1);
        if let Some((f, sections)) = self.last_f {
            self.key_f = f.wrapping_add(sections).wrapping_add(self.settings_f);
            self.f_start_frame = self.frame_index;
        }
        self.last_cell_rays = NEW_MAP;
    }

    /// The LOD setting the grids of the local-edit region table (`RegionTable::region_lod`).
    pub fn region_lod(&self) -> i32 {
        self.regions.region_lod
    }

    fn create_hash(gpu: &Arc<Gpu>, capacity: u32) -> Result<HashMapGpu> {
        let cells = Buffer::new(
            gpu,
            "hash map cells",
            capacity as u64 * std::mem::size_of::<HashCell>() as u64,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        gpu.run_commands(|cmd| unsafe {
            gpu.device.cmd_fill_buffer(cmd, cells.raw, 0, vk::WHOLE_SIZE, 0);
        })?;
        Ok(HashMapGpu { capacity, cells })
    }

    pub fn gpu(&self) -> &Arc<Gpu> {
        &self.gpu
    }

    pub fn size(&self) -> (u32, u32) {
        (self.targets.width, self.targets.height)
    }

    /// Changes the internal resolution (the hash map is world space and survives).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        let (w, h) = (width.max(1), height.max(1));
        if (w, h) != self.size() {
            self.gpu.wait_idle();
            self.targets = Targets::new(&self.gpu, w, h)?;
            self.still_key = None;
        }
        Ok(())
    }

    /// Applies new settings, invalidating what their change invalidates (`AoSettings::invalidates`): the whole
    /// map gets a new F (a new hash capacity reallocates and empties it); the still image restarts at the next
    /// frame unless nothing shown changed.
    pub fn set_settings(&mut self, settings: AoSettings) -> Result<()> {
        settings.validate().map_err(CoreError::Invalid)?;
        let whole_map = self.settings.invalidates(&settings) == Invalidates::WholeMap;
        if settings.hash_capacity != self.hash.capacity {
            self.gpu.wait_idle();
            self.hash = Self::create_hash(&self.gpu, settings.hash_capacity)?;
            self.gpu.run_commands(|cmd| unsafe {
                // The occupancy counter restarts with the empty table.
                self.gpu
                    .device
                    .cmd_fill_buffer(cmd, self.stats.raw, 0, vk::WHOLE_SIZE, 0);
            })?;
            self.last_cell_rays = NEW_MAP;
        }
        self.settings = settings;
        if whole_map {
            self.invalidate_map();
            self.sync_region_size();
        }
        Ok(())
    }

    /// Empties the hash map (all cached AO is forgotten).
    pub fn clear_cache(&mut self) -> Result<()> {
        self.gpu.wait_idle();
        let (cells, stats) = (self.hash.cells.raw, self.stats.raw);
        self.gpu.run_commands(|cmd| unsafe {
            self.gpu.device.cmd_fill_buffer(cmd, cells, 0, vk::WHOLE_SIZE, 0);
            self.gpu.device.cmd_fill_buffer(cmd, stats, 0, vk::WHOLE_SIZE, 0);
        })?;
        self.regions.reset();
        self.last_cell_rays = NEW_MAP;
        Ok(())
    }

    fn globals_for(&self, camera: &Camera, key_f: u32) -> FrameGlobals {
        let s = &self.settings;
        let t = &self.targets;
        let cam = Camera {
            width: t.width,
            height: t.height,
            ..*camera
        };
        let (f, view_height, (top, bottom)) = match self.tile {
            // A tile: the full image's rays, cells sized for the full image's pixels.
            Some(tile) => (
                tile.frame(
                    &Camera {
                        width: tile.full.0,
                        height: tile.full.1,
                        ..*camera
                    }
                    .frame(),
                    (t.width, t.height),
                    camera.is_orthographic(),
                ),
                tile.full.1,
                tile.gradient(self.background_top, self.background_bottom, t.height),
            ),
            None => (
                cam.frame(),
                t.height,
                (self.background_top, self.background_bottom),
            ),
        };
        let view_height = if self.view_height > 0 {
            self.view_height
        } else {
            view_height
        };
        let feature_size = crate::hash::FeatureSize::for_camera(&cam, view_height, s.s_p);
        let mut flags = 0;
        if self.output_bgra {
            flags |= gpu::FLAG_OUTPUT_BGRA;
        }
        if s.filter && s.filter_iterations > 0 {
            flags |= gpu::FLAG_FILTER;
        }
        if self.check_bounds {
            flags |= gpu::FLAG_CHECK_BOUNDS;
        }
        if s.shaded {
            flags |= gpu::FLAG_SHADED;
        }
        if s.refine {
            flags |= gpu::FLAG_REFINE;
        }
        if s.edges {
            flags |= gpu::FLAG_EDGES;
        }
        if self.regions.any_edit() {
            flags |= gpu::FLAG_REGION_EPOCHS;
        }
        if self.young_map() {
            flags |= gpu::FLAG_YOUNG_MAP;
            if s.near_weight > 0.0 {
                flags |= gpu::FLAG_NEAR_FIELD;
            }
        }
        let jitter = if self.jitter && s.accumulates() && self.still_index > 0 {
            // R2 points in the pixel, frame after frame (the centre first).
            let i = self.still_index as f64;
            [
                ((0.7548776662466927 * i).fract() - 0.5) as f32,
                ((0.5698402909980532 * i).fract() - 0.5) as f32,
            ]
        } else {
            [0.0, 0.0]
        };
        let v4 = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        let c4 = |c: [f32; 3]| [c[0], c[1], c[2], 1.0];
        FrameGlobals {
            eye: v4(f.eye),
            cam_u: v4(f.u),
            cam_v: v4(f.v),
            cam_w: v4(f.w),
            jitter,
            width: t.width,
            height: t.height,
            still_index: self.still_index,
            scene_f: key_f,
            frame_index: self.frame_index,
            f_start_frame: self.f_start_frame,
            mode: s.mode.gpu_value(),
            flags,
            rays_per_pixel: s.rays_per_pixel,
            ao_radius: s.ao_radius,
            s_w_per_distance: feature_size.per_distance,
            s_w_max: s.ao_radius * s.max_cell_fraction,
            log2_s_min: crate::hash::log2_s_min(s.s_min),
            s_nd: s.s_nd,
            hash_capacity: self.hash.capacity,
            max_samples: s.max_samples,
            min_samples: s.min_samples,
            max_probe: s.max_probe,
            stale_frames: s.stale_frames,
            filter_iterations: s.filter_iterations,
            prior_rays: s.prior_rays,
            prior_rays_max: s.prior_rays_max,
            prior_sigma: s.prior_sigma,
            filter_sigma: s.filter_sigma,
            region_lod: self.regions.region_lod,
            crease_cos: s.crease_deg.to_radians().cos(),
            background_top: c4(top),
            background_bottom: c4(bottom),
            gbuffer: t.gbuffer.address,
            instances: 0,
            geometries: 0,
            ao: t.ao.address,
            lod_used: t.lod_used.address,
            filter_plan: t.filter_plan.address,
            filter_guide: t.filter_guide.address,
            filter_tmp: t.filter_tmp.address,
            pixel_rays: t.pixel_rays.address,
            accum: t.accum.address,
            output_rgba: t.output.address,
            hash_cells: self.hash.cells.address,
            pixel_cells: t.pixel_cells.address,
            stats: self.stats.address,
            ray_queue: t.ray_queue.address,
            filter_queue: t.filter_queue.address,
            dispatch_args: self.dispatch_args.address,
            regions: self.regions.address(),
            projection: match cam.projection {
                Projection::Perspective => gpu::PROJECTION_PERSPECTIVE,
                Projection::Orthographic => gpu::PROJECTION_ORTHOGRAPHIC,
            },
            s_w_base: feature_size.base,
            view_height,
            edge_width: EDGE_WIDTH,
            section0: [0.0; 4],
            section1: [0.0; 4],
            section2: [0.0; 4],
            section_count: 0,
            residual_sigma: s.residual_sigma,
            still_smoothing: s.still_smoothing,
            pooled_residual: s.pooled_residual,
            cell_gradient: s.cell_gradient,
            contact_detail: s.contact_detail,
            obscurance: t.obscurance.address,
            trace_fraction: s.trace_fraction,
            level_blend: s.level_blend,
            bias_evidence: t.bias_evidence.address,
            near_weight: s.near_weight,
            near_fraction: s.near_fraction,
            normal_offset: s.normal_offset,
            pad0: 0,
        }
    }

    fn still_key_for(&self, scene: &SceneGpu, scene_f: u32, camera: &Camera) -> StillKey {
        let scene_f = Self::effective_f(scene, scene_f);
        StillKey {
            camera: Camera {
                width: self.targets.width,
                height: self.targets.height,
                ..*camera
            },
            settings: self.settings.clone(),
            scene_f,
            tlas: scene.tlas.raw,
            scene_version: scene.version(),
            view_height: self.view_height,
            jitter: self.jitter,
            primary: self.primary,
            tile: self.tile,
        }
    }

    /// True when the output buffer already holds the final image of this view: the last frame converged and
    /// nothing it depends on (camera, size, settings, scene, instances) has changed since. A viewer can then
    /// present the output again instead of rendering (expose events, UI repaints).
    pub fn shows_final(&self, scene: &SceneGpu, scene_f: u32, camera: &Camera) -> bool {
        self.last_converged && self.still_key.as_ref() == Some(&self.still_key_for(scene, scene_f, camera))
    }

    /// The F the frame hashes with (eq. 6): the caller's, plus one per section plane change, since moving a
    /// plane changes the AO as an edit does. Both only grow, so the sum changes whenever either does.
    pub fn effective_f(scene: &SceneGpu, scene_f: u32) -> u32 {
        scene_f.wrapping_add(scene.section_changes())
    }

    /// Prepares the frame's globals and records all passes into `cmd` (the caller submits and then calls
    /// `finish_frame`). The output is left in `output_buffer()`.
    pub fn record_frame(
        &mut self,
        cmd: vk::CommandBuffer,
        scene: &SceneGpu,
        scene_f: u32,
        camera: &Camera,
    ) -> Result<()> {
        let local_edit = self.scene_changed(scene, scene_f);
        let key = self.still_key_for(scene, scene_f, camera);
        if local_edit {
            // A local edit keeps the still accumulation of the view; composite.comp restarts it only in the
            // edited regions.
            if let Some(k) = self.still_key.as_mut() {
                k.scene_f = key.scene_f;
                k.tlas = key.tlas;
                k.scene_version = key.scene_version;
            }
        }
        if self.still_key.as_ref() == Some(&key) {
            self.still_index = self.still_index.saturating_add(1);
        } else {
            self.still_index = 0;
            self.still_key = Some(key);
        }
        if local_edit || self.still_index == 0 {
            self.edit_still_index = self.still_index;
        }
        self.regions.upload()?;
        let mut globals = self.globals_for(camera, self.key_f);
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
        self.globals.write(&[globals])?;
        self.passes.bind_tlas(scene.tlas.raw, scene.tlas_generation());

        let (w, h) = self.size();
        let primary = self.primary;
        if primary == Primary::Raster {
            let raster = match &mut self.raster {
                Some(r) => r,
                None => self.raster.insert(Rasterizer::new(&self.gpu)?),
            };
            raster.prepare(w, h)?;
        }
        let mode = self.settings.mode;
        let cell_levels = self.cell_levels();
        let young = self.young_map();
        let adaptive_split = self.settings.adaptive_rays && young;
        let mut rec = Recorder::new(&self.gpu, cmd, &self.passes, self.timer.as_mut());
        match (primary, &self.raster) {
            (Primary::Raster, Some(raster)) => {
                // A perspective tile is an off-axis part of the full image's frustum: the full image's axis,
                // moved by the tile's centre (an orthographic tile moves its eye instead, as its rays do).
                let off_axis = match self.tile {
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
                );
            }
            _ => rec.dispatch(Pass::Primary, w, h, [0; 4]),
        }
        let contact_detail = mode.uses_hash() && self.settings.contact_detail > 0.0 && young;
        if contact_detail {
            // Contact detail's obscurance reads only the G-buffer: beside the cell finder, after one barrier.
            rec.dispatch(Pass::Obscurance, w, h, [0; 4]);
        }
        if mode == Mode::Rtao {
            rec.dispatch(Pass::Rtao, w, h, [0; 4]);
        } else if mode.uses_hash() {
            // The last cell-finder dispatch also queues the pixels whose cell still takes rays, packed densely
            // (the update then runs no idle lanes), and its last work group writes the update's dispatch size.
            for &(top, bottom) in &cell_levels {
                rec.dispatch(Pass::CellFinder, w, h, [top, bottom, 0, 0]);
            }
            let rays = gpu::RAY_ARGS_OFFSET;
            let args = self.dispatch_args.raw;
            if adaptive_split {
                // Adaptive sampling (ours): a quarter of the budget, the weights, the rest shared by them.
                for phase in 1..=3 {
                    rec.dispatch_indirect(Pass::AoUpdate, args, rays, [phase, 0, 0, 0]);
                }
            } else {
                rec.dispatch_indirect(Pass::AoUpdate, args, rays, [0; 4]);
            }
            rec.dispatch(Pass::Resolve, w, h, [0; 4]);
            let iterations = self.settings.filter_iterations;
            if self.settings.filter && iterations > 0 {
                // Over the pixels the resolve queued (those whose plan takes an iteration). Ping-pong:
                // iteration i reads one buffer and writes the other; an even count ends in `ao`. The resolve's
                // last work group wrote the queue's dispatch size.
                let filter = gpu::FILTER_ARGS_OFFSET;
                for i in 0..iterations {
                    rec.dispatch_indirect(Pass::Filter, args, filter, [i, iterations, 0, 0]);
                }
            }
            if self.settings.pooled_residual > 0.0 && young {
                // Over the pixels that traced into their cells (the ray queue), while the map is young.
                rec.dispatch_indirect(Pass::Residual, args, rays, [0; 4]);
            }
            if contact_detail {
                // Contact detail (ours): over the ray queue the fit of its gain to this frame's rays and the
                // correction (detail.comp's two phases), from the obscurance found after primary visibility.
                for phase in 1..=2 {
                    rec.dispatch_indirect(Pass::Detail, args, rays, [phase, 0, 0, 0]);
                }
            }
        }
        // The frame's counters, once, for `finish_frame`: composite.comp counts nothing (its declaration
        // writes no `Stats`), so the copy is recorded before it and shares its barrier.
        let bytes = std::mem::size_of::<FrameStats>() as u64;
        let (stats, readback) = (self.stats.raw, self.stats_readback.raw);
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
        rec.dispatch(Pass::Composite, w, h, [0; 4]);
        self.last_events = rec.finish();
        Ok(())
    }

    /// Follows the scene's F (eq. 6). Returns true for a local edit: the change is located
    /// (`SceneGpu::changes_between`), `local_edits` is on and the regions within reach of it (R plus a region,
    /// so every cell whose AO can change) got new epochs; cells elsewhere keep their keys. Otherwise, as the
    /// paper does, the new F re-keys every cell and the old ones become reclaimable.
    fn scene_changed(&mut self, scene: &SceneGpu, scene_f: u32) -> bool {
        let now = (scene_f, scene.section_changes());
        let last = self.last_f.replace(now);
        if last == Some(now) {
            return false;
        }
        if let Some((f0, sections0)) = last {
            // Located edits and plane moves: only the regions within reach of them.
            let located = scene.changes_between(f0, scene_f).and_then(|mut boxes| {
                boxes.extend(scene.section_changes_between(sections0, now.1)?);
                Some(boxes)
            });
            if let (true, Some(boxes)) = (self.settings.local_edits, located) {
                if self
                    .regions
                    .invalidate(&boxes, self.settings.ao_radius, self.frame_index)
                {
                    return true;
                }
            }
        }
        self.key_f = Self::effective_f(scene, scene_f).wrapping_add(self.settings_f);
        self.f_start_frame = self.frame_index;
        false
    }

    /// The cell finder's dispatches as (coarsest, finest) level ranges (paper §4). While the map has room every
    /// level is found in one pass over the pixels. Where it may not (more pixels than half the capacity: cells
    /// claimed in a frame stay live for `stale_frames`, so the first frame decides), and for LEVELWISE_FRAMES
    /// frames after an insert failed, one dispatch per level, coarsest first: the coarse cells, shared by many
    /// pixels, then take the free slots before any finer one, and pixels whose fine cells fail fall back to them.
    fn cell_levels(&self) -> Vec<(u32, u32)> {
        let top = gpu::LOD_COUNT - 1;
        let crowded = self.pixel_count() as u64 > self.hash.capacity as u64 / 2;
        // Frame numbers wrap: compare their difference.
        if crowded || (self.levelwise_until.wrapping_sub(self.frame_index) as i32) > 0 {
            (0..=top).rev().map(|l| (l, l)).collect()
        } else {
            vec![(top, 0)]
        }
    }

    /// Whether the map is young this frame: new, re-keyed (eq. 6), or its cells still take many rays (in the
    /// last frame at least 1/YOUNG_CELL_RAYS_DEN of the budget: a new view, the first still frames). Our
    /// first-frame additions run only then: adaptive sampling's three dispatches (`adaptive_rays`), the
    /// near-field control variate's ray classification (`near_weight`), the pooled residual
    /// (`pooled_residual`) and contact detail (`contact_detail`). In a navigation frame a few newly seen
    /// cells take rays, and in a late still frame the pixels' own: they trace as in the paper, one dispatch of
    /// first-hit queries.
    fn young_map(&self) -> bool {
        let (cell_rays, budget) = self.last_cell_rays;
        self.f_start_frame == self.frame_index || cell_rays.saturating_mul(YOUNG_CELL_RAYS_DEN) >= budget
    }

    /// Whether this frame's GPU timestamps measure its passes. Lavapipe writes the timestamps recorded after a
    /// raster pass only when the submission ends, so there every pass after raster primary visibility read about
    /// 0.1 ms in a 950 ms frame (862×800, `examples/orbit_profile`); such frames report no per-pass times.
    pub fn timestamps_measure(&self) -> bool {
        !(self.gpu.info.is_software && self.primary == Primary::Raster)
    }

    /// Reads the statistics of the frame just completed.
    pub fn finish_frame(&mut self, scene_f: u32, wall_ms: f64) -> Result<FrameReport> {
        self.frame_index = self.frame_index.wrapping_add(1);
        let stats: FrameStats = self.stats_readback.read(1)?[0];
        let c = stats.counters;
        let rays = |i: u32| stats.rays[i as usize];
        let gpu_ms = match &self.timer {
            Some(t) if self.timestamps_measure() => t.read()?,
            _ => Vec::new(),
        };
        let occupied = c[gpu::STAT_OCCUPIED as usize];
        if c[gpu::STAT_FAILED_INSERTS as usize] > 0 {
            self.levelwise_until = self.frame_index.wrapping_add(LEVELWISE_FRAMES);
        }
        let young_pixels =
            c[gpu::STAT_RAY_QUEUE as usize] as u64 + c[gpu::STAT_UNPICKED_PIXELS as usize] as u64;
        self.last_converged = self.converged(young_pixels);
        let budget = self.pixel_count() as f64
            * self.settings.rays_per_pixel as f64
            * self.settings.trace_fraction.clamp(0.0, 1.0) as f64;
        self.last_cell_rays = (rays(gpu::RAYS_CELL), budget.ceil() as u64);
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
            capped_pixels: c[gpu::STAT_CAPPED_PIXELS as usize],
            occupied_cells: occupied,
            load_factor: occupied as f64 / self.hash.capacity as f64,
            scene_f: self
                .last_f
                .map_or(scene_f, |(f, sections)| f.wrapping_add(sections)),
            map_f: self.key_f,
            accumulated_frames: self.still_index + 1,
            refine_rays: rays(gpu::RAYS_REFINE),
            cell_rays: rays(gpu::RAYS_CELL),
            ray_pixels: c[gpu::STAT_RAY_QUEUE as usize],
            filtered_pixels: c[gpu::STAT_FILTER_QUEUE as usize],
            converged: self.last_converged,
        })
    }

    /// Renders one frame headless and waits for it.
    pub fn render(&mut self, scene: &SceneGpu, scene_f: u32, camera: &Camera) -> Result<FrameReport> {
        let t0 = Instant::now();
        let gpu = self.gpu.clone();
        let mut recorded = Ok(());
        gpu.run_commands(|cmd| recorded = self.record_frame(cmd, scene, scene_f, camera))?;
        recorded?;
        self.finish_frame(scene_f, t0.elapsed().as_secs_f64() * 1e3)
    }

    /// Chooses the faster primary visibility for `scene` by measurement: a frame without AO with each, timed
    /// on the wall clock (GPU timestamps after a render pass are unreliable on lavapipe), after a warm-up frame
    /// each (the first dispatch compiles pipelines). Keeps the choice in `self.primary` and returns it with the
    /// two times in ms (ray queries, raster; NaN when a scene above `RASTER_TRIAL_TRIANGLES`, or a device that
    /// cannot rasterise it, is not tried).
    pub fn pick_primary(
        &mut self,
        scene: &SceneGpu,
        scene_f: u32,
        camera: &Camera,
    ) -> Result<(Primary, f64, f64)> {
        if let Err(e) = Rasterizer::available(&self.gpu) {
            log::info!("{e}");
            self.primary = Primary::RayQuery;
            return Ok((self.primary, f64::NAN, f64::NAN));
        }
        if scene.raster.triangles() > RASTER_TRIAL_TRIANGLES {
            self.primary = Primary::RayQuery;
            return Ok((self.primary, f64::NAN, f64::NAN));
        }
        let saved = self.settings.clone();
        self.settings.mode = Mode::NoAo;
        let time = |r: &mut Renderer, primary| -> Result<f64> {
            r.primary = primary;
            r.render(scene, scene_f, camera)?;
            Ok(r.render(scene, scene_f, camera)?.wall_ms)
        };
        let ray_query = time(self, Primary::RayQuery);
        let raster = time(self, Primary::Raster);
        self.settings = saved;
        self.still_key = None;
        let (ray_query, raster) = (ray_query?, raster?);
        self.primary = if raster < ray_query {
            Primary::Raster
        } else {
            Primary::RayQuery
        };
        Ok((self.primary, ray_query, raster))
    }

    /// Whether the frame just rendered (`still_index` frames into its view, `young_pixels` of it on
    /// cells that still take rays, traced this frame or not) is final: per-pixel RTAO and HRTAO with refinement
    /// once each pixel has `still_samples` of its own rays (and, with jitter, `AA_FRAMES` samples); the paper's
    /// HRTAO once no pixel on screen has a cell that takes rays; other modes once anti-aliased.
    fn converged(&self, young_pixels: u64) -> bool {
        let s = &self.settings;
        let frames = self.still_index + 1;
        let aa = !self.jitter || frames >= AA_FRAMES;
        let own_rays = |frames: u32| frames as u64 * s.rays_per_pixel as u64 >= s.still_samples as u64;
        match s.mode {
            Mode::Rtao => aa && (s.rays_per_pixel == 0 || own_rays(frames)),
            // Pixels near a local edit restarted their own rays then.
            Mode::Hrtao if s.refine => {
                aa && (s.rays_per_pixel == 0 || own_rays(self.still_index - self.edit_still_index))
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

    /// The composited sRGB RGBA8 image of the last frame, row 0 at the top.
    pub fn read_rgba(&self) -> Result<Vec<u8>> {
        let px: Vec<u32> = self.read_buffer(&self.targets.output, self.pixel_count())?;
        Ok(bytemuck::cast_slice(&px).to_vec())
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
        self.read_buffer(&self.hash.cells, self.hash.capacity as usize)
    }

    /// Evaluates the shaders' hash on `cases` (for the CPU-mirror test), with this renderer's s_min, s_nd and
    /// capacity. Needs a scene only for the descriptor set's TLAS binding.
    pub fn hash_on_gpu(&mut self, scene: &SceneGpu, cases: &[HashTestCase]) -> Result<Vec<HashTestCase>> {
        let buf = Buffer::from_slice(&self.gpu, "hash test cases", cases, vk::BufferUsageFlags::empty())?;
        let mut globals = self.globals_for(&Camera::default(), 0);
        const ROW: u32 = 256;
        globals.width = ROW;
        globals.height = (cases.len() as u32).div_ceil(ROW).max(1);
        self.globals.write(&[globals])?;
        self.passes.bind_tlas(scene.tlas.raw, scene.tlas_generation());
        let addr = buf.address;
        let push = [addr as u32, (addr >> 32) as u32, cases.len() as u32, 0];
        self.gpu.run_commands(|cmd| {
            let mut rec = Recorder::new(&self.gpu, cmd, &self.passes, None);
            rec.dispatch(Pass::HashTest, ROW, globals.height, push);
            rec.finish();
        })?;
        buf.read(cases.len())
    }

    /// The keys of the cells the cell finder gives a G-buffer sample at each level (a CPU mirror of
    /// cell_finder.comp for tests of the map).
    pub fn pixel_cell_keys(&self, camera: &Camera, scene_f: u32, px: &GPixel) -> [crate::hash::CellKey; 4] {
        // The F cells are keyed with: the renderer's after a local edit of this F, else `scene_f`.
        let key_f = if self.last_f.map(|l| l.0) == Some(scene_f) {
            self.key_f
        } else {
            scene_f.wrapping_add(self.settings_f)
        };
        let g = self.globals_for(camera, key_f);
        let size = crate::hash::FeatureSize {
            base: g.s_w_base,
            per_distance: g.s_w_per_distance,
        };
        let lod = crate::hash::pixel_lod(px.t, size, g.s_w_max, g.log2_s_min);
        std::array::from_fn(|level| {
            let l = lod + level as i32;
            let c = crate::hash::cell_coord(px.position.into(), l);
            let epoch = self.regions.epoch(crate::hash::region_index(c, l, g.region_lod));
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

    /// The dispatches, other commands and barriers the last recorded frame consists of, in order.
    pub fn last_frame_events(&self) -> &[Event] {
        &self.last_events
    }

    /// Frames rendered so far (the hash map's clock).
    pub fn frame_index(&self) -> u32 {
        self.frame_index
    }
}
