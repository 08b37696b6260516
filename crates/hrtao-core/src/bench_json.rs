//! The results `hrtao bench` writes (schema [`SCHEMA`]) and the report of `docs/benchmarks.md` reads: one type for
//! both sides, so a field the bench writes is a field the report can read.
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::metrics::AoError;
use crate::raster::Primary;
use crate::stats::{median, paired_ratio};
use crate::{Camera, FrameReport};

/// The paper's Table 2 columns (HRTAO's own passes; Table 1 times are their sum).
pub const HRTAO_PASSES: [&str; 4] = ["cell finder", "ray-tracing update", "per-pixel AO", "filtering"];
/// HRTAO passes that trace no ray.
pub const NON_RAY_PASSES: [&str; 3] = ["cell finder", "per-pixel AO", "filtering"];

/// Sums the milliseconds of the named sections.
pub fn section_sum(sections: &[(String, f64)], names: &[&str]) -> f64 {
    sections
        .iter()
        .filter(|(n, _)| names.contains(&n.as_str()))
        .map(|(_, ms)| ms)
        .sum()
}

pub const SCHEMA: &str = "hrtao-bench/1";

/// One rendered frame.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrameRecord {
    pub index: usize,
    /// "first" (from an empty hash map / no accumulation) or "nav".
    pub kind: String,
    pub wall_ms: f64,
    pub gpu_total_ms: f64,
    /// GPU ms per section (timestamp queries).
    pub passes: BTreeMap<String, f64>,
    /// Sum of the paper's Table 2 passes (cell finder, ray-tracing update, per-pixel AO, filtering).
    pub hrtao_passes_ms: f64,
    pub rays: u64,
    pub occupied_cells: u32,
    pub load_factor: f64,
    pub cells_inserted: u32,
    pub failed_inserts: u32,
}

impl FrameRecord {
    /// The record of frame `index` of a run (`kind`: "first", "settle" or "nav").
    pub fn new(index: usize, kind: &str, r: &FrameReport) -> FrameRecord {
        let mut passes = BTreeMap::new();
        for (name, ms) in &r.gpu_ms {
            *passes.entry(name.clone()).or_insert(0.0) += ms;
        }
        FrameRecord {
            index,
            kind: kind.into(),
            wall_ms: r.wall_ms,
            gpu_total_ms: r.gpu_total_ms,
            hrtao_passes_ms: section_sum(&r.gpu_ms, &HRTAO_PASSES),
            passes,
            rays: r.rays,
            occupied_cells: r.occupied_cells,
            load_factor: r.load_factor,
            cells_inserted: r.cells_inserted,
            failed_inserts: r.failed_inserts,
        }
    }
}

/// Medians of a set of frames.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct FrameSummary {
    pub frames: usize,
    pub wall_ms: f64,
    pub gpu_total_ms: f64,
    pub hrtao_passes_ms: f64,
    pub rays: f64,
    pub passes: BTreeMap<String, f64>,
}

impl FrameSummary {
    pub fn of(frames: &[FrameRecord]) -> FrameSummary {
        let m = |f: &dyn Fn(&FrameRecord) -> f64| median(&frames.iter().map(f).collect::<Vec<_>>());
        let mut names: Vec<&String> = frames.iter().flat_map(|f| f.passes.keys()).collect();
        names.sort();
        names.dedup();
        let passes = names
            .into_iter()
            .map(|n| {
                let v: Vec<f64> = frames.iter().map(|f| *f.passes.get(n).unwrap_or(&0.0)).collect();
                (n.clone(), median(&v))
            })
            .collect();
        FrameSummary {
            frames: frames.len(),
            wall_ms: m(&|f| f.wall_ms),
            gpu_total_ms: m(&|f| f.gpu_total_ms),
            hrtao_passes_ms: m(&|f| f.hrtao_passes_ms),
            rays: m(&|f| f.rays as f64),
            passes,
        }
    }

    pub fn pass(&self, name: &str) -> f64 {
        *self.passes.get(name).unwrap_or(&0.0)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModeRun {
    /// Repetitions of the first frame.
    pub first: Vec<FrameRecord>,
    /// Static frames between the first frame and the navigation (the map fills; rays per frame fall).
    #[serde(default)]
    pub settle: Vec<FrameRecord>,
    /// Navigation frames along the path.
    pub nav: Vec<FrameRecord>,
    pub first_stats: FrameSummary,
    pub nav_stats: FrameSummary,
    /// Medians over the second half of the navigation (the cache has settled).
    pub nav_late_stats: FrameSummary,
}

impl ModeRun {
    /// The run's frames and their medians (the late half: the second half of `nav`).
    pub fn new(first: Vec<FrameRecord>, settle: Vec<FrameRecord>, nav: Vec<FrameRecord>) -> ModeRun {
        let late = &nav[nav.len() / 2..];
        ModeRun {
            settle,
            first_stats: FrameSummary::of(&first),
            nav_stats: FrameSummary::of(&nav),
            nav_late_stats: FrameSummary::of(late),
            first,
            nav,
        }
    }

    /// This run's navigation cost over `base`'s, frame by frame (`stats::paired_ratio`): the whole frame, or
    /// one pass.
    pub fn nav_paired_ratio(&self, base: &ModeRun, pass: Option<&str>) -> f64 {
        let cost = |run: &ModeRun| -> Vec<f64> {
            run.nav
                .iter()
                .map(|f| match pass {
                    Some(p) => f.passes.get(p).copied().unwrap_or(f64::NAN),
                    None => f.gpu_total_ms,
                })
                .collect()
        };
        paired_ratio(&cost(self), &cost(base))
    }
}

/// Table 1, Table 2 and the throughput ratios.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Summary {
    /// Table 1 "HRTAO 0s": sum of the four HRTAO passes of the first frame (GPU ms, median).
    pub first_ms: f64,
    /// Table 1 "HRTAO nav.": median over the navigation frames of the same sum.
    pub nav_ms: f64,
    pub nav_over_first: f64,
    /// The same with whole frames (primary visibility, clear and composite included).
    pub first_frame_gpu_ms: f64,
    pub nav_frame_gpu_ms: f64,
    pub nav_over_first_frame: f64,
    pub first_wall_ms: f64,
    pub nav_wall_ms: f64,
    /// Table 2: the first frame's HRTAO passes (GPU ms, medians).
    pub cell_finder_ms: f64,
    pub ray_tracing_update_ms: f64,
    pub per_pixel_ao_ms: f64,
    pub filtering_ms: f64,
    pub primary_visibility_ms: f64,
    /// (cell finder + per-pixel AO + filtering) / HRTAO passes of the first frame.
    pub non_ray_share: f64,
    /// Non-ray part of the whole first frame: everything but primary visibility and the ray-tracing update.
    pub non_ray_share_frame: f64,
    /// Per-pixel RTAO at the same B: first frame and navigation, whole frame GPU ms.
    pub rtao_frame_gpu_ms: f64,
    pub rtao_nav_frame_gpu_ms: f64,
    /// Raw AO-ray throughput (rays/ms): per-pixel RTAO rays / (primary visibility + per-pixel RTAO).
    pub raw_rays_per_ms: f64,
    /// Raw AO-ray throughput of the AO pass alone: rays / per-pixel RTAO.
    pub raw_pass_rays_per_ms: f64,
    /// HRTAO ray pass throughput: first-frame rays / ray-tracing update.
    pub hrtao_rays_per_ms: f64,
    pub hrtao_fraction_of_raw: f64,
    pub hrtao_fraction_of_raw_pass: f64,
    pub hrtao_first_rays: f64,
    pub rtao_first_rays: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HrtaoPoint {
    pub frame: usize,
    pub rays_per_pixel: f64,
    pub mae: f64,
    pub rmse: f64,
    /// Per-pixel RTAO error at the same cumulated rays (log-log interpolation on its curve; NaN outside).
    pub rtao_mae_same_rays: f64,
    pub rtao_rmse_same_rays: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Quality {
    /// Pixels with geometry (per-pixel RTAO traces B rays on each).
    pub covered_pixels: u64,
    pub step: u32,
    pub max_rays: u32,
    /// The reference: per-pixel RTAO samples max_rays..max_rays+ref_rays of each pixel's sequence.
    pub ref_rays: u32,
    /// MAE between the reference's two halves / 2: the reference's own noise.
    pub ref_noise_mae: f64,
    /// Per-pixel RTAO: error after N rays per pixel (N = step, 2 step, ... max_rays).
    pub rtao_curve: Vec<CurvePoint>,
    /// Per-pixel RTAO, one frame at the bench's B.
    pub rtao_same_b: CurvePoint,
    /// HRTAO from an empty map, static camera, frame by frame.
    pub hrtao_curve: Vec<HrtaoPoint>,
    /// Mean |ΔAO| between consecutive HRTAO frames of the still camera after frame 4 (None: too few frames).
    #[serde(default)]
    pub hrtao_flicker: Option<f64>,
    /// The same run and flicker with the paper's behaviour (`AoSettings::paper`).
    #[serde(default)]
    pub paper_curve: Vec<HrtaoPoint>,
    #[serde(default)]
    pub paper_flicker: Option<f64>,
    /// Per-pixel rays needed to match HRTAO's one-frame MAE / RMSE, and their ratio to HRTAO's rays.
    pub match_mae: Match,
    pub match_rmse: Match,
    pub rays_ratio_mae: f64,
    pub rays_ratio_rmse: f64,
    /// Against the independent --reference image, when given: [converged RTAO, RTAO at B, HRTAO 1 frame,
    /// HRTAO last frame].
    pub external: Option<ExternalErrors>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ExternalErrors {
    pub path: String,
    pub reference_vs_external: ImageError,
    pub rtao_same_b: ImageError,
    pub hrtao_first: ImageError,
    pub hrtao_last: ImageError,
}

/// An image error (the core's `AoError`, serialisable both ways).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct ImageError {
    pub mae: f64,
    pub rmse: f64,
    pub pixels: usize,
}

impl From<AoError> for ImageError {
    fn from(e: AoError) -> Self {
        ImageError {
            mae: e.mae,
            rmse: e.rmse,
            pixels: e.pixels,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneInfo {
    pub spec: String,
    pub label: String,
    pub group: String,
    pub meshes: usize,
    pub instances: usize,
    pub unique_triangles: u64,
    pub instanced_triangles: u64,
    pub load_ms: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Memory {
    pub host_rss_bytes: u64,
    pub host_peak_bytes: u64,
    /// Device memory allocated after the scene upload and acceleration structures.
    pub device_scene_bytes: u64,
    /// Device memory with the renderer (targets, hash map) too.
    pub device_total_bytes: u64,
    /// "allocator" (`Gpu::device_memory_bytes`) or "estimate" (sizes summed here when the counter is unusable).
    #[serde(default)]
    pub device_bytes_source: String,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HostInfo {
    pub cpu_cores: usize,
    pub cpu_model: String,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BenchResult {
    pub schema: String,
    pub date: String,
    pub unix_time: u64,
    pub host: HostInfo,
    pub device: serde_json::Value,
    pub scene: SceneInfo,
    pub build: serde_json::Value,
    pub memory: Memory,
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    /// Primary visibility of every mode (`setup::Device::install`; results without it used ray queries).
    #[serde(default)]
    pub primary: Primary,
    pub settings: serde_json::Value,
    /// "orbit" or "path", and the navigation frame count.
    pub navigation: String,
    pub nav_frames: usize,
    pub hrtao: ModeRun,
    /// HRTAO as the paper has it (`AoSettings::paper`: our additions off), over the same cameras.
    #[serde(default)]
    pub paper: Option<ModeRun>,
    pub rtao: ModeRun,
    pub summary: Summary,
    pub quality: Option<Quality>,
    pub validation_messages: u32,
    pub total_bench_s: f64,
}

/// One point of an error-versus-rays curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    /// Rays traced per covered pixel, cumulated.
    pub rays_per_pixel: f64,
    pub mae: f64,
    pub rmse: f64,
}

/// Where a target error falls on a curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MatchKind {
    /// Between two measured points (log-log interpolation).
    Interpolated,
    /// Already reached at the first point: the number is an upper bound (extrapolated below it).
    BelowFirst,
    /// Not reached within the measured range: extrapolated along the power-law tail (a lower bound at least
    /// equal to the last measured rays).
    BeyondLast,
    /// The curve has fewer than two usable points.
    Unknown,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Match {
    pub rays_per_pixel: f64,
    pub kind: MatchKind,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn section_sums() {
        let s = vec![
            ("cell finder".to_string(), 1.0),
            ("ray-tracing update".to_string(), 2.0),
            ("primary visibility".to_string(), 4.0),
        ];
        assert_eq!(section_sum(&s, &HRTAO_PASSES), 3.0);
        assert_eq!(section_sum(&s, &NON_RAY_PASSES), 1.0);
    }
}
