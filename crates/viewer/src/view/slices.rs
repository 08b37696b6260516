//! Still frames in slices, so that input never waits for a refinement frame: while the view rests, each
//! presented frame draws one slice of the full-resolution image (every lattice-th pixel, `FrameDesc::lattice`),
//! about the frame-time target's worth of work, and input is handled between slices. The lattice follows the
//! measured cost of a slice; the still image's rays per pixel are set once when it starts (a change would
//! restart it), from the ray budget per frame over one slice's pixels, so a slice traces about the rays of a
//! moving frame and the image converges in about as many rounds as it needs rays.
use hrtao_core::{RayBudget, MAX_LATTICE};

use super::budget::MAX_RAYS_PER_PIXEL;

/// The lattice shrinks only to one whose slices would cost at most this fraction of the target (hysteresis).
const SHRINK_BELOW: f64 = 0.8;

/// The lattice of the still frames and the still image's budget.
#[derive(Debug, Clone, PartialEq)]
pub struct Slicing {
    lattice: u32,
    /// Set when a still image starts, kept until the view moves again.
    still_budget: Option<RayBudget>,
}

impl Default for Slicing {
    fn default() -> Self {
        Slicing {
            lattice: 1,
            still_budget: None,
        }
    }
}

/// The lattice whose slices of a frame costing `whole_ms` cost about `target_ms`: ⌈√(whole / target)⌉.
pub fn lattice_for(whole_ms: f64, target_ms: f64) -> u32 {
    let n = (whole_ms.max(0.0) / target_ms.max(1.0)).sqrt().ceil();
    (n as u32).clamp(1, MAX_LATTICE)
}

impl Slicing {
    /// The lattice to ask of the next still frame.
    pub fn lattice(&self) -> u32 {
        self.lattice
    }

    /// The view moves: whole frames at the moving scale, and the next still image gets a new budget.
    pub fn moving(&mut self) {
        self.still_budget = None;
    }

    /// The budget of a still frame of `pixels` (full resolution): the current still image's, or, when one
    /// starts, its lattice from the last moving frame (`moving_ms` over `moving_pixels`, scaled to `pixels`)
    /// and its rays per pixel from `rays_per_frame` over one slice.
    pub fn still_budget(
        &mut self,
        rays_per_frame: u32,
        pixels: u64,
        moving: Option<(f64, u64)>,
        target_ms: f64,
    ) -> RayBudget {
        if let Some(b) = self.still_budget {
            return b;
        }
        if let Some((ms, moving_pixels)) = moving {
            let whole = ms * pixels as f64 / moving_pixels.max(1) as f64;
            self.lattice = lattice_for(whole, target_ms);
        }
        let slice_pixels = (pixels as f64 / (self.lattice * self.lattice) as f64).max(1.0);
        let rpp = (rays_per_frame as f64 / slice_pixels).round() as u32;
        let b = RayBudget {
            rays_per_pixel: rpp.clamp(1, MAX_RAYS_PER_PIXEL),
            trace_fraction: 1.0,
        };
        self.still_budget = Some(b);
        b
    }

    /// After a still frame that took `frame_ms` and drew one of `slices` slices: the lattice whose slice would
    /// cost the target if the whole frame cost `frame_ms` × slices (an upper bound: the frame's fixed costs do
    /// not shrink with the slice), shrinking only while a slice would stay under `SHRINK_BELOW` of the target.
    /// Decided once the renderer draws the lattice asked (it takes a new one at a round's start).
    pub fn observe(&mut self, frame_ms: f64, slices: u32, target_ms: f64) {
        if slices != self.lattice * self.lattice || !frame_ms.is_finite() {
            return;
        }
        let whole = frame_ms * slices as f64;
        let mut next = lattice_for(whole, target_ms);
        if next < self.lattice && whole / (next * next) as f64 > target_ms * SHRINK_BELOW {
            next += 1;
        }
        self.lattice = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lattice_makes_a_slice_cost_the_target() {
        assert_eq!(lattice_for(50.0, 100.0), 1);
        assert_eq!(lattice_for(100.0, 100.0), 1);
        assert_eq!(lattice_for(409.0, 100.0), 3);
        assert_eq!(lattice_for(390.0, 100.0), 2);
        assert_eq!(lattice_for(1e9, 100.0), MAX_LATTICE);
        assert_eq!(lattice_for(f64::NAN, 100.0), 1);
    }

    #[test]
    fn a_still_image_keeps_its_budget_until_the_view_moves() {
        let mut s = Slicing::default();
        // An 82 ms moving frame of 87k pixels: a 707k-pixel still frame would take about 666 ms.
        let b = s.still_budget(300_000, 707_200, Some((82.0, 87_000)), 100.0);
        assert_eq!(s.lattice(), 3);
        // 300k rays over a ninth of the pixels: 4 rays each (3.8 rounded).
        assert_eq!(b.rays_per_pixel, 4);
        s.observe(150.0, 9, 100.0);
        assert_eq!(s.lattice(), 4, "a slice over the target grows the lattice");
        assert_eq!(s.still_budget(1_000, 707_200, Some((10.0, 87_000)), 100.0), b);
        s.moving();
        let b2 = s.still_budget(1_000, 707_200, Some((10.0, 87_000)), 100.0);
        assert_eq!((s.lattice(), b2.rays_per_pixel), (1, 1));
    }

    #[test]
    fn the_lattice_follows_the_slices_cost() {
        let mut s = Slicing {
            lattice: 3,
            still_budget: None,
        };
        // Not yet drawn with the lattice asked: no decision.
        s.observe(500.0, 4, 100.0);
        assert_eq!(s.lattice(), 3);
        // A cheap slice: 30 ms at 9 slices is at most 68 ms at 4, under 80 % of the target.
        s.observe(30.0, 9, 100.0);
        assert_eq!(s.lattice(), 2);
        // 45 ms at 4 slices: at most 180 ms whole, over 80 % of the target: stay.
        s.observe(45.0, 4, 100.0);
        assert_eq!(s.lattice(), 2);
        s.observe(120.0, 4, 100.0);
        assert_eq!(s.lattice(), 3);
        // A first frame's estimate far too high: down in one step.
        let mut s = Slicing {
            lattice: MAX_LATTICE,
            still_budget: None,
        };
        s.observe(5.0, MAX_LATTICE * MAX_LATTICE, 100.0);
        assert_eq!(s.lattice(), 2);
        s.observe(1e4, 4, 100.0);
        assert_eq!(s.lattice(), MAX_LATTICE);
    }
}
