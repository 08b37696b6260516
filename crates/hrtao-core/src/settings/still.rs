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
/// average, a lag of about 1/x - 1 frames).
pub const STILL_SMOOTHING: f32 = 0.15;

settings_group! {
    /// Still-camera refinement.
    pub struct StillSettings {
        /// Ours: while the view rests, pixels trace their own rays and converge to the ray-traced AO; primary
        /// samples are jittered when the frame allows it. Off: the paper's cell estimate only.
        refine: bool = true, StillImage, paper (false);
        /// A still image is final once every pixel has this many rays of its own (refinement, per-pixel RTAO).
        still_samples: u32 = 64, StillImage, paper keep;
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
    }
}
