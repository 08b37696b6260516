//! How full the hash map's table is, as its owner knows it between frames, and the three decisions made from
//! it: whether an insert takes the free slot that ends its probe run before a stale one met on the way
//! (`has_room`, hash_map.glsl `find_or_insert`), whether the cell finder runs level by level (`cell_levels`),
//! and how much of the cache lifetime the table can keep (`lifetime_fraction`).
use crate::gpu;
use crate::settings::MAX_PROBE;

/// The table has room while at most 1/this of its slots are taken. Linear probing (§1) stays short there: an
/// unsuccessful search at load a reads about (1 + 1/(1 - a)²) / 2 slots, 2.5 at a half, 8.5 at three quarters.
pub const ROOM_DEN: u64 = 2;
/// Frames the cell finder stays level by level after a failed insert (`cell_levels`).
pub const LEVELWISE_FRAMES: u32 = 64;
/// Halvings of the cache lifetime at most under pressure (`lifetime_fraction`): down to 1/64 of it, the frame
/// clock's checkpoint interval (`hash_map::lifetime`), below which its ring cannot tell frames apart.
pub const MAX_LIFETIME_HALVINGS: u32 = 6;
/// Frames without a failed insert after which a halved lifetime doubles back.
pub const CALM_FRAMES: u32 = 16;

/// New cells a frame claims per pixel at most, about: a finest cell spans s_p/2 to s_p view pixels (eq. 2-3),
/// so a pixel holds at most (2/s_p)² of them (and never more than one), and the three coarser levels add a
/// third (1/4 + 1/16 + 1/64). The cell cap (`MapSettings::cell_cap`) can make far cells smaller: such a frame may
/// still overflow, and its failed inserts make the next frames level by level. With the default s_p = 4: 1/3.
pub fn claims_per_pixel(s_p: f32) -> f64 {
    (2.0 / s_p as f64).powi(2).min(1.0) * 4.0 / 3.0
}

/// The table's size and use at the end of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TableLoad {
    pub capacity: u32,
    /// Slots that hold a cell, live or stale (`STAT_OCCUPIED`): slots are reclaimed but never emptied, so this
    /// only grows until the map is emptied.
    pub occupied: u32,
    /// The longest probe run of the last frame (`STAT_MAX_PROBE`): how close its inserts came to failing.
    pub longest_probe: u32,
    /// Until this frame the cell finder runs level by level (an insert failed, see `cell_levels`).
    levelwise_until: Option<u32>,
    /// Times the cache lifetime is halved (`lifetime_fraction`), and frames without a failed insert since the
    /// last change.
    halvings: u32,
    calm_frames: u32,
}

impl TableLoad {
    /// An empty table of `capacity` slots.
    pub fn empty(capacity: u32) -> TableLoad {
        TableLoad {
            capacity,
            ..TableLoad::default()
        }
    }

    /// Whether inserts take the free slot ending their probe run rather than a stale slot met before it
    /// (`FLAG_MAP_HAS_ROOM`): while at most 1/ROOM_DEN of the table is taken, a stale cell (older than the
    /// cache lifetime) keeps its AO for a later revisit and probes stay short; past it, stale slots are
    /// recycled first so the table still fills slowly.
    pub fn has_room(&self) -> bool {
        (self.occupied as u64) * ROOM_DEN < self.capacity as u64
    }

    /// The frame `frame_index` (counted after it) ended with `occupied` slots taken, its longest probe run
    /// `longest_probe` slots long; `failed_inserts`: an insert found its probe run full of live cells.
    pub fn finish_frame(
        &mut self,
        frame_index: u32,
        occupied: u32,
        longest_probe: u32,
        failed_inserts: bool,
    ) {
        self.occupied = occupied;
        self.longest_probe = longest_probe;
        if failed_inserts {
            self.levelwise_until = Some(frame_index.wrapping_add(LEVELWISE_FRAMES));
            self.halvings = (self.halvings + 1).min(MAX_LIFETIME_HALVINGS);
            self.calm_frames = 0;
        } else if self.halvings > 0 {
            self.calm_frames += 1;
            if self.calm_frames >= CALM_FRAMES {
                self.halvings -= 1;
                self.calm_frames = 0;
            }
        }
    }

    /// The fraction of the cache lifetime the table keeps this frame. The lifetime holds while the table can
    /// hold every cell used within it; when an insert fails, every slot of its run held a cell used within the
    /// lifetime, so the cells the view needs now would wait for older ones to expire (up to the whole lifetime:
    /// AO = 1, or coarse cells, on newly seen surfaces meanwhile). Each frame with a failed insert halves the
    /// lifetime (down to 1/2^MAX_LIFETIME_HALVINGS): the least recently used cells become reclaimable first, and
    /// a frame's own cells are never among them. CALM_FRAMES frames without one double it back.
    pub fn lifetime_fraction(&self) -> f64 {
        0.5f64.powi(self.halvings as i32)
    }

    /// Whether the frame `frame_index` of `pixels` pixels may find probe runs full of live cells: an insert
    /// failed in the last LEVELWISE_FRAMES frames (real contention); or it is the first frame of the map's F
    /// (`first_of_f`: a new or emptied map, or eq. 6's new F) and its cells may not fit in the table: every slot
    /// is then free or reclaimable, and the cells it claims stay live for the cache lifetime, so the first frame
    /// decides which levels hold the slots (`claims_per_pixel`); or the table is past its room and the last
    /// frame's longest probe run reached half of MAX_PROBE. Past its room an insert takes the first stale slot
    /// of its run, so a run is long only where live cells (used within the cache lifetime) crowd it: the host
    /// counts no live cells (stale ones are known only to the probes, and `occupied` only grows), the probes
    /// measure them where the frame's keys live. Otherwise one pass: a 1080p view at the default s_p claims
    /// about 4·10^5 cells (0.18 per pixel measured on racks_5x5; at most 7·10^5), which the default 2^20 slots
    /// hold.
    pub fn crowded(&self, frame_index: u32, first_of_f: bool, pixels: u32, s_p: f32) -> bool {
        // Frame numbers wrap: compare their difference.
        let failed_recently = self
            .levelwise_until
            .is_some_and(|until| (until.wrapping_sub(frame_index) as i32) > 0);
        let first_of_f = first_of_f || self.occupied == 0;
        let may_overflow = first_of_f && pixels as f64 * claims_per_pixel(s_p) > self.capacity as f64;
        let long_runs = 2 * self.longest_probe >= MAX_PROBE;
        failed_recently || may_overflow || (!self.has_room() && long_runs)
    }

    /// The cell finder's dispatches as (coarsest, finest) level ranges (paper §4): every level in one pass over
    /// the pixels, or, when the frame is `crowded`, one dispatch per level, coarsest first: the coarse cells,
    /// shared by many pixels, then take the free slots before any finer one, and pixels whose fine cells fail
    /// fall back to them.
    pub fn cell_levels(&self, frame_index: u32, first_of_f: bool, pixels: u32, s_p: f32) -> Vec<(u32, u32)> {
        let top = gpu::LOD_COUNT - 1;
        if self.crowded(frame_index, first_of_f, pixels, s_p) {
            (0..=top).rev().map(|l| (l, l)).collect()
        } else {
            vec![(top, 0)]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEFAULT_CAPACITY: u32 = 1 << 20;

    /// Passes of a frame after the first of its F, 1080p at the default s_p.
    fn passes(load: &TableLoad, frame: u32) -> usize {
        load.cell_levels(frame, false, HD, 4.0).len()
    }

    const HD: u32 = 1920 * 1080;

    /// The first frame of a map's F: level by level when its cells may not fit in the table. 1080p at s_p = 4
    /// (~7·10^5 cells at most, 0.18 per pixel measured on racks_5x5) fits the default table: one pass, where
    /// the old rule `pixels > capacity / 2` took 4. 320x180 at s_p = 1.5 (the overloaded map test: 38,530 cells
    /// for 2048 slots) does not. Catches a first frame that is not checked (`may_overflow` dropped: the
    /// overloaded map's first frame claims the slots for its fine cells, which stay live, and its MAE doubles).
    #[test]
    fn a_first_frame_goes_level_by_level_when_its_cells_may_not_fit() {
        let empty = TableLoad::empty(DEFAULT_CAPACITY);
        assert_eq!(empty.cell_levels(0, true, HD, 4.0).len(), 1);
        assert_eq!(empty.cell_levels(0, true, 4 * HD, 4.0).len(), 4, "4K");
        let small = TableLoad::empty(2048);
        assert_eq!(small.cell_levels(0, true, 320 * 180, 1.5).len(), 4);
        assert_eq!(small.cell_levels(0, true, 64 * 36, 4.0).len(), 1);
        // A later frame of the same F: the measured table decides (`occupied` > 0, not the first of its F).
        let mut used = small;
        used.finish_frame(1, 1500, 3, false);
        assert_eq!(used.cell_levels(1, false, 320 * 180, 1.5).len(), 1);
        // A new F (an edit, eq. 6): every slot is reclaimable again, the first frame is checked again.
        assert_eq!(used.cell_levels(1, true, 320 * 180, 1.5).len(), 4);
    }

    /// The default table: one pass while it has room, whatever the frame's size (a 1080p frame has more pixels
    /// than half the slots, which the old rule `pixels > capacity / 2` took for crowded: 4 passes on every 1080p
    /// frame), even when its runs are long; past its room, one pass while the last frame's runs were short and
    /// one per level once they reach half of MAX_PROBE. Catches the old rule, a rule on occupancy alone
    /// (`!self.has_room()`: every frame of a session whose table once filled would take 4 passes, occupancy
    /// only grows) and one on probe lengths alone (`long_runs`: a table with room would go level by level).
    #[test]
    fn the_cell_finder_goes_level_by_level_only_when_runs_crowd_past_the_room() {
        let mut load = TableLoad::empty(DEFAULT_CAPACITY);
        assert_eq!(passes(&load, 0), 1, "empty table");
        load.finish_frame(1, 400_000, MAX_PROBE, false);
        assert!(load.has_room());
        assert_eq!(passes(&load, 1), 1, "a 1080p view in the table, one long run");
        load.finish_frame(2, DEFAULT_CAPACITY - 1000, 3, false);
        assert!(!load.has_room());
        assert_eq!(passes(&load, 2), 1, "full of stale cells: short runs");
        load.finish_frame(3, DEFAULT_CAPACITY - 1000, MAX_PROBE / 2, false);
        assert_eq!(passes(&load, 3), 4, "past the room, runs half of MAX_PROBE");
        load.finish_frame(4, DEFAULT_CAPACITY - 1000, MAX_PROBE / 2 - 1, false);
        assert_eq!(passes(&load, 4), 1, "the runs got shorter again");
    }

    /// After a failed insert, LEVELWISE_FRAMES frames go level by level whatever the occupancy, also across
    /// the wrap of frame numbers. Catches a failure that is forgotten (`levelwise_until` not set) and a window
    /// compared without wrapping (`until > frame_index`: one pass right after a failure near the wrap).
    #[test]
    fn a_failed_insert_makes_the_next_frames_level_by_level() {
        for start in [10u32, u32::MAX - 20] {
            let mut load = TableLoad::empty(1 << 12);
            load.finish_frame(start, 100, 1, true);
            let passes = |f: u32| load.cell_levels(start.wrapping_add(f), false, 64, 4.0).len();
            for f in 0..LEVELWISE_FRAMES {
                assert_eq!(passes(f), 4, "frame {f} after");
            }
            assert_eq!(passes(LEVELWISE_FRAMES), 1);
            assert_eq!(passes(1 << 20), 1);
        }
    }

    /// Failed inserts halve the lifetime, down to 1/64; frames without one double it back, CALM_FRAMES at a
    /// time. Catches a lifetime that never yields (`halvings` not raised: a table full of live cells fails the
    /// view's inserts for a whole lifetime) and one that never recovers (not lowered).
    #[test]
    fn failed_inserts_shorten_the_lifetime_until_the_table_copes() {
        let mut load = TableLoad::empty(4096);
        assert_eq!(load.lifetime_fraction(), 1.0);
        for f in 0..10 {
            load.finish_frame(f, 4096, MAX_PROBE, true);
        }
        assert_eq!(load.lifetime_fraction(), 1.0 / 64.0);
        for f in 10..10 + CALM_FRAMES - 1 {
            load.finish_frame(f, 4096, 3, false);
        }
        assert_eq!(load.lifetime_fraction(), 1.0 / 64.0);
        load.finish_frame(10 + CALM_FRAMES, 4096, 3, false);
        assert_eq!(load.lifetime_fraction(), 1.0 / 32.0);
        for f in 0..10 * CALM_FRAMES {
            load.finish_frame(100 + f, 4096, 3, false);
        }
        assert_eq!(load.lifetime_fraction(), 1.0);
    }

    #[test]
    fn room_is_half_the_table() {
        let mut load = TableLoad::empty(4096);
        load.finish_frame(1, 2047, 1, false);
        assert!(load.has_room());
        load.finish_frame(2, 2048, 1, false);
        assert!(!load.has_room());
    }
}
