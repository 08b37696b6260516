//! The viewer's ray budget: rays per frame, independent of the internal resolution (the hash map shares rays
//! between the pixels of a cell, §3, so full resolution need not multiply the AO cost), converted each frame to
//! the renderer's rays per pixel; and the frame-time target controller that adapts it while the camera moves.

/// A moving frame's rays as the device model prices them (`DeviceModel::rays_that_fit`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RayFit {
    /// The rays that fit in the target over the floor, at least `least`.
    pub fits: u32,
    /// The rays of `device::MIN_RAY_SHARE` of the target (`device::GUESSED_SHARE` of that while the price is
    /// the probe's guess): a budget is never cut below them.
    pub least: u32,
}

/// Default budget: about today's 4 rays per pixel at the software default of 0.35 × an 862×800 view.
pub const DEFAULT_RAYS_PER_FRAME: u32 = 300_000;
pub const MIN_RAYS_PER_FRAME: u32 = 1_000;
pub const MAX_RAYS_PER_FRAME: u32 = 64_000_000;
/// The renderer's per-pixel budget is an integer of at least 1 (0 would stop the AO update altogether).
pub const MAX_RAYS_PER_PIXEL: u32 = 64;

/// The smallest fraction of the pixels that trace in a frame (`RayBudget::trace_fraction`): below it a cell of
/// the finest level (a pixel or two while moving) would wait too many frames for a ray.
pub const MIN_TRACE_FRACTION: f32 = 1.0 / 16.0;

/// The renderer's budget for `rays_per_frame` spread over `width`×`height` internal pixels: rays per pixel,
/// rounded, within 1..=MAX_RAYS_PER_PIXEL, and below one ray per pixel the fraction of the pixels that trace
/// (at least MIN_TRACE_FRACTION), so the budget holds at full resolution too.
pub fn per_pixel_budget(rays_per_frame: u32, width: u32, height: u32) -> (u32, f32) {
    let pixels = (width.max(1) as f64) * (height.max(1) as f64);
    let per_pixel = rays_per_frame as f64 / pixels;
    let rpp = (per_pixel.round() as u32).clamp(1, MAX_RAYS_PER_PIXEL);
    let fraction = (per_pixel as f32).clamp(MIN_TRACE_FRACTION, 1.0);
    (rpp, fraction)
}

/// The share of the frame-time target a scene's first frame spends on AO rays, priced at the primary probe's
/// rate: an AO ray costs about 1.5-2.5× a primary one here (bundled scene, san_francisco).
pub const FIRST_FRAME_RAY_SHARE: f64 = 0.25;

/// A scene's first ray budget: the rays its primary probe traced (`pixels` ray-query primary rays in `probe_ms`,
/// `Renderer::pick_primary`) in `FIRST_FRAME_RAY_SHARE` of `target_ms`, within MIN..=DEFAULT; the default when
/// the probe did not run (NaN). A young map's first frame traces for every pixel: at the default, san_francisco's
/// took ~400 ms on lavapipe, and input that came meanwhile waited for it. The frame-time target adapts the
/// budget from there in moving frames.
pub fn first_rays_per_frame(probe_ms: f64, pixels: u64, target_ms: f64) -> u32 {
    if !(probe_ms.is_finite() && probe_ms > 0.0) || pixels == 0 {
        return DEFAULT_RAYS_PER_FRAME;
    }
    let rays = pixels as f64 / probe_ms * target_ms * FIRST_FRAME_RAY_SHARE;
    (rays.round().min(u32::MAX as f64) as u32).clamp(MIN_RAYS_PER_FRAME, DEFAULT_RAYS_PER_FRAME)
}

/// A frame that traced at least this share of the rays it was granted used its budget: only then may the budget
/// grow. Over cached geometry most cells take no rays, so a budget grown on such frames' slack (up to 64 M
/// rays before this rule) would trace ~31 rays per pixel at 1080p at the next swing into unseen geometry.
pub const USED_SHARE: f64 = 0.8;
/// The most a budget grows in one frame, whatever the model says fits (its estimate may be young).
pub const MAX_GROWTH: f64 = 2.0;

/// One step of the frame-time controller (the paper, §6: "the ray budget can be adjusted to match a target
/// rendering speed") after a moving frame of `frame_ms` that traced `traced` of its `granted` rays; `fits`: the
/// rays the device model says fit in the target and the least it keeps (`DeviceModel::rays_that_fit`), None
/// before it priced the rays. Over the target, a decrease in proportion to the excess (with a margin, as if the
/// whole frame were rays: at most 0.9, at least 0.25 per frame), never above what fits and never below the
/// least (a frame over the target with that many rays is over because of its floor: fewer rays would not
/// bring it closer). Under 0.8 of the target, and only when the granted rays were used, an increase to what
/// fits (at most `MAX_GROWTH`×; without a model, 10 %). Otherwise the budget holds, cut to what fits: frames
/// settle at or under the target (an upper bound).
pub fn next_rays_per_frame(
    rays_per_frame: u32,
    granted: f64,
    traced: u64,
    frame_ms: f64,
    target_ms: f64,
    fit: Option<RayFit>,
) -> u32 {
    let b = rays_per_frame as f64;
    let fits = fit.map(|f| f.fits as f64);
    let least = fit.map_or(0.0, |f| f.least as f64);
    let used = traced as f64 >= USED_SHARE * granted;
    let next = if frame_ms > target_ms {
        let cut = b * (0.9 * target_ms / frame_ms).clamp(0.25, 0.9);
        fits.map_or(cut, |f| f.min(cut)).max(least)
    } else if frame_ms < target_ms * 0.8 && used {
        fits.map_or(b * 1.1 + 1.0, |f| f.max(b)).min(b * MAX_GROWTH + 1.0)
    } else {
        fits.map_or(b, |f| f.min(b))
    };
    if next.is_nan() {
        return rays_per_frame.clamp(MIN_RAYS_PER_FRAME, MAX_RAYS_PER_FRAME);
    }
    (next.round() as u32).clamp(MIN_RAYS_PER_FRAME, MAX_RAYS_PER_FRAME)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_pixel_budget_follows_the_pixel_count() {
        assert_eq!(per_pixel_budget(300_000, 302, 280), (4, 1.0));
        assert_eq!(per_pixel_budget(300_000, 151, 140).0, 14);
        // Full resolution: one ray per pixel, from 43.5 % of the pixels each frame.
        let (rpp, fraction) = per_pixel_budget(300_000, 862, 800);
        assert_eq!(rpp, 1);
        assert!((fraction - 0.435).abs() < 0.001, "{fraction}");
        assert_eq!(per_pixel_budget(u32::MAX, 1, 1), (MAX_RAYS_PER_PIXEL, 1.0));
        assert_eq!(per_pixel_budget(0, 0, 0), (1, MIN_TRACE_FRACTION));
    }

    /// The first budget follows the scene's ray cost: the bundled scene's probe (459 ms for 960×800 ray-query
    /// primary rays on lavapipe) gives ~42k rays; a GPU's (2 ms) the default; no probe, the default.
    #[test]
    fn a_scene_starts_from_the_rays_its_probe_traced_in_the_target() {
        let px = 960 * 800;
        let lavapipe = first_rays_per_frame(459.0, px, 100.0);
        assert!((41_000..43_000).contains(&lavapipe), "{lavapipe}");
        assert!(first_rays_per_frame(1300.0, px, 100.0) < lavapipe / 2);
        assert_eq!(first_rays_per_frame(2.0, px, 100.0), DEFAULT_RAYS_PER_FRAME);
        assert_eq!(first_rays_per_frame(f64::NAN, px, 100.0), DEFAULT_RAYS_PER_FRAME);
        assert_eq!(first_rays_per_frame(1e9, px, 100.0), MIN_RAYS_PER_FRAME);
    }

    /// The old steps where the model has not priced the rays yet and the rays were used.
    fn step(b: u32, frame_ms: f64, target_ms: f64) -> u32 {
        next_rays_per_frame(b, b as f64, b as u64, frame_ms, target_ms, None)
    }

    #[test]
    fn controller_settles_near_the_target() {
        assert_eq!(step(100_000, 200.0, 100.0), 45_000);
        assert_eq!(step(100_000, 1000.0, 100.0), 25_000);
        assert_eq!(step(100_000, 100.0, 100.0), 100_000);
        assert_eq!(step(100_000, 105.0, 100.0), 85_714);
        assert!(step(100_000, 50.0, 100.0) > 100_000);
        assert_eq!(step(MIN_RAYS_PER_FRAME, 1e6, 100.0), MIN_RAYS_PER_FRAME);
        assert_eq!(step(100_000, f64::NAN, 100.0), 100_000);
        // A frame time proportional to the budget settles within the dead band under the target.
        let mut b = 2_000_000;
        for _ in 0..200 {
            b = step(b, 10.0 + b as f64 * 1e-4, 60.0);
        }
        let ms = 10.0 + b as f64 * 1e-4;
        assert!((60.0 * 0.8 * 0.8..=60.0 * 1.1).contains(&ms), "{b} rays: {ms} ms");
    }

    /// What the model says fits, with no least above the minimum budget.
    fn fit(fits: u32) -> Option<RayFit> {
        Some(RayFit {
            fits,
            least: MIN_RAYS_PER_FRAME,
        })
    }

    /// A frame over the target whose rays are at the model's least keeps them: its floor, not its rays, is
    /// over (the bundled scene's moving frames on lavapipe, ~100 ms with 1,000 rays). Fails with the least
    /// left out of the cut (20,000 rays fall to 10,800, then to the 1,000 minimum).
    #[test]
    fn a_frame_over_the_target_because_of_its_floor_keeps_its_rays() {
        let floor_bound = Some(RayFit {
            fits: 20_000,
            least: 20_000,
        });
        let mut b = 20_000;
        for _ in 0..10 {
            b = next_rays_per_frame(b, b as f64, b as u64, 120.0, 100.0, floor_bound);
        }
        assert_eq!(b, 20_000);
        // Over the least, the cut goes down to it, not under.
        let cut = next_rays_per_frame(80_000, 8e4, 80_000, 300.0, 100.0, floor_bound);
        assert_eq!(cut, 20_000);
    }

    /// A fast frame that traced a tenth of its rays (cells over cached geometry take none) does not grow the
    /// budget; one that used them grows it to what the model says fits, at most doubled; over the target the
    /// cut never leaves more than fits. Fails with the `used` condition left out (the budget doubles on a
    /// frame that used a tenth of it) and with `fits` ignored over the target.
    #[test]
    fn the_budget_grows_only_when_its_rays_were_used() {
        let (b, target) = (1_000_000, 16.7);
        assert_eq!(
            next_rays_per_frame(b, 1e6, 100_000, 5.0, target, fit(8_000_000)),
            b
        );
        assert_eq!(next_rays_per_frame(b, 1e6, 100_000, 5.0, target, None), b);
        assert_eq!(
            next_rays_per_frame(b, 1e6, 950_000, 5.0, target, fit(1_500_000)),
            1_500_000
        );
        assert_eq!(
            next_rays_per_frame(b, 1e6, 950_000, 5.0, target, fit(8_000_000)),
            2_000_001
        );
        // Unused, and the model says less fits: cut to it.
        assert_eq!(
            next_rays_per_frame(b, 1e6, 100_000, 5.0, target, fit(600_000)),
            600_000
        );
        // Over the target: the smaller of the proportional cut and what fits.
        assert_eq!(
            next_rays_per_frame(b, 1e6, 1_000_000, 33.4, target, fit(200_000)),
            200_000
        );
        assert_eq!(
            next_rays_per_frame(b, 1e6, 1_000_000, 33.4, target, fit(900_000)),
            450_000
        );
    }
}
