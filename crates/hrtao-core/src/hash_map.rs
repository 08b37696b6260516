//! The world-space hash map (paper §1) and everything that decides what its cells mean, in one owner: the cells
//! buffer and its capacity, the F its keys carry (eq. 6), the local-edit region epochs (ours, `regions.rs`),
//! emptying it, whether it is young, how the cell finder fills it, its occupancy (`load`) and how long its cells
//! live (`lifetime`). The renderer asks it; the shaders reach it through `FrameGlobals::hash_cells`.
use std::sync::Arc;
use std::time::{Duration, Instant};

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::Result;
use crate::gpu::HashCell;
use crate::regions::RegionTable;
use crate::settings::AoSettings;

pub mod lifetime;
pub mod load;

pub use lifetime::{FrameClock, NO_AGE_LIMIT};
pub use load::TableLoad;

/// The map counts as young in frames after one whose cells took at least 1/this of its budget (`young`).
const YOUNG_CELL_RAYS_DEN: u64 = 4;
/// `last_cell_rays` of an empty map: its next frame is young.
const NEW_MAP: (u64, u64) = (u64::MAX, 0);

pub struct WorldHashMap {
    gpu: Arc<Gpu>,
    /// Allocated with the capacity of the first frame's settings, again when a frame's capacity differs.
    cells: Option<(u32, Buffer)>,
    /// Sky light: each cell's transfer sums (`gpu::SKY_COEFFS` int64 per slot, shaders/sky.glsl), made while
    /// the sky light is on (`ensure_sky`), dropped with the cells.
    sky: Option<Buffer>,
    /// `frame_index` of the first frame rendered with the current key F (eq. 6).
    f_start_frame: u32,
    /// The F cells are keyed with (eq. 6): the scene's F (plus section changes) after a global change, plus
    /// `settings_f`; local edits leave it and bump region epochs instead (`regions`).
    key_f: u32,
    /// Settings changes that invalidated the whole map (`Invalidates::WholeMap`): added to the F cells are keyed
    /// with, so that key F values only ever grow and a key never reverts to one of before such a change.
    settings_f: u32,
    pub(crate) regions: RegionTable,
    /// The table's use at the end of the last frame: free slots first or stale ones, one cell finder pass or
    /// one per level.
    load: TableLoad,
    /// The times of recent frames, which turn the cache lifetime into a frame age (eq. 6's lazy removal).
    clock: FrameClock,
    /// The origin of frame times that a frame does not give (`FrameDesc::time`): the monotonic clock.
    started: Instant,
    /// This frame's age in frames past which a cell may be reclaimed (`FrameGlobals::lifetime_frames`).
    lifetime_frames: u32,
    /// Rays the cells took in the last finished frame (u64::MAX before the first), and that frame's ray
    /// budget: see `young`.
    last_cell_rays: (u64, u64),
}

impl WorldHashMap {
    /// No cells yet: the first frame's settings give the capacity.
    pub fn new(gpu: &Arc<Gpu>) -> Result<WorldHashMap> {
        Ok(WorldHashMap {
            gpu: gpu.clone(),
            cells: None,
            sky: None,
            f_start_frame: 0,
            key_f: 0,
            settings_f: 0,
            regions: RegionTable::new(gpu)?,
            load: TableLoad::default(),
            clock: FrameClock::new(),
            started: Instant::now(),
            lifetime_frames: NO_AGE_LIMIT,
            last_cell_rays: NEW_MAP,
        })
    }

    /// Capacity in cells (0 before the first frame).
    pub fn capacity(&self) -> u32 {
        self.cells.as_ref().map_or(0, |(c, _)| *c)
    }

    /// The cells' device address (0 before the first frame).
    pub fn address(&self) -> u64 {
        self.cells.as_ref().map_or(0, |(_, b)| b.address)
    }

    pub fn cells(&self) -> Option<&Buffer> {
        self.cells.as_ref().map(|(_, b)| b)
    }

    /// The F this frame's cells are keyed with (eq. 6).
    pub fn key_f(&self) -> u32 {
        self.key_f
    }

    /// The key F a frame of `effective_f` would use after a whole-map change that is not a setting's.
    pub fn key_f_after_change(&self, effective_f: u32) -> u32 {
        effective_f.wrapping_add(self.settings_f)
    }

    pub fn f_start_frame(&self) -> u32 {
        self.f_start_frame
    }

    /// The map with `capacity` cells: the one in use, else a new empty one (eq. 6's map is world space and
    /// survives everything else). A new map empties `stats` too (its occupancy counter restarts).
    pub fn ensure(&mut self, capacity: u32, stats: &Buffer) -> Result<()> {
        if self.capacity() == capacity && self.cells.is_some() {
            return Ok(());
        }
        self.gpu.wait_idle();
        self.cells = None;
        self.sky = None;
        let cells = Buffer::new(
            &self.gpu,
            "hash map cells",
            capacity as u64 * std::mem::size_of::<HashCell>() as u64,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        self.fill_zero(Some(cells.raw), stats)?;
        self.cells = Some((capacity, cells));
        self.load = TableLoad::empty(capacity);
        self.last_cell_rays = NEW_MAP;
        Ok(())
    }

    /// Sky light: the cells' transfer sums, made (zeroed) on first use for the map's capacity. A cell's sums are
    /// emptied when a key claims it, as its counters are.
    pub fn ensure_sky(&mut self) -> Result<()> {
        if self.sky.is_some() {
            return Ok(());
        }
        let sky = Buffer::new(
            &self.gpu,
            "sky transfer sums",
            self.capacity().max(1) as u64 * crate::gpu::SKY_COEFFS as u64 * 8,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        let device = &self.gpu.device;
        self.gpu
            .run_commands(|cmd| unsafe { device.cmd_fill_buffer(cmd, sky.raw, 0, vk::WHOLE_SIZE, 0) })?;
        self.sky = Some(sky);
        Ok(())
    }

    /// The sky sums' address (0 while there are none).
    pub fn sky_address(&self) -> u64 {
        self.sky.as_ref().map_or(0, |b| b.address)
    }

    /// Empties the map (all cached AO is forgotten) and its occupancy counter in `stats`.
    pub fn clear(&mut self, stats: &Buffer) -> Result<()> {
        self.gpu.wait_idle();
        self.fill_zero(self.cells.as_ref().map(|(_, b)| b.raw), stats)?;
        self.regions.reset();
        self.load = TableLoad::empty(self.capacity());
        self.last_cell_rays = NEW_MAP;
        Ok(())
    }

    fn fill_zero(&self, cells: Option<vk::Buffer>, stats: &Buffer) -> Result<()> {
        let device = &self.gpu.device;
        self.gpu.run_commands(|cmd| unsafe {
            if let Some(cells) = cells {
                device.cmd_fill_buffer(cmd, cells, 0, vk::WHOLE_SIZE, 0);
            }
            device.cmd_fill_buffer(cmd, stats.raw, 0, vk::WHOLE_SIZE, 0);
        })
    }

    /// Every cell invalidated from `frame_index` on (eq. 6): keys carry a new F, `effective_f` plus the
    /// settings changes so far (one more when `by_settings`). New region grids for `settings` only here: epochs
    /// back at 0 under the same F would give cells their pre-edit keys back.
    pub fn rekey(&mut self, effective_f: u32, by_settings: bool, frame_index: u32, settings: &AoSettings) {
        if by_settings {
            self.settings_f = self.settings_f.wrapping_add(1);
        }
        self.key_f = effective_f.wrapping_add(self.settings_f);
        self.f_start_frame = frame_index;
        self.last_cell_rays = NEW_MAP;
        let m = &settings.map;
        let l = RegionTable::region_lod_for(
            m.ao_radius * crate::settings::MAX_CELL_FRACTION,
            crate::hash::log2_s_min(m.s_min),
        );
        if l != self.regions.region_lod {
            self.regions.region_lod = l;
            self.regions.reset();
        }
    }

    /// A local edit: the cells within `reach` of `boxes` get new region epochs. False when the region table
    /// cannot take them (the caller re-keys the whole map).
    pub fn invalidate_regions(
        &mut self,
        boxes: &[(glam::Vec3, glam::Vec3)],
        reach: f32,
        frame_index: u32,
    ) -> bool {
        self.regions.invalidate(boxes, reach, frame_index)
    }

    /// Whether the map is young this frame: new, re-keyed (eq. 6), or its cells still take many rays (in the
    /// last frame at least 1/YOUNG_CELL_RAYS_DEN of the budget: a new view, the first still frames). Our
    /// first-frame additions (`crate::additions`) run only then. In a navigation frame a few newly seen cells
    /// take rays, and in a late still frame the pixels' own: they trace as in the paper, one dispatch of
    /// first-hit queries.
    pub fn young(&self, frame_index: u32) -> bool {
        let (cell_rays, budget) = self.last_cell_rays;
        self.f_start_frame == frame_index || cell_rays.saturating_mul(YOUNG_CELL_RAYS_DEN) >= budget
    }

    /// Frame `frame_index` starts at `time` (`FrameDesc::time`; None: now on the monotonic clock): the cells
    /// it may reclaim for their age are those last used more than `lifetime_s` seconds before it (eq. 6's lazy
    /// removal, in time: `lifetime`), or a fraction of it while inserts fail (`TableLoad::lifetime_fraction`).
    pub fn begin_frame(&mut self, frame_index: u32, time: Option<Duration>, lifetime_s: f32) {
        let time = time.unwrap_or_else(|| self.started.elapsed());
        let lifetime_s = lifetime_s as f64;
        let full = self
            .clock
            .lifetime_frames(frame_index, time.as_secs_f64(), lifetime_s);
        let fraction = self.load.lifetime_fraction();
        self.lifetime_frames = if fraction < 1.0 {
            self.clock.frames_within(frame_index, lifetime_s * fraction)
        } else {
            full
        };
    }

    /// This frame's age in frames past which a cell may be reclaimed (`begin_frame`).
    pub fn lifetime_frames(&self) -> u32 {
        self.lifetime_frames
    }

    /// Whether this frame's inserts take the free slot ending their probe run before a stale one
    /// (`TableLoad::has_room`, `FLAG_MAP_HAS_ROOM`).
    pub fn has_room(&self) -> bool {
        self.load.has_room()
    }

    /// The cell finder's dispatches as (coarsest, finest) level ranges (paper §4) for a frame of `pixels`
    /// pixels with feature size `s_p` (eq. 2): one pass over every level, or one per level, coarsest first,
    /// when probe runs may be full (`TableLoad::crowded`).
    pub fn cell_levels(&self, frame_index: u32, pixels: u32, s_p: f32) -> Vec<(u32, u32)> {
        let first_of_f = self.f_start_frame == frame_index;
        self.load.cell_levels(frame_index, first_of_f, pixels, s_p)
    }

    /// What the finished frame `frame_index` (counted after it) did to the map: the rays its cells took of its
    /// budget (youth), the slots taken at its end and its longest probe run, and whether an insert failed (the
    /// cell finder goes level by level for a while).
    pub fn finish_frame(
        &mut self,
        frame_index: u32,
        cell_rays: u64,
        budget: u64,
        occupied: u32,
        longest_probe: u32,
        failed_inserts: bool,
    ) {
        self.load
            .finish_frame(frame_index, occupied, longest_probe, failed_inserts);
        self.last_cell_rays = (cell_rays, budget);
    }
}
