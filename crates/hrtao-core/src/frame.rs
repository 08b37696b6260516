//! The one description of a frame (`FrameDesc`), and the one place that decides what the change from the
//! previous frame invalidates (`Change::between`): nothing, the still image, the cells of a region, or the whole
//! map. The renderer takes a `FrameDesc` whole; the viewer, `hrtao render`, `hrtao bench` and the screenshot
//! tiles each build one per frame.
use std::time::Duration;

use glam::Vec3;

use crate::accel::SceneGpu;
use crate::camera::Camera;
use crate::raster::Primary;
use crate::settings::{AoSettings, Invalidates};
use crate::tile::Tile;

/// A frame's own ray budget (a viewer's frame-time target): B rays per pixel, traced this frame by this fraction
/// of the pixels whose cells take rays (a different random subset each frame; budgets below one ray per pixel,
/// ours). Refinement frames ignore the fraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayBudget {
    pub rays_per_pixel: u32,
    pub trace_fraction: f32,
}

/// The largest slice lattice (`FrameDesc::lattice`): 144 slices of a whole frame. 8 left san_francisco's slices
/// on lavapipe at 80-115 ms even at half the rays per visit (a drag waited for them: input latency p95 179-216
/// ms); at 12 they meet the 50 ms slice target (p95 143 ms) and the time to converge stayed (72 s). A viewer
/// takes a lattice this large only where its slices need it; its held rounds show the spacing-3 grid
/// (`slice_order`). (16 was tried when the held rounds showed the lattice's coarsest grid: a blocky image for
/// ~17 s after every move; the first round now shows each finer grid as it completes.)
pub const MAX_LATTICE: u32 = 12;

/// How the composite writes its output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// BGRA byte order (a swapchain that cannot be blitted to), else RGBA.
    pub bgra: bool,
    /// The background gradient, top and bottom (linear RGB).
    pub background: ([f32; 3], [f32; 3]),
}

impl Default for Output {
    fn default() -> Self {
        Output {
            bgra: false,
            background: ([0.62, 0.68, 0.76], [0.93, 0.94, 0.95]),
        }
    }
}

/// Everything one frame depends on.
#[derive(Clone, Copy)]
pub struct FrameDesc<'a> {
    /// The scene: its geometry generation (the TLAS build), instances, section planes and edit log.
    pub scene: &'a SceneGpu,
    /// The scene's F (eq. 6), bumped by every edit.
    pub scene_f: u32,
    /// The camera; its width and height are the internal render size.
    pub camera: Camera,
    /// Height of the view in pixels when rendering at a reduced internal resolution (0 = the internal height):
    /// s_p and the feature-edge width count view pixels, so cells do not change with the render scale.
    pub view_height: u32,
    pub settings: &'a AoSettings,
    /// None: `settings.map.rays_per_pixel` for every pixel that traces.
    pub budget: Option<RayBudget>,
    /// Render this window of a larger image (large screenshots); None = the camera's whole image.
    pub tile: Option<Tile>,
    /// Jitter the primary samples of still frames (anti-aliasing); `hrtao render` keeps pixel centres.
    pub jitter: bool,
    pub output: Output,
    /// Slices (ours): each frame draws every `lattice`-th pixel in x and y, one of lattice² interleaved
    /// slices in turn, so a frame costs about 1/lattice² of a whole one; a still image's round of slices
    /// accumulates as one whole frame would (1 = whole frames). Changing it changes nothing that was drawn:
    /// it takes effect at the next round, except that a larger one restarts a still image's first round.
    pub lattice: u32,
    /// When the frame starts, from an origin fixed for the renderer (None: now on the renderer's monotonic
    /// clock). Only the cache lifetime reads it (`MapSettings::cache_lifetime_s`): tests and replays give
    /// simulated times (`at`), so a run at 10 or 144 frames per second is reproducible. Not part of what the
    /// frame shows: a new time changes nothing that was drawn.
    pub time: Option<Duration>,
    /// Rays traced besides the image (`probes.rs`, at most `MAX_PROBE_RAYS`): their hits come with the frame's
    /// report. Not part of what the frame shows.
    pub probes: &'a [crate::gpu::ProbeRay],
}

impl<'a> FrameDesc<'a> {
    /// A frame of `camera` (its size is the render size) with `settings`; no tile, no jitter, RGBA output.
    pub fn new(scene: &'a SceneGpu, scene_f: u32, camera: Camera, settings: &'a AoSettings) -> FrameDesc<'a> {
        FrameDesc {
            scene,
            scene_f,
            camera,
            view_height: 0,
            settings,
            budget: None,
            tile: None,
            jitter: false,
            output: Output::default(),
            lattice: 1,
            time: None,
            probes: &[],
        }
    }

    /// This frame at time `time` (simulated: see `time`).
    pub fn at(self, time: Duration) -> FrameDesc<'a> {
        FrameDesc {
            time: Some(time),
            ..self
        }
    }

    /// The render size.
    pub fn size(&self) -> (u32, u32) {
        (self.camera.width.max(1), self.camera.height.max(1))
    }

    /// Rays per pixel and the fraction of tracing pixels this frame.
    pub fn budget(&self) -> RayBudget {
        self.budget.unwrap_or(RayBudget {
            rays_per_pixel: self.settings.map.rays_per_pixel,
            trace_fraction: 1.0,
        })
    }

    /// Checks the settings and the budget; the message names what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        self.settings.validate()?;
        if let Some(b) = self.budget {
            if !(b.trace_fraction > 0.0 && b.trace_fraction <= 1.0) {
                return Err(format!(
                    "trace fraction must be in (0, 1], got {}",
                    b.trace_fraction
                ));
            }
            if b.rays_per_pixel > 1024 {
                return Err(format!(
                    "ray budget {} is above 1024 rays per pixel",
                    b.rays_per_pixel
                ));
            }
        }
        if !(1..=MAX_LATTICE).contains(&self.lattice) {
            return Err(format!(
                "slice lattice must be in 1..={MAX_LATTICE}, got {}",
                self.lattice
            ));
        }
        if self.lattice > 1 && self.tile.is_some() {
            return Err("a tile is drawn whole: slices of a tile are not supported".into());
        }
        Ok(())
    }

    /// The F the frame hashes with (eq. 6): the scene's, plus one per section plane change, since moving a
    /// plane changes the AO as an edit does. Both only grow, so the sum changes whenever either does.
    pub fn effective_f(&self) -> u32 {
        self.scene_f.wrapping_add(self.scene.section_changes())
    }

    /// What the renderer keeps of this frame to compare the next one with.
    pub(crate) fn key(&self, primary: Primary) -> FrameKey {
        FrameKey {
            camera: self.camera,
            view_height: self.view_height,
            settings: self.settings.clone(),
            budget: self.budget(),
            tile: self.tile,
            jitter: self.jitter,
            output: self.output,
            primary,
            scene_f: self.scene_f,
            section_changes: self.scene.section_changes(),
            tlas_generation: self.scene.tlas_generation(),
            scene_version: self.scene.version(),
            highlight: self.scene.highlight_version(),
        }
    }
}

/// What a frame depended on, kept until the next one.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameKey {
    pub camera: Camera,
    pub view_height: u32,
    pub settings: AoSettings,
    pub budget: RayBudget,
    pub tile: Option<Tile>,
    pub jitter: bool,
    pub output: Output,
    pub primary: Primary,
    pub scene_f: u32,
    pub section_changes: u32,
    pub tlas_generation: u64,
    pub scene_version: u64,
    /// The highlighted instances' version (`SceneGpu::set_highlight`): only the composite shows it.
    pub highlight: u64,
}

/// What happens to the hash map's cells.
#[derive(Clone, Debug, PartialEq)]
pub enum MapChange {
    /// They keep their keys.
    Keep,
    /// A local edit: the cells within reach of these boxes (world space) get new region epochs; the pixels
    /// there restart their still refinement. The renderer falls back to `Whole` when the region table refuses.
    Regions(Vec<(Vec3, Vec3)>),
    /// Every cell is invalidated (a new F, eq. 6).
    Whole,
}

/// What the change from one frame to the next invalidates.
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// The still image restarts (camera, size, settings that change what is shown, scene instances).
    pub still_image: bool,
    pub map: MapChange,
    /// A setting's change invalidates the whole map (as opposed to a scene edit): the renderer keys cells with
    /// a new F of its own, so that key F values never revert.
    pub settings_invalidate_map: bool,
}

impl Change {
    /// The first frame: a new still image and a new map.
    pub fn first() -> Change {
        Change {
            still_image: true,
            map: MapChange::Whole,
            settings_invalidate_map: false,
        }
    }

    /// The change from `prev` to `next`. `locate(prev, next)` lists the world boxes the scene edits and section
    /// plane moves between the two touched (`SceneGpu::changes_between`), or None when some change is not
    /// located. Every field of `FrameKey` is named here (an exhaustive destructuring: a new field does not
    /// compile until it is classified); settings classify themselves (`AoSettings::invalidates`).
    pub fn between(
        prev: &FrameKey,
        next: &FrameKey,
        locate: impl FnOnce(&FrameKey, &FrameKey) -> Option<Vec<(Vec3, Vec3)>>,
    ) -> Change {
        let FrameKey {
            camera,
            view_height,
            settings,
            budget,
            tile,
            jitter,
            output,
            primary,
            scene_f,
            section_changes,
            tlas_generation,
            scene_version,
            highlight,
        } = prev;
        let settings_class = settings.invalidates(&next.settings);
        // What is shown: the view, the render size, the frame's budget, primary visibility, the instances.
        let view_changed = *camera != next.camera
            || *view_height != next.view_height
            || *budget != next.budget
            || *tile != next.tile
            || *jitter != next.jitter
            || *output != next.output
            || *primary != next.primary;
        // A new TLAS or instance table: the instances changed (or were rebuilt for the same content). A new
        // highlight too: the composite accumulates each pixel's shade with its AO over the still frames, so the
        // pixels' accumulations restart (the map keeps its cells).
        let instances_changed = *tlas_generation != next.tlas_generation
            || *scene_version != next.scene_version
            || *highlight != next.highlight;
        let edited = (*scene_f, *section_changes) != (next.scene_f, next.section_changes);
        let map = if settings_class == Invalidates::WholeMap {
            MapChange::Whole
        } else if !edited {
            MapChange::Keep
        } else {
            // Local edits need the cell cap: the region grids cover cells up to 2R (`RegionTable`).
            let local = next.settings.edits.local_edits && next.settings.map.cell_cap;
            match local.then(|| locate(prev, next)).flatten() {
                Some(boxes) => MapChange::Regions(boxes),
                None => MapChange::Whole,
            }
        };
        Change {
            // A local edit keeps the still image: composite.comp restarts it only in the edited regions.
            // (An instance change that is not located restarts it whole.)
            still_image: view_changed
                || settings_class >= Invalidates::StillImage
                || match map {
                    MapChange::Keep => instances_changed,
                    MapChange::Regions(_) => false,
                    MapChange::Whole => true,
                },
            settings_invalidate_map: settings_class == Invalidates::WholeMap,
            map,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> FrameKey {
        FrameKey {
            camera: Camera::default(),
            view_height: 0,
            settings: AoSettings::default(),
            budget: RayBudget {
                rays_per_pixel: 4,
                trace_fraction: 1.0,
            },
            tile: None,
            jitter: true,
            output: Output::default(),
            primary: Primary::RayQuery,
            scene_f: 3,
            section_changes: 0,
            tlas_generation: 1,
            scene_version: 1,
            highlight: 0,
        }
    }

    fn boxes() -> Option<Vec<(Vec3, Vec3)>> {
        Some(vec![(Vec3::ZERO, Vec3::ONE)])
    }

    #[test]
    fn an_unchanged_frame_invalidates_nothing() {
        let c = Change::between(&key(), &key(), |_, _| panic!("nothing to locate"));
        assert_eq!((c.still_image, c.map), (false, MapChange::Keep));
    }

    #[test]
    fn the_view_restarts_the_still_image_only() {
        for next in [
            FrameKey {
                camera: Camera {
                    fov_y_deg: 30.0,
                    ..Camera::default()
                },
                ..key()
            },
            FrameKey {
                view_height: 7,
                ..key()
            },
            FrameKey {
                budget: RayBudget {
                    rays_per_pixel: 1,
                    trace_fraction: 0.5,
                },
                ..key()
            },
            FrameKey {
                jitter: false,
                ..key()
            },
            FrameKey {
                primary: Primary::Raster,
                ..key()
            },
            FrameKey {
                tlas_generation: 2,
                ..key()
            },
            FrameKey {
                scene_version: 2,
                ..key()
            },
            FrameKey {
                highlight: 1,
                ..key()
            },
        ] {
            let c = Change::between(&key(), &next, |_, _| None);
            assert_eq!((c.still_image, c.map), (true, MapChange::Keep), "{next:?}");
        }
    }

    #[test]
    fn settings_classify_themselves() {
        let mut s = AoSettings::default();
        s.map.cache_lifetime_s = 7.0;
        let c = Change::between(&key(), &FrameKey { settings: s, ..key() }, |_, _| None);
        assert_eq!((c.still_image, c.map), (false, MapChange::Keep));
        let mut s = AoSettings::default();
        s.map.s_p = 7.0;
        let c = Change::between(&key(), &FrameKey { settings: s, ..key() }, |_, _| None);
        assert_eq!((c.still_image, c.map), (true, MapChange::Keep));
        let s = AoSettings::default().with_radius(2.0);
        let c = Change::between(&key(), &FrameKey { settings: s, ..key() }, |_, _| None);
        assert_eq!(
            (c.still_image, c.map, c.settings_invalidate_map),
            (true, MapChange::Whole, true)
        );
    }

    #[test]
    fn a_located_edit_invalidates_its_regions_and_keeps_the_still_image() {
        // An edit rebuilds the TLAS and the instance table too.
        let next = FrameKey {
            scene_f: 4,
            tlas_generation: 2,
            scene_version: 2,
            ..key()
        };
        let c = Change::between(&key(), &next, |_, _| boxes());
        assert_eq!(
            (c.still_image, c.map),
            (false, MapChange::Regions(boxes().unwrap()))
        );
        // A plane move is an edit too.
        let next = FrameKey {
            section_changes: 1,
            tlas_generation: 2,
            ..key()
        };
        let c = Change::between(&key(), &next, |_, _| boxes());
        assert_eq!(
            (c.still_image, c.map),
            (false, MapChange::Regions(boxes().unwrap()))
        );
    }

    #[test]
    fn an_edit_invalidates_the_whole_map_when_unlocated_or_without_local_edits_or_the_cell_cap() {
        let next = FrameKey { scene_f: 4, ..key() };
        let c = Change::between(&key(), &next, |_, _| None);
        assert_eq!(
            (c.still_image, c.map, c.settings_invalidate_map),
            (true, MapChange::Whole, false)
        );
        for off in [r#"{"local_edits": false}"#, r#"{"cell_cap": false}"#] {
            let s = AoSettings::default().with_overrides(off).unwrap();
            let (prev, next) = (
                FrameKey {
                    settings: s.clone(),
                    ..key()
                },
                FrameKey {
                    settings: s,
                    scene_f: 4,
                    ..key()
                },
            );
            let c = Change::between(&prev, &next, |_, _| boxes());
            assert_eq!(c.map, MapChange::Whole, "{off}");
        }
    }
}
