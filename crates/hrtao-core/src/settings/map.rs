//! The paper's hash map and its sampling (§1–4, §6), and our two changes to where a cell lives.
use super::settings_group;
use crate::gpu::{self, FrameGlobals};

/// Ours (`offset_bins`): eq. (5)'s bins shifted by this fraction of a bin, floor(n s_nd + offset). It keeps every
/// bin edge at least 0.02 from the normal components of axis-aligned faces, 30°/45°/60° chamfers and hexagon
/// faces (0, ±1/2, ±√2/2, ±√3/2, ±1) at the default s_nd, so such a face never splits between bins on rounding
/// noise (eq. (5) as published puts its edges on axis-aligned normals).
pub const NORMAL_BIN_OFFSET: f32 = 0.25;

/// Ours (`cell_cap`): the finest cell size s_w is at most this fraction of the AO radius R (eq. 2–3), so cells
/// stay small against the contact shadows they store. The grids of local edits are sized by it.
pub const MAX_CELL_FRACTION: f32 = 0.25;

/// Longest linear probe (§1) before an insert fails.
pub const MAX_PROBE: u32 = 32;

/// The longest cache lifetime accepted (`cache_lifetime_s`): a day. Longer, a cell's seconds would outgrow
/// the frame clock's precision long before anyone revisits it.
pub const MAX_CACHE_LIFETIME_S: f32 = 86_400.0;

settings_group! {
    /// The paper's hash map and its sampling.
    pub struct MapSettings {
        /// AO radius R in scene units (§1: rays longer than this count as unoccluded). The viewer's default: 8 mm
        /// for the bundled gearbox, 5% of the bounding-box diagonal otherwise.
        ao_radius: f32 = 1.0, WholeMap, paper keep, range 0.0..=f32::INFINITY, above_min, log, label "AO radius",
            custom;
        /// Ray budget B: rays traced per pixel per frame (§3, §6). A viewer with a frame-time target may give a
        /// frame its own budget (`FrameDesc::budget`); the viewer's panel sets it in rays per frame.
        rays_per_pixel: u32 = 4, StillImage, paper keep, range 0..=1024, label "ray budget", hidden;
        /// s_p: target feature size in view pixels (eq. 2); the cell size s_w grows with distance. Larger:
        /// coarser cells, fewer rays per cell needed, blurrier AO.
        s_p: f32 = 4.0, StillImage, paper keep, range 0.5..=64.0, log, label "s_p";
        /// s_nd: normal discretisation (eq. 5); cells are keyed by position and quantised normal so surfaces
        /// with different orientations don't share AO.
        s_nd: f32 = 3.0, WholeMap, paper keep, range 0.5..=16.0, label "s_nd";
        /// s_min: smallest world feature (eq. 3).
        s_min: f32 = 1e-10, WholeMap, paper keep, range 0.0..=f32::INFINITY, above_min, label "s_min", hidden;
        /// Rays per cell after which a cell stops receiving rays (§6: 1000), freeing the budget for the others.
        max_samples: u32 = 1000, StillImage, paper keep, range 1..=gpu::MAX_SAMPLES_LIMIT, log;
        /// Fewer samples than this in the finest cell: use the next coarser LOD (§4).
        min_samples: u32 = 8, StillImage, paper keep, range 0..=256;
        /// Hash map capacity in cells (§1, §6), a power of two: the world-space cache of AO values. Changing it
        /// empties the cache.
        hash_capacity: u32 = 1 << 20, WholeMap, paper keep, range 1024..=1 << 28, power_of_two, custom;
        /// Seconds a cell keeps its AO after its last use (eq. 6's lazy removal): older cells may be reclaimed
        /// while probing, and while the table has room they are kept still. Counted in time, not frames, so a
        /// region revisited within it is found, not traced again, at any frame rate. (Replaces `stale_frames`,
        /// 240 frames: 24 s at 10 fps, 1.7 s at 144 fps.)
        cache_lifetime_s: f32 = 30.0, Nothing, paper keep, range 0.0..=MAX_CACHE_LIFETIME_S, above_min,
            label "cache lifetime", hidden;
        /// Ours: eq. 5's normal bins shifted by a quarter bin (`NORMAL_BIN_OFFSET`), so axis-aligned faces and
        /// 30°/45°/60° chamfers never sit on a bin edge. Off: eq. 5 as published.
        offset_bins: bool = true, WholeMap, paper (false);
        /// Ours: the finest cell is at most a quarter of the AO radius (`MAX_CELL_FRACTION`), so cells stay
        /// small against the contact shadows they store. Off: eq. 2-3 alone (and edits empty the whole map).
        cell_cap: bool = true, WholeMap, paper (false);
    }
}

impl MapSettings {
    /// The largest finest cell s_w (eq. 2–3 capped by `cell_cap`); unbounded without the cap.
    pub fn s_w_max(&self) -> f32 {
        if self.cell_cap {
            self.ao_radius * MAX_CELL_FRACTION
        } else {
            f32::MAX
        }
    }

    /// The offset of eq. (5)'s bins, in bins.
    pub fn normal_offset(&self) -> f32 {
        if self.offset_bins {
            NORMAL_BIN_OFFSET
        } else {
            0.0
        }
    }

    /// The map's parameters (the capacity is the allocated table's, and the lifetime in frames is the frame
    /// clock's: both written by the map's owner).
    pub fn write_gpu(&self, g: &mut FrameGlobals) {
        g.rays_per_pixel = self.rays_per_pixel;
        g.ao_radius = self.ao_radius;
        g.s_w_max = self.s_w_max();
        g.log2_s_min = crate::hash::log2_s_min(self.s_min);
        g.s_nd = self.s_nd;
        g.normal_offset = self.normal_offset();
        g.max_samples = self.max_samples;
        g.min_samples = self.min_samples;
        g.max_probe = MAX_PROBE;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_settings_are_checked_and_named() {
        let ok = MapSettings::default();
        assert!(ok.validate().is_ok());
        for (bad, name) in [
            (
                MapSettings {
                    ao_radius: f32::NAN,
                    ..ok.clone()
                },
                "AO radius",
            ),
            (
                MapSettings {
                    s_nd: 0.0,
                    ..ok.clone()
                },
                "s_nd",
            ),
            (
                MapSettings {
                    hash_capacity: 1000,
                    ..ok.clone()
                },
                "hash capacity",
            ),
            (
                MapSettings {
                    rays_per_pixel: 2000,
                    ..ok.clone()
                },
                "ray budget",
            ),
            (
                MapSettings {
                    cache_lifetime_s: f32::NAN,
                    ..ok.clone()
                },
                "cache lifetime",
            ),
            (
                MapSettings {
                    cache_lifetime_s: 0.0,
                    ..ok.clone()
                },
                "cache lifetime",
            ),
            (
                MapSettings {
                    cache_lifetime_s: -1.0,
                    ..ok.clone()
                },
                "cache lifetime",
            ),
            (
                MapSettings {
                    cache_lifetime_s: f32::INFINITY,
                    ..ok.clone()
                },
                "cache lifetime",
            ),
            (
                MapSettings {
                    cache_lifetime_s: 1e9,
                    ..ok.clone()
                },
                "cache lifetime",
            ),
        ] {
            let e = bad.validate().unwrap_err();
            assert!(e.contains(name), "{e}");
        }
    }

    /// Settings saved before the lifetime was counted in seconds load: the old `stale_frames` is skipped (and
    /// named), the rest kept, the lifetime at its default.
    #[test]
    fn saved_settings_with_stale_frames_still_load() {
        let old = serde_json::json!({"stale_frames": 240, "ao_radius": 2.0});
        let (s, skipped) = crate::settings::AoSettings::from_json_lenient(&old);
        assert_eq!(skipped, ["stale_frames"]);
        assert_eq!(s.map.ao_radius, 2.0);
        assert_eq!(s.map.cache_lifetime_s, MapSettings::default().cache_lifetime_s);
        let plain: crate::settings::AoSettings = serde_json::from_value(old).unwrap();
        assert_eq!(plain.map.ao_radius, 2.0);
    }

    #[test]
    fn no_cap_and_published_bins_in_the_papers_mode() {
        let p = MapSettings::default().paper();
        assert_eq!(p.s_w_max(), f32::MAX);
        assert_eq!(p.normal_offset(), 0.0);
        assert_eq!(MapSettings::default().s_w_max(), MAX_CELL_FRACTION);
    }
}
