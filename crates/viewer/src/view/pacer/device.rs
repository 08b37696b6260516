//! What the device affords: its class (a CPU rasteriser such as lavapipe, or a GPU), the display's refresh
//! interval, and the cost of a moving frame learned from the frames measured, `frame = floor + rays × ms_per_ray`
//! (the floor: every pass but the ray-tracing update, the UI, the submission). From it come the per-class
//! defaults the pacer starts from: the frame-time target (the refresh on a GPU, 100 ms on a CPU), the first ray
//! budget (the paper's 10 rays per pixel where the device affords them, §6 / Table 1), the moving frames' filter
//! and render scale; and the rays that fit in the target, which size the budget (`budget::next_rays_per_frame`)
//! instead of blind steps. Pure: measurements come in as numbers.
use super::budget::{self, RayFit, MAX_RAYS_PER_FRAME, MIN_RAYS_PER_FRAME};
use super::motion::{MIN_MOVING_SCALE, MOVING_FILTER_ITERATIONS};

/// The frame-time target of a software device: its frames take 50-150 ms at the reduced moving scale.
pub const SOFTWARE_TARGET_MS: f64 = 100.0;
/// A GPU whose display reports no refresh rate (Xvfb, some Wayland compositors) aims at 60 Hz.
pub const DEFAULT_REFRESH_MS: f64 = 1000.0 / 60.0;
/// A frame that waited longer than this for its swapchain image was paced by the display.
const PACED_WAIT_MS: f64 = 0.5;
/// Present intervals of display-paced frames kept; their median is the refresh where the display reports none.
const PRESENT_SAMPLES: usize = 15;
/// Display-paced frames needed before their intervals stand for the refresh.
const MIN_PRESENT_SAMPLES: usize = 8;
/// Refresh rates outside 20-500 Hz are taken for a misreport.
const REFRESH_MS_RANGE: (f64, f64) = (1000.0 / 500.0, 1000.0 / 20.0);
/// The paper's budget (Table 1: 10 rays per pixel at 1080p): the first moving frame's rays per pixel at most.
pub const PAPER_RAYS_PER_PIXEL: f64 = 10.0;
/// An AO ray costs about twice a primary one (1.5-2.5× on lavapipe, bundled scene and san_francisco): the
/// primary probe's rate halved is the first estimate of the AO rays' rate.
pub const AO_RAY_COST: f64 = 2.0;
/// The share of a GPU's frame-time target the first frame spends on AO rays, priced by the probe: the first
/// frames trace a young map, whose rays reach unseen geometry and cost more than the probe's.
pub const FIRST_FRAME_SHARE: f64 = 0.6;
/// A GPU with no probe (no rasteriser to compare, or a scene too large for the trial) is priced at 1 Grays/s
/// (the paper's slowest scene: Endeavor's 20.7 M rays in 26.1 ms on a Quadro RTX 8000).
const GPU_PRIOR_MS_PER_RAY: f64 = 1e-6;
/// The share of the target a moving frame's predicted cost aims at: a margin for the frames' noise.
pub const FILL: f64 = 0.85;
/// The share of the target a moving frame's AO rays keep whatever the floor. Where the floor alone fills the
/// target (a CPU at its smallest moving scale, a large scene's primary visibility), fewer rays bring the frame
/// no closer to it (the render scale is what cuts the floor) and only starve the moving image: the bundled
/// scene on lavapipe, whose 280×280 moving frames cost ~90 ms without rays, fell to the 1,000-ray minimum
/// (one ray from 1 pixel in 16), where 25 ms of rays are ~20k. A frame still over the target with its rays at
/// this share is the floor's.
pub const MIN_RAY_SHARE: f64 = 0.25;
/// While the rays' price is still the probe's guess (no frame has measured it since the scene opened: the ray
/// pass's own time, or a line through frames whose rays differ), the least is this share of `MIN_RAY_SHARE`'s
/// rays: a primary ray hits near, and an AO ray into unseen geometry may cost several (up to ~7×) of them.
/// Frames of one ray count cannot tell the rays' cost from the floor's, and probing the price by varying the
/// budget was tried and left: on lavapipe the rays traced over cached geometry are ~2 ms of a ~100 ms frame,
/// and the line through such frames priced a ray at 5-11 µs now and then (it costs ~1.4 µs), which sized the
/// first still image for rays 8× too dear (lattice 12 at half its rays: 78-82 s to converge instead of 47-50).
pub const GUESSED_SHARE: f64 = 0.5;
/// Weight of a measurement below the estimate (one above it replaces it: latency wins, a frame over the target
/// must not wait for an average).
const FALL_EMA: f64 = 0.3;
/// Frames that trace fewer rays than this say nothing of the rays' cost (the pass's own overhead dominates).
const MIN_PRICED_RAYS: u64 = 1_000;
/// Moving frames fitted when the device has no per-pass times (the last ones: the view changes).
const FIT_FRAMES: usize = 8;
/// The fewest frames on either side of the middle of the fitted rays' range: a single frame far from the
/// others decides a least-squares slope alone, and a frame's noise is ±10 % on lavapipe (the bundled scene:
/// the first moving frame's 12,281 rays against seven of ~1,100 priced a ray at 2.5 µs in one run and 0.8 µs
/// in another; a still slice's rays cost 1.4 µs there).
const MIN_FRAMES_PER_SIDE: usize = 2;
/// A fitted slope stands for the rays' price only at this many standard errors above zero (its residuals'
/// spread against the rays' spread): lavapipe's moving frames over cached geometry traced 1.1-2.7k rays in
/// 92-131 ms frames, and the line through them priced a ray at 11 µs (it costs ~1.4 µs). That price then sized
/// the first still image's slices for rays 8× too dear (lattice 12 at fewer rays: 70 s to converge, not 40).
const MIN_SLOPE_T: f64 = 3.0;

/// The kind of device, from `DeviceInfo::is_software`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceClass {
    /// A CPU rasteriser (lavapipe): frames of tens of milliseconds at a fraction of the view.
    Software,
    Gpu,
}

/// A device's defaults and its learned moving-frame cost.
#[derive(Clone, Debug)]
pub struct DeviceModel {
    pub class: DeviceClass,
    /// The display's refresh interval, when it reports one in range.
    refresh_ms: Option<f64>,
    /// Milliseconds per AO ray: from the primary probe, then from the frames.
    ms_per_ray: Option<f64>,
    /// Whether a frame measured `ms_per_ray` since the scene opened (else it is the probe's or the prior).
    measured: bool,
    /// The non-ray cost of a moving frame, milliseconds.
    floor_ms: Option<f64>,
    /// (rays, frame ms) of the last moving frames, for frames without the ray pass's own time, all of
    /// `recent_pixels` pixels (a frame of another size has another floor).
    recent: Vec<(f64, f64)>,
    recent_pixels: u64,
    /// Intervals between display-paced frames (`observe_present`), while the display reports no refresh.
    presents: Vec<f64>,
}

impl DeviceModel {
    /// `software`: `DeviceInfo::is_software`; `refresh_mhz`: the window's monitor's refresh rate in millihertz
    /// (winit's `refresh_rate_millihertz`), None when unknown.
    pub fn new(software: bool, refresh_mhz: Option<u32>) -> DeviceModel {
        let mut model = DeviceModel {
            class: if software {
                DeviceClass::Software
            } else {
                DeviceClass::Gpu
            },
            refresh_ms: None,
            ms_per_ray: None,
            measured: false,
            floor_ms: None,
            recent: Vec::new(),
            recent_pixels: 0,
            presents: Vec::new(),
        };
        model.display_refresh(refresh_mhz);
        model
    }

    /// The display's refresh rate in millihertz (None, 0 or out of range: unknown).
    pub fn display_refresh(&mut self, refresh_mhz: Option<u32>) {
        self.refresh_ms = refresh_mhz
            .filter(|&m| m > 0)
            .map(|m| 1e6 / m as f64)
            .filter(|ms| (REFRESH_MS_RANGE.0..=REFRESH_MS_RANGE.1).contains(ms));
    }

    /// The frame-time target when the user set none: a frame per refresh on a GPU (the display's, else the
    /// one its presents show, else 60 Hz), 100 ms on a CPU.
    pub fn target_ms(&self) -> f64 {
        match self.class {
            DeviceClass::Software => SOFTWARE_TARGET_MS,
            DeviceClass::Gpu => self
                .refresh_ms
                .or_else(|| self.presented_refresh_ms())
                .unwrap_or(DEFAULT_REFRESH_MS),
        }
    }

    /// After a frame presented `interval_ms` after the last one, having waited `waited_ms` for its swapchain
    /// image: where the display reports no refresh, the intervals of frames the display paced (they waited)
    /// measure it. Frames that did not wait say nothing (the device, not the display, set their pace).
    pub fn observe_present(&mut self, interval_ms: f64, waited_ms: f64) {
        let in_range = (REFRESH_MS_RANGE.0..=REFRESH_MS_RANGE.1).contains(&interval_ms);
        if self.refresh_ms.is_some() || !(waited_ms > PACED_WAIT_MS && in_range) {
            return;
        }
        self.presents.push(interval_ms);
        if self.presents.len() > PRESENT_SAMPLES {
            self.presents.remove(0);
        }
    }

    /// The median interval of the display-paced frames, once there are enough of them.
    fn presented_refresh_ms(&self) -> Option<f64> {
        if self.presents.len() < MIN_PRESENT_SAMPLES {
            return None;
        }
        let mut v = self.presents.clone();
        v.sort_by(f64::total_cmp);
        Some(v[v.len() / 2])
    }

    /// The first moving frames' render scale: a CPU starts at the smallest (its frames at full size take
    /// seconds), a GPU at the full view.
    pub fn first_moving_scale(&self) -> f32 {
        match self.class {
            DeviceClass::Software => MIN_MOVING_SCALE,
            DeviceClass::Gpu => 1.0,
        }
    }

    /// À-trous iterations of a moving frame for the user's `iterations`: all of them on a GPU (the paper's
    /// filter costs 0.4-2.2 ms at 1080p, Table 2), one on a CPU (each iteration a full pass over the image).
    pub fn moving_filter_iterations(&self, iterations: u32) -> u32 {
        match self.class {
            DeviceClass::Software => iterations.min(MOVING_FILTER_ITERATIONS),
            DeviceClass::Gpu => iterations,
        }
    }

    /// A scene's first ray budget from its primary probe (`pixels` ray-query primary rays in `probe_ms`, NaN
    /// when it did not run) for moving frames of `moving_pixels`. A CPU: the rays the probe traced in a quarter
    /// of the target, at most the default (`budget::first_rays_per_frame`). A GPU: the AO rays the probe's rate
    /// prices in `FIRST_FRAME_SHARE` of the target, at most the paper's 10 rays per pixel.
    pub fn first_rays(&mut self, probe_ms: f64, pixels: u64, moving_pixels: u64, target_ms: f64) -> u32 {
        let probed = probe_ms.is_finite() && probe_ms > 0.0 && pixels > 0;
        if probed {
            self.ms_per_ray = Some(probe_ms * AO_RAY_COST / pixels as f64);
        }
        self.measured = false;
        self.floor_ms = None;
        self.recent.clear();
        match self.class {
            DeviceClass::Software => budget::first_rays_per_frame(probe_ms, pixels, target_ms),
            DeviceClass::Gpu => {
                let per_ray = self.ms_per_ray.filter(|_| probed).unwrap_or(GPU_PRIOR_MS_PER_RAY);
                let affordable = FIRST_FRAME_SHARE * target_ms.max(0.0) / per_ray;
                let paper = PAPER_RAYS_PER_PIXEL * moving_pixels.max(1) as f64;
                clamp_rays(affordable.min(paper))
            }
        }
    }

    /// After a moving frame of `frame_ms` (its wait for the swapchain left out) that traced `rays`, `ray_ms` of
    /// them in the ray-tracing update when the device's timestamps measure it, at `pixels`: the floor and the
    /// rays' cost. Without the pass's time, a least-squares line through the last moving frames of the same
    /// size, where their rays differ enough to tell the slope; else the floor under the last rays' cost.
    pub fn observe(&mut self, frame_ms: f64, rays: u64, ray_ms: Option<f64>, pixels: u64) {
        if !(frame_ms.is_finite() && frame_ms >= 0.0) {
            return;
        }
        let priced = rays >= MIN_PRICED_RAYS;
        match ray_ms.filter(|ms| ms.is_finite() && *ms >= 0.0 && *ms <= frame_ms) {
            Some(ms) => {
                if priced {
                    self.ms_per_ray = Some(rise_or_fall(self.ms_per_ray, ms / rays as f64));
                    self.measured = true;
                }
                self.floor_ms = Some(rise_or_fall(self.floor_ms, frame_ms - ms));
            }
            None => {
                if pixels != self.recent_pixels {
                    self.recent.clear();
                    self.recent_pixels = pixels;
                }
                self.recent.push((rays as f64, frame_ms));
                if self.recent.len() > FIT_FRAMES {
                    self.recent.remove(0);
                }
                if let Some((floor, per_ray)) = fit_line(&self.recent).filter(|_| priced) {
                    self.ms_per_ray = Some(rise_or_fall(self.ms_per_ray, per_ray));
                    self.floor_ms = Some(floor);
                    self.measured = true;
                } else {
                    let rays_ms = self.ms_per_ray.map_or(0.0, |c| c * rays as f64);
                    self.floor_ms = Some(rise_or_fall(self.floor_ms, (frame_ms - rays_ms).max(0.0)));
                }
            }
        }
    }

    /// The rays a moving frame can trace in `FILL` of `target_ms` over its floor, and the rays of
    /// `MIN_RAY_SHARE` of the target it keeps whatever the floor (a floor over the target leaves the render
    /// scale to cut); None before the device's rays were priced.
    pub fn rays_that_fit(&self, target_ms: f64) -> Option<RayFit> {
        let per_ray = self.ms_per_ray.filter(|c| *c > 0.0)?;
        let floor = self.floor_ms?;
        let guess = if self.measured { 1.0 } else { GUESSED_SHARE };
        let least = guess * MIN_RAY_SHARE * target_ms.max(0.0);
        Some(RayFit {
            fits: clamp_rays((FILL * target_ms - floor).max(least) / per_ray),
            least: clamp_rays(least / per_ray),
        })
    }

    /// The learned (floor ms, ms per ray), for the log and the tests.
    pub fn cost(&self) -> (Option<f64>, Option<f64>) {
        (self.floor_ms, self.ms_per_ray)
    }
}

fn clamp_rays(rays: f64) -> u32 {
    if rays.is_nan() {
        return MIN_RAYS_PER_FRAME;
    }
    (rays.round().min(u32::MAX as f64) as u32).clamp(MIN_RAYS_PER_FRAME, MAX_RAYS_PER_FRAME)
}

/// A rise replaces the estimate, a fall is smoothed.
fn rise_or_fall(estimate: Option<f64>, x: f64) -> f64 {
    match estimate {
        Some(e) if x < e => e + FALL_EMA * (x - e),
        _ => x,
    }
}

/// The least-squares line ms = floor + rays × per_ray through `points`, where the rays spread by at least a
/// fifth of their mean (else the slope is noise), at least `MIN_FRAMES_PER_SIDE` frames lie on each side of
/// the middle of the rays' range (else one frame decides the slope, and its noise with it), and the slope
/// comes out positive by `MIN_SLOPE_T` standard errors.
fn fit_line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    if n < 2.0 {
        return None;
    }
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.0), hi.max(p.0))
        });
    let above = points.iter().filter(|p| p.0 > 0.5 * (lo + hi)).count();
    if above.min(points.len() - above) < MIN_FRAMES_PER_SIDE {
        return None;
    }
    let (sx, sy) = points.iter().fold((0.0, 0.0), |(x, y), p| (x + p.0, y + p.1));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if mx <= 0.0 || (sxx / n).sqrt() < 0.2 * mx {
        return None;
    }
    let per_ray = sxy / sxx;
    let floor = my - per_ray * mx;
    let residual: f64 = points.iter().map(|p| (p.1 - floor - per_ray * p.0).powi(2)).sum();
    let standard_error = (residual / (n - 2.0).max(1.0) / sxx).sqrt();
    (per_ray > MIN_SLOPE_T * standard_error).then(|| (floor.max(0.0), per_ray))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_target_is_the_refresh_on_a_gpu_and_100_ms_on_a_cpu() {
        assert_eq!(
            DeviceModel::new(true, Some(144_000)).target_ms(),
            SOFTWARE_TARGET_MS
        );
        let rtx = DeviceModel::new(false, Some(144_000)).target_ms();
        assert!((rtx - 6.944).abs() < 0.01, "{rtx}");
        // No refresh reported, or a misreport: 60 Hz.
        assert_eq!(DeviceModel::new(false, None).target_ms(), DEFAULT_REFRESH_MS);
        assert_eq!(DeviceModel::new(false, Some(0)).target_ms(), DEFAULT_REFRESH_MS);
        assert_eq!(DeviceModel::new(false, Some(5)).target_ms(), DEFAULT_REFRESH_MS);
    }

    #[test]
    fn a_gpu_filters_moving_frames_fully_a_cpu_once() {
        assert_eq!(DeviceModel::new(false, None).moving_filter_iterations(3), 3);
        assert_eq!(DeviceModel::new(true, None).moving_filter_iterations(3), 1);
        assert_eq!(DeviceModel::new(true, None).moving_filter_iterations(0), 0);
        assert_eq!(DeviceModel::new(false, None).first_moving_scale(), 1.0);
        assert_eq!(
            DeviceModel::new(true, None).first_moving_scale(),
            MIN_MOVING_SCALE
        );
    }

    /// A GPU starts at the paper's 10 rays per pixel where its probe affords them, fewer where not; a CPU from
    /// its probe as before. Fails with the paper's cap left out (an RTX's probe prices 28 rays per pixel).
    #[test]
    fn the_first_budget_follows_the_probe_up_to_the_papers_rays_per_pixel() {
        let px = 1920 * 1080;
        // An RTX-class probe: 2.07 M primary rays in 0.2 ms.
        let rtx = DeviceModel::new(false, Some(144_000)).first_rays(0.2, px, px, 6.94);
        assert_eq!(rtx as f64, (PAPER_RAYS_PER_PIXEL * px as f64).round());
        // A mid-range one: 1 ms; priced to ~4.8 rays per pixel in 60 % of 16.7 ms.
        let mid = DeviceModel::new(false, Some(60_000)).first_rays(1.04, px, px, 16.67) as f64 / px as f64;
        assert!((4.0..6.0).contains(&mid), "{mid}");
        // No probe: 1 Grays/s.
        let none = DeviceModel::new(false, None).first_rays(f64::NAN, px, px, 16.67);
        assert_eq!(none, 10_002_000);
        // A CPU: the probe's rays in a quarter of the target, as before.
        let cpu = DeviceModel::new(true, None).first_rays(459.0, 960 * 800, 960 * 800, 100.0);
        assert_eq!(cpu, budget::first_rays_per_frame(459.0, 960 * 800, 100.0));
    }

    /// A display that reports no refresh (Xvfb, some compositors): a GPU's target becomes the interval of the
    /// frames the display paced, once 8 did; frames that did not wait, intervals out of range, a software
    /// device and a reported refresh are left alone. Fails with `observe_present` counting every frame (the
    /// 30 ms device-paced frames pull the median).
    #[test]
    fn a_gpu_without_a_reported_refresh_takes_it_from_its_presents() {
        let mut m = DeviceModel::new(false, None);
        for i in 0..7 {
            m.observe_present(6.94, 2.0);
            m.observe_present(30.0 + i as f64, 0.0);
        }
        assert_eq!(m.target_ms(), DEFAULT_REFRESH_MS, "7 paced frames are not enough");
        m.observe_present(6.95, 1.0);
        m.observe_present(1e4, 5.0);
        assert!((m.target_ms() - 6.94).abs() < 0.02, "{}", m.target_ms());
        let mut cpu = DeviceModel::new(true, None);
        let mut reported = DeviceModel::new(false, Some(60_000));
        for _ in 0..20 {
            cpu.observe_present(6.94, 2.0);
            reported.observe_present(6.94, 2.0);
        }
        assert_eq!(cpu.target_ms(), SOFTWARE_TARGET_MS);
        assert!((reported.target_ms() - 16.667).abs() < 0.01);
    }

    /// With the ray pass timed, the floor and the rays' cost come from it; without, from a line through frames
    /// whose rays differ. A rise counts at once, a fall is smoothed; bad input changes nothing.
    #[test]
    fn the_model_learns_the_floor_and_the_rays_cost() {
        let mut m = DeviceModel::new(false, None);
        m.observe(5.0, 2_000_000, Some(4.0), 1);
        assert_eq!(m.cost(), (Some(1.0), Some(2e-6)));
        // 5.8 ms fit in 0.85 × 8 ms: 2.9 M rays.
        assert_eq!(m.rays_that_fit(8.0).map(|f| f.fits), Some(2_900_000));
        m.observe(9.0, 2_000_000, Some(8.0), 1);
        assert_eq!(m.cost().1, Some(4e-6), "a rise counts at once");
        m.observe(5.0, 2_000_000, Some(4.0), 1);
        assert!((m.cost().1.unwrap() - 3.4e-6).abs() < 1e-12, "a fall is smoothed");
        let before = m.cost();
        m.observe(f64::NAN, 1, None, 1);
        m.observe(-1.0, 1, Some(f64::INFINITY), 1);
        assert_eq!(m.cost(), before);
        // No pass times: 30 ms + rays × 4 µs, fitted.
        let mut cpu = DeviceModel::new(true, None);
        for rays in [10_000u64, 20_000, 5_000, 15_000] {
            cpu.observe(30.0 + rays as f64 * 4e-3, rays, None, 1000);
        }
        let (floor, per_ray) = cpu.cost();
        assert!((floor.unwrap() - 30.0).abs() < 1e-6 && (per_ray.unwrap() - 4e-3).abs() < 1e-9);
        assert_eq!(
            cpu.rays_that_fit(100.0),
            Some(RayFit {
                fits: 13_750,
                least: 6_250
            })
        );
    }

    /// A floor that alone fills the target leaves the rays their share, not the minimum budget: the bundled
    /// scene's moving frames on lavapipe (~90 ms at 280×280 without rays, the probe's 0.94 µs an AO ray).
    /// Fails with `MIN_RAY_SHARE` left out of `rays_that_fit` (1,000 rays).
    #[test]
    fn a_floor_over_the_target_leaves_the_rays_their_share() {
        let mut m = DeviceModel::new(true, None);
        m.first_rays(300.0, 640_000, 78_400, SOFTWARE_TARGET_MS);
        for _ in 0..4 {
            m.observe(95.0, 1_100, None, 78_400);
        }
        let fit = m.rays_that_fit(SOFTWARE_TARGET_MS).expect("priced");
        let per_ray = m.cost().1.unwrap();
        assert!((per_ray - 0.9375e-3).abs() < 1e-9, "{per_ray}");
        assert_eq!(fit.fits, fit.least);
        assert_eq!(fit.least, (0.5 * 25.0 / per_ray).round() as u32);
    }

    /// Frames whose rays differ by less than their noise does not price the rays: lavapipe's moving frames
    /// over cached geometry (frame ms, traced rays) as recorded by `hrtao view --stats`, the budget
    /// alternating between two values. Fails without `MIN_SLOPE_T` (11 µs a ray).
    #[test]
    fn frames_whose_rays_differ_by_less_than_their_noise_do_not_price_the_rays() {
        let frames = [
            (2_668u64, 128.0),
            (1_215, 119.0),
            (2_456, 131.0),
            (1_345, 106.0),
            (2_475, 102.0),
            (1_222, 123.0),
            (2_473, 120.0),
            (1_417, 114.0),
        ];
        let mut m = DeviceModel::new(true, None);
        m.first_rays(300.0, 640_000, 78_400, SOFTWARE_TARGET_MS);
        for (rays, ms) in frames {
            m.observe(ms, rays, None, 78_400);
        }
        let (_, per_ray) = m.cost();
        assert!((per_ray.unwrap() - 0.9375e-3).abs() < 1e-9, "{per_ray:?}");
        assert_eq!(m.rays_that_fit(SOFTWARE_TARGET_MS).unwrap().least, 13_333);
    }

    /// One frame far from the others does not price the rays: lavapipe's moving frames of the bundled scene
    /// after its install (frame ms, rays) as recorded by `hrtao view --stats`, the young map's first frame
    /// 14 ms over seven frames of ~1,100 rays. Fails without `MIN_FRAMES_PER_SIDE` (2.5 µs a ray from this
    /// run, 0.8 µs from another of the same build: the first still image's slices were priced over four
    /// times the target and it took lattice 12 at half its rays, converging in 88 s instead of 50).
    #[test]
    fn one_frame_far_from_the_others_does_not_price_the_rays() {
        let frames = [
            (12_281u64, 140.0),
            (1_148, 126.0),
            (1_169, 108.0),
            (1_084, 110.0),
            (1_108, 101.0),
            (1_197, 118.0),
            (1_114, 109.0),
            (1_087, 118.0),
        ];
        let mut m = DeviceModel::new(true, None);
        m.first_rays(f64::NAN, 0, 78_400, SOFTWARE_TARGET_MS);
        for (rays, ms) in frames {
            m.observe(ms, rays, None, 78_400);
        }
        assert_eq!(m.cost().1, None, "{:?}", m.cost());
        assert!((100.0..120.0).contains(&m.cost().0.unwrap()), "{:?}", m.cost());
    }
}
