//! User-facing AO settings, with the paper's names.
use serde::{Deserialize, Serialize};

use crate::gpu;

/// What the renderer computes and shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Brute-force per-pixel ray-traced AO (the baseline), accumulated while nothing changes.
    Rtao,
    /// The paper's hashed ray-traced AO.
    #[default]
    Hrtao,
    /// Shading without AO.
    NoAo,
    /// Debug: hash cell false colours (paper Fig. 3).
    DebugCells,
    /// Debug: LOD used per pixel.
    DebugLod,
    /// Debug: samples per cell heat map.
    DebugSamples,
}

impl Mode {
    pub fn gpu_value(self) -> u32 {
        match self {
            Mode::Rtao => gpu::MODE_RTAO,
            Mode::Hrtao => gpu::MODE_HRTAO,
            Mode::NoAo => gpu::MODE_NO_AO,
            Mode::DebugCells => gpu::MODE_DEBUG_CELLS,
            Mode::DebugLod => gpu::MODE_DEBUG_LOD,
            Mode::DebugSamples => gpu::MODE_DEBUG_SAMPLES,
        }
    }

    /// True when the hash map passes run (HRTAO and its debug views).
    pub fn uses_hash(self) -> bool {
        matches!(
            self,
            Mode::Hrtao | Mode::DebugCells | Mode::DebugLod | Mode::DebugSamples
        )
    }

    pub const ALL: [Mode; 6] = [
        Mode::Hrtao,
        Mode::Rtao,
        Mode::NoAo,
        Mode::DebugCells,
        Mode::DebugLod,
        Mode::DebugSamples,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Mode::Rtao => "per-pixel RTAO",
            Mode::Hrtao => "HRTAO",
            Mode::NoAo => "AO off",
            Mode::DebugCells => "debug: hash cells",
            Mode::DebugLod => "debug: LOD used",
            Mode::DebugSamples => "debug: samples per cell",
        }
    }
}

impl std::str::FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s {
            "rtao" => Mode::Rtao,
            "hrtao" => Mode::Hrtao,
            "none" | "no-ao" => Mode::NoAo,
            "cells" | "debug-cells" => Mode::DebugCells,
            "lod" | "debug-lod" => Mode::DebugLod,
            "samples" | "debug-samples" => Mode::DebugSamples,
            _ => {
                return Err(format!(
                    "unknown mode `{s}` (rtao, hrtao, none, debug-cells, debug-lod, debug-samples)"
                ))
            }
        })
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AoSettings {
    pub mode: Mode,
    /// AO radius R in scene units (rays longer than this count as unoccluded).
    pub ao_radius: f32,
    /// Ray budget B: rays traced per pixel per frame (§3, §6).
    pub rays_per_pixel: u32,
    /// Budgets below one ray per pixel (ours): the fraction of the pixels whose cells take rays that trace
    /// `rays_per_pixel` rays this frame (a different random subset each frame); 1 = all of them, as the paper.
    /// The cells still fill, since a cell pools the rays of all its pixels (§3). Refinement frames ignore it.
    pub trace_fraction: f32,
    /// s_p: target feature size in pixels (eq. 2).
    pub s_p: f32,
    /// s_nd: normal discretisation (eq. 5).
    pub s_nd: f32,
    /// Ours: eq. (5)'s bins shifted by this fraction of a bin, floor(n s_nd + offset). The default keeps every
    /// bin edge at least 0.02 from the normal components of axis-aligned faces, 30°/45°/60° chamfers and
    /// hexagon faces (0, ±1/2, ±√2/2, ±√3/2, ±1) at the default s_nd, so such a face never splits between
    /// bins on rounding noise; 0 = eq. (5) as published (its edges lie on axis-aligned normals).
    pub normal_offset: f32,
    /// s_min: smallest world feature (eq. 3).
    pub s_min: f32,
    /// Rays per cell after which a cell stops receiving rays (§6: 1000).
    pub max_samples: u32,
    /// Fewer samples than this in the finest cell: use the next coarser LOD (§4).
    pub min_samples: u32,
    /// Adaptive à-trous filter on/off (§5) and its iterations.
    pub filter: bool,
    pub filter_iterations: u32,
    /// Ours: variance-guided à-trous (edge-stopping on the AO difference in units of the cells' noise, as
    /// Schied et al. 2017 do with luminance), so the filter smooths the noise of young cells over more than a
    /// cell and stops at real AO gradients. 0 = the paper's filter, bounded by the cell footprint.
    pub filter_sigma: f32,
    /// Hash map capacity in cells (power of two).
    pub hash_capacity: u32,
    /// Longest linear probe before an insert fails.
    pub max_probe: u32,
    /// Cells untouched for this many frames may be reclaimed while probing (lazy removal, eq. 6).
    pub stale_frames: u32,
    /// Use base colours (else a uniform grey clay look).
    pub shaded: bool,
    /// Still-camera refinement (ours, docs/algorithm.md): while the view rests, every pixel traces its own rays
    /// and its AO converges from the cell estimate to the ray-traced value; primary samples are jittered when
    /// the renderer allows it. Off: the paper's behaviour (the cell estimate only).
    pub refine: bool,
    /// Weight of the cell estimate in the refinement, in rays of the pixel's own (the k of composite.comp),
    /// where the pixel's own rays show that its cell is biased: the smallest k.
    pub prior_rays: f32,
    /// Ours (docs/algorithm.md): the largest k, where the pixel's own rays agree with its cell within their
    /// noise. Between the two, k follows an empirical-Bayes shrinkage; `prior_rays_max` <= `prior_rays` keeps
    /// k fixed at `prior_rays`. Default 0 (fixed k): 1024 cuts the still flicker 3-4x but leaves engine's
    /// 32-frame error at 1.7x per-pixel RTAO's.
    pub prior_rays_max: f32,
    /// The own-ray noise (in standard deviations) that a difference from the cell must exceed to count as bias.
    pub prior_sigma: f32,
    /// Ours (docs/algorithm.md): the refinement pools the pixel's own-ray residual (own mean minus cell
    /// estimate) with its 3x3 neighbours' on the same surface whose residuals agree within this many standard
    /// deviations of their noise, so the still image moves to the ray-traced value with less flicker. 0 = the
    /// pixel's own residual only.
    pub residual_sigma: f32,
    /// Ours (docs/algorithm.md): each still frame the shown AO moves this fraction of the way to the refined
    /// estimate (an exponential moving average, a lag of about 1/x - 1 frames), in (0, 1]; 1 = none.
    pub still_smoothing: f32,
    /// A still image is final once every pixel has this many rays of its own (HRTAO refinement, per-pixel RTAO).
    pub still_samples: u32,
    /// The finest cell size s_w is at most this fraction of the AO radius R (eq. 2-3), so cells stay small
    /// against the contact shadows they store.
    pub max_cell_fraction: f32,
    /// Feature edges over the shading (silhouettes: depth and instance changes; creases: normals meeting at
    /// more than `crease_deg`), as CAD viewports draw them. Never in the AO image.
    pub edges: bool,
    pub crease_deg: f32,
    /// Ours (docs/algorithm.md, `regions.rs`): an edit invalidates only the cells within reach of what it
    /// changed (region epochs in the key); off = the paper's eq. (6), every edit empties the whole map.
    pub local_edits: bool,
    /// Ours (docs/algorithm.md, near-field control variate): a pixel that traced rays this frame corrects its
    /// cell estimate by this weight β times its own near-open fraction minus its cells' (rays that hit
    /// nothing within `near_fraction` x R), restoring the contact shadows a cell averages away; shrunk
    /// unless its same-surface neighbours' rays show the contact too, so unlucky pixels do not speckle.
    /// 0 = the paper's cell estimate alone.
    pub near_weight: f32,
    /// The near radius r_n of the control variate as a fraction of the AO radius R (0.5: smaller radii make
    /// the near-open fraction curve within a cell where the AO does not, which biases the correction).
    pub near_fraction: f32,
    /// Ours (docs/algorithm.md, level blend): while a pixel's finest cell is young (below `max_samples`), its
    /// interpolated AO a_f is shrunk toward the next coarser level's a_c by the Wiener weight
    /// d²/(d² + λ v), d = a_f - a_c, v the binomial noise of a_f: the coarse level's rays smooth the noise where
    /// the levels agree, and the fine level keeps the detail where they differ. λ is this setting; 0 = the
    /// paper's finest level alone.
    pub level_blend: f32,
    /// Ours (docs/algorithm.md, adaptive sampling): while the map is young, pixels whose cells take rays trace
    /// a quarter of their budget, then the rest of the frame's budget goes to them in proportion to the noise
    /// their cells still have, so cells that came out open take few and noisy ones more. Off: every pixel
    /// traces its budget (the paper). Refinement frames always trace each pixel's budget.
    pub adaptive_rays: bool,
    /// Ours (docs/algorithm.md, pooled residual control variate): while a pixel's cell is young, its AO a is
    /// corrected by the residual r = (open rays / traced rays) - a of the rays traced this frame by the pixel
    /// and its 3x3 neighbours on the same surface, shrunk by the Wiener weight r²/(r² + λ v) against the
    /// binomial noise v of those rays: detail finer than the cells (faces of a few pixels) comes back where
    /// the rays show it. λ is this setting; 0 = off (the paper).
    pub pooled_residual: f32,
    /// Ours (docs/algorithm.md, linear cells): each cell also keeps the least-squares slope of its AO across
    /// the cell, from where its rays started, and the resolve evaluates that line at the pixel instead of the
    /// cell's mean. The slope is shrunk by the Wiener weight g²/(g² + λ v) against its noise v. λ is this
    /// setting; 0 = constant cells (the paper), the default until its navigation cost is measured (2 is the
    /// best measured value, docs/algorithm.md).
    pub cell_gradient: f32,
    /// Ours (docs/algorithm.md, contact detail): while a pixel's cell is young, the detail of its screen-space
    /// obscurance (how much of the G-buffer around it rises above its tangent plane within R, minus the same on
    /// its surface's 3x3 neighbours) is added to its AO with a gain fitted each frame to the rays the pixels
    /// traced (least squares over the image, shrunk against its noise, never brightening creases): contact
    /// shadows finer than the cells and the filter come back. This setting scales the fitted gain; 0 = off
    /// (the paper), 1 = the fit.
    pub contact_detail: f32,
}

/// What a change of a setting invalidates (`AoSettings::invalidates`), from least to most.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Invalidates {
    /// Nothing shown changes: the still image keeps accumulating.
    Nothing,
    /// The still image restarts; the hash map keeps its cells (they hold the same AO).
    StillImage,
    /// What a cell holds or where it lives changes: every cell of the map is invalidated (a new F, eq. 6).
    WholeMap,
}

impl Default for AoSettings {
    fn default() -> Self {
        AoSettings {
            mode: Mode::Hrtao,
            ao_radius: 1.0,
            rays_per_pixel: 4,
            trace_fraction: 1.0,
            s_p: 4.0,
            s_nd: 3.0,
            normal_offset: 0.25,
            s_min: 1e-10,
            max_samples: 1000,
            min_samples: 8,
            filter: true,
            filter_iterations: 5,
            filter_sigma: 1.0,
            hash_capacity: 1 << 20,
            max_probe: 32,
            stale_frames: 240,
            shaded: true,
            refine: true,
            prior_rays: 32.0,
            prior_rays_max: 0.0,
            prior_sigma: 1.0,
            residual_sigma: 0.5,
            still_smoothing: 0.15,
            still_samples: 64,
            max_cell_fraction: 0.25,
            edges: true,
            crease_deg: 40.0,
            local_edits: true,
            near_weight: 1.0,
            near_fraction: 0.5,
            level_blend: 1.0,
            adaptive_rays: true,
            pooled_residual: 16.0,
            cell_gradient: 0.0,
            contact_detail: 1.0,
        }
    }
}

impl AoSettings {
    /// The paper's behaviour with these parameters: our additions (still-camera refinement, variance-guided
    /// filter, local edits, ...) off and eq. (5)'s normal bins as published (`normal_offset` 0), so
    /// `hrtao bench` can run both side by side.
    pub fn paper(&self) -> AoSettings {
        AoSettings {
            refine: false,
            filter_sigma: 0.0,
            normal_offset: 0.0,
            local_edits: false,
            near_weight: 0.0,
            level_blend: 0.0,
            adaptive_rays: false,
            pooled_residual: 0.0,
            cell_gradient: 0.0,
            contact_detail: 0.0,
            ..self.clone()
        }
    }

    /// What changing these settings to `new` invalidates: the largest class of the fields that differ. Every
    /// field is named here (an exhaustive destructuring: a new field does not compile until it is classified).
    pub fn invalidates(&self, new: &AoSettings) -> Invalidates {
        use Invalidates::{Nothing, StillImage, WholeMap};
        let AoSettings {
            mode,
            ao_radius,
            rays_per_pixel,
            trace_fraction,
            s_p,
            s_nd,
            normal_offset,
            s_min,
            max_samples,
            min_samples,
            filter,
            filter_iterations,
            filter_sigma,
            hash_capacity,
            max_probe,
            stale_frames,
            shaded,
            refine,
            prior_rays,
            prior_rays_max,
            prior_sigma,
            residual_sigma,
            still_smoothing,
            still_samples,
            max_cell_fraction,
            edges,
            crease_deg,
            local_edits,
            near_weight,
            near_fraction,
            level_blend,
            adaptive_rays,
            pooled_residual,
            cell_gradient,
            contact_detail,
        } = self;
        let classes = [
            // What a cell holds: rays within R, and the near-field counts within near_fraction x R.
            (*ao_radius != new.ao_radius, WholeMap),
            (*near_fraction != new.near_fraction, WholeMap),
            // Which cell a point maps to: the normal bins, the LOD scale and the largest finest cell (which
            // also sets the region grids of local edits, `RegionTable::region_lod`).
            (*s_nd != new.s_nd, WholeMap),
            (*normal_offset != new.normal_offset, WholeMap),
            (*s_min != new.s_min, WholeMap),
            (*max_cell_fraction != new.max_cell_fraction, WholeMap),
            // Where cells live: a new table, and the probe runs a key is looked up in.
            (*hash_capacity != new.hash_capacity, WholeMap),
            (*max_probe != new.max_probe, WholeMap),
            // Linear cells keep their offset sums only while on: turned on, old cells have rays without them.
            ((*cell_gradient > 0.0) != (new.cell_gradient > 0.0), WholeMap),
            (*cell_gradient != new.cell_gradient, StillImage),
            // How the cells' AO is sampled, resolved, filtered and refined, and how the image is shaded: the
            // cells keep their estimates.
            (*mode != new.mode, StillImage),
            (*rays_per_pixel != new.rays_per_pixel, StillImage),
            (*trace_fraction != new.trace_fraction, StillImage),
            (*s_p != new.s_p, StillImage),
            (*max_samples != new.max_samples, StillImage),
            (*min_samples != new.min_samples, StillImage),
            (*filter != new.filter, StillImage),
            (*filter_iterations != new.filter_iterations, StillImage),
            (*filter_sigma != new.filter_sigma, StillImage),
            (*shaded != new.shaded, StillImage),
            (*refine != new.refine, StillImage),
            (*prior_rays != new.prior_rays, StillImage),
            (*prior_rays_max != new.prior_rays_max, StillImage),
            (*prior_sigma != new.prior_sigma, StillImage),
            (*residual_sigma != new.residual_sigma, StillImage),
            (*still_smoothing != new.still_smoothing, StillImage),
            (*still_samples != new.still_samples, StillImage),
            (*edges != new.edges, StillImage),
            (*crease_deg != new.crease_deg, StillImage),
            (*near_weight != new.near_weight, StillImage),
            (*level_blend != new.level_blend, StillImage),
            (*adaptive_rays != new.adaptive_rays, StillImage),
            (*pooled_residual != new.pooled_residual, StillImage),
            (*contact_detail != new.contact_detail, StillImage),
            // Only when cells are reclaimed, and how later edits invalidate: nothing shown now.
            (*stale_frames != new.stale_frames, Nothing),
            (*local_edits != new.local_edits, Nothing),
        ];
        classes
            .into_iter()
            .filter(|&(changed, _)| changed)
            .map(|(_, class)| class)
            .max()
            .unwrap_or(Nothing)
    }

    /// Whether still frames accumulate (per-pixel RTAO; HRTAO and AO off with refinement). Must agree with
    /// composite.comp.
    pub fn accumulates(&self) -> bool {
        match self.mode {
            Mode::Rtao => true,
            Mode::Hrtao | Mode::NoAo => self.refine,
            _ => false,
        }
    }

    /// These settings with the fields of the JSON object `overrides` replaced, e.g. `{"near_weight": 0}`
    /// (`--set` of the command line and the development examples). An unknown field or a value of the wrong
    /// type is an error; the result is validated.
    pub fn with_overrides(&self, overrides: &str) -> Result<AoSettings, String> {
        let mut v = serde_json::to_value(self).map_err(|e| e.to_string())?;
        let fields: serde_json::Map<String, serde_json::Value> =
            serde_json::from_str(overrides).map_err(|e| format!("settings overrides {overrides:?}: {e}"))?;
        for (k, x) in fields {
            match v.get_mut(&k) {
                Some(slot) => *slot = x,
                None => return Err(format!("settings overrides: no setting {k:?}")),
            }
        }
        let s: AoSettings = serde_json::from_value(v).map_err(|e| format!("settings overrides: {e}"))?;
        s.validate()?;
        Ok(s)
    }

    /// Checks ranges; the message names the setting.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.ao_radius.is_finite() && self.ao_radius > 0.0) {
            return Err(format!(
                "AO radius must be a positive number, got {}",
                self.ao_radius
            ));
        }
        if !(self.s_p.is_finite() && self.s_p > 0.0) {
            return Err(format!("s_p must be positive, got {}", self.s_p));
        }
        if !(self.s_nd.is_finite() && self.s_nd > 0.0) {
            return Err(format!("s_nd must be positive, got {}", self.s_nd));
        }
        if !(self.normal_offset.is_finite() && (0.0..1.0).contains(&self.normal_offset)) {
            return Err(format!(
                "normal offset must be in [0, 1) of a bin, got {}",
                self.normal_offset
            ));
        }
        if !(self.s_min.is_finite() && self.s_min > 0.0) {
            return Err(format!("s_min must be positive, got {}", self.s_min));
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
        if !(self.trace_fraction > 0.0 && self.trace_fraction <= 1.0) {
            return Err(format!(
                "trace fraction must be in (0, 1], got {}",
                self.trace_fraction
            ));
        }
        if self.max_probe == 0 || self.max_probe > 4096 {
            return Err("max probe must be in 1..=4096".into());
        }
        if self.max_samples > gpu::MAX_SAMPLES_LIMIT {
            return Err(format!(
                "max samples {} is above {}",
                self.max_samples,
                gpu::MAX_SAMPLES_LIMIT
            ));
        }
        if !(self.prior_rays.is_finite() && self.prior_rays >= 0.0) {
            return Err(format!(
                "prior rays must be a number >= 0, got {}",
                self.prior_rays
            ));
        }
        for (name, v) in [
            ("prior rays max", self.prior_rays_max),
            ("prior sigma", self.prior_sigma),
            ("residual sigma", self.residual_sigma),
            ("level blend", self.level_blend),
            ("pooled residual", self.pooled_residual),
            ("cell gradient", self.cell_gradient),
            ("contact detail", self.contact_detail),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{name} must be a number >= 0, got {v}"));
            }
        }
        if !(self.still_smoothing > 0.0 && self.still_smoothing <= 1.0) {
            return Err(format!(
                "still smoothing must be in (0, 1], got {}",
                self.still_smoothing
            ));
        }
        if !(self.max_cell_fraction.is_finite() && self.max_cell_fraction > 0.0) {
            return Err(format!(
                "max cell fraction must be positive, got {}",
                self.max_cell_fraction
            ));
        }
        if !(self.crease_deg.is_finite() && (0.0..=180.0).contains(&self.crease_deg)) {
            return Err(format!(
                "crease angle must be in 0..=180 degrees, got {}",
                self.crease_deg
            ));
        }
        if !(self.filter_sigma.is_finite() && self.filter_sigma >= 0.0) {
            return Err(format!(
                "filter sigma must be a number >= 0, got {}",
                self.filter_sigma
            ));
        }
        if !(self.near_fraction.is_finite() && (0.0..=1.0).contains(&self.near_fraction)) {
            return Err(format!(
                "near fraction must be in 0..=1 (of the AO radius), got {}",
                self.near_fraction
            ));
        }
        if !(self.near_weight.is_finite() && (0.0..=1.0).contains(&self.near_weight)) {
            return Err(format!("near weight must be in 0..=1, got {}", self.near_weight));
        }
        if self.filter_iterations > 8 {
            return Err("at most 8 filter iterations".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_named_fields_and_reject_unknown_or_invalid_ones() {
        let base = AoSettings::default();
        let s = base
            .with_overrides(r#"{"near_weight": 0, "adaptive_rays": false}"#)
            .unwrap();
        assert_eq!((s.near_weight, s.adaptive_rays), (0.0, false));
        assert_eq!(s.s_p, base.s_p);
        let err = base.with_overrides(r#"{"near_wieght": 0}"#).unwrap_err();
        assert!(err.contains("near_wieght"), "{err}");
        assert!(base.with_overrides(r#"{"near_weight": "no"}"#).is_err());
        assert!(base
            .with_overrides(r#"{"near_weight": 2}"#)
            .unwrap_err()
            .contains("near weight"));
        assert!(base.with_overrides("not json").is_err());
    }

    #[test]
    fn near_field_settings_are_checked_named_and_off_in_the_paper_mode() {
        let ours = AoSettings::default();
        assert!(ours.near_weight > 0.0);
        assert_eq!(ours.paper().near_weight, 0.0);
        for bad in [-0.5, 1.5, f32::NAN] {
            let e = AoSettings {
                near_weight: bad,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("near weight"), "{e}");
        }
        for bad in [-0.1, 1.5, f32::INFINITY] {
            let e = AoSettings {
                near_fraction: bad,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("near fraction"), "{e}");
        }
    }

    #[test]
    fn adaptive_prior_settings_are_checked_and_named() {
        assert!(AoSettings::default().validate().is_ok());
        for bad in [-1.0, f32::NAN, f32::INFINITY] {
            let e = AoSettings {
                prior_rays_max: bad,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("prior rays max"), "{e}");
            let e = AoSettings {
                prior_sigma: bad,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("prior sigma"), "{e}");
        }
        // 0 keeps k fixed at prior_rays (the shader clamps k_max up to k_min).
        assert!(AoSettings {
            prior_rays_max: 0.0,
            ..Default::default()
        }
        .validate()
        .is_ok());
    }

    #[test]
    fn still_refinement_settings_are_checked_and_named() {
        for bad in [-1.0, f32::NAN, f32::INFINITY] {
            let e = AoSettings {
                residual_sigma: bad,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("residual sigma"), "{e}");
        }
        for bad in [0.0, -0.5, 1.5, f32::NAN] {
            let e = AoSettings {
                still_smoothing: bad,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("still smoothing"), "{e}");
        }
        // 1 = no smoothing, 0 = no pooling: the refinement before them.
        assert!(AoSettings {
            still_smoothing: 1.0,
            residual_sigma: 0.0,
            ..Default::default()
        }
        .validate()
        .is_ok());
    }
}
