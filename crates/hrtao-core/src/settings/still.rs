//! Still-camera refinement (ours, docs/algorithm.md): while the view rests, every pixel traces its own rays and
//! its AO converges from the cell estimate to the ray-traced value (composite.comp).
use super::settings_group;
use crate::gpu::{self, FrameGlobals};

/// The weight of the cell estimate in the refinement, in rays of the pixel's own (the k of composite.comp).
pub const PRIOR_RAYS: f32 = 32.0;
/// A neighbour's own-ray residual joins the pixel's when they agree within this many standard deviations of
/// their noise (composite.comp's residual pooling).
pub const RESIDUAL_SIGMA: f32 = 0.5;
/// Each still frame the shown AO moves this fraction of the way to the refined estimate (an exponential moving
/// average, a lag of about 1/x - 1 frames). A round of slices counts it per ray (`frame_smoothing`).
pub const STILL_SMOOTHING: f32 = 0.15;

/// The smoothing of a round of slices of `rays_per_pixel` own rays: `STILL_SMOOTHING` per ray, so the image a
/// round of B rays ends settles as B whole frames of one ray would. (Whole frames of several rays keep the
/// per-frame smoothing: counted per ray there, the noise of frames 2-4 at 4 rays rose, rod MAE 0.0182 → 0.0204.)
pub fn frame_smoothing(rays_per_pixel: u32) -> f32 {
    1.0 - (1.0 - STILL_SMOOTHING).powi(rays_per_pixel.clamp(1, 1024) as i32)
}

settings_group! {
    /// Still-camera refinement.
    pub struct StillSettings {
        /// Ours: while the view rests, pixels trace their own rays and converge to the ray-traced AO; primary
        /// samples are jittered when the frame allows it. Off: the paper's cell estimate only.
        refine: bool = true, StillImage, paper (false), label "refine when still";
        /// A still image is final once every pixel has this many rays of its own (refinement, per-pixel RTAO).
        still_samples: u32 = 64, StillImage, paper keep, range 1..=4096, log, label "rays per pixel",
            needs "refine";
    }
}

impl StillSettings {
    pub fn write_gpu(&self, g: &mut FrameGlobals) {
        if self.refine {
            g.flags |= gpu::FLAG_REFINE;
        }
        g.prior_rays = PRIOR_RAYS;
        g.residual_sigma = RESIDUAL_SIGMA;
        g.still_smoothing = STILL_SMOOTHING;
        g.still_samples = self.still_samples as f32;
    }
}
