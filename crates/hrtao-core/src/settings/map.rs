//! The paper's hash map and its sampling (§1–4, §6), and our two changes to where a cell lives.
use super::{positive, settings_group};
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
        /// AO radius R in scene units (rays longer than this count as unoccluded).
        ao_radius: f32 = 1.0, WholeMap, paper keep;
        /// Ray budget B: rays traced per pixel per frame (§3, §6). A viewer with a frame-time target may give a
        /// frame its own budget (`FrameDesc::budget`).
        rays_per_pixel: u32 = 4, StillImage, paper keep;
        /// s_p: target feature size in view pixels (eq. 2).
        s_p: f32 = 4.0, StillImage, paper keep;
        /// s_nd: normal discretisation (eq. 5).
        s_nd: f32 = 3.0, WholeMap, paper keep;
        /// s_min: smallest world feature (eq. 3).
        s_min: f32 = 1e-10, WholeMap, paper keep;
        /// Rays per cell after which a cell stops receiving rays (§6: 1000).
        max_samples: u32 = 1000, StillImage, paper keep;
        /// Fewer samples than this in the finest cell: use the next coarser LOD (§4).
        min_samples: u32 = 8, StillImage, paper keep;
        /// Hash map capacity in cells (a power of two).
        hash_capacity: u32 = 1 << 20, WholeMap, paper keep;
        /// Seconds a cell keeps its AO after its last use (eq. 6's lazy removal): older cells may be reclaimed
        /// while probing, and while the table has room they are kept still. Counted in time, not frames, so a
        /// region revisited within it is found, not traced again, at any frame rate. (Replaces `stale_frames`,
        /// 240 frames: 24 s at 10 fps, 1.7 s at 144 fps.)
        cache_lifetime_s: f32 = 30.0, Nothing, paper keep;
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

    pub fn validate(&self) -> Result<(), String> {
        positive("AO radius", self.ao_radius)?;
        positive("s_p", self.s_p)?;
        positive("s_nd", self.s_nd)?;
        positive("s_min", self.s_min)?;
        positive("cache lifetime", self.cache_lifetime_s)?;
        if self.cache_lifetime_s > MAX_CACHE_LIFETIME_S {
            return Err(format!(
                "cache lifetime must be at most {MAX_CACHE_LIFETIME_S} s (a day), got {} s",
                self.cache_lifetime_s
            ));
        }
        if !self.hash_capacity.is_power_of_two() || self.hash_capacity < 1024 || self.hash_capacity > 1 << 28
        {
            return Err(format!(
                "hash capacity must be a power of two in 1024..=2^28, got {}",
                self.hash_capacity
            ));
        }
        if self.rays_per_pixel > 1024 {
            return Err(format!(
                "ray budget {} is above 1024 rays per pixel",
                self.rays_per_pixel
            ));
        }
        if self.max_samples > gpu::MAX_SAMPLES_LIMIT {
            return Err(format!(
                "max samples {} is above {}",
                self.max_samples,
                gpu::MAX_SAMPLES_LIMIT
            ));
        }
        Ok(())
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
