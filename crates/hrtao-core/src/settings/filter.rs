//! The paper's adaptive à-trous filter (§5), and our variance guidance.
use super::settings_group;
use crate::gpu::{self, FrameGlobals};

/// Ours (`variance_filter`): a neighbour stops the filter when its AO differs from the pixel's by more than this
/// many standard deviations of the cells' binomial noise (edge-stopping on the AO difference, as Schied et al.
/// 2017 do with luminance), so the filter smooths the noise of young cells over more than a cell and stops at
/// real AO gradients (filter.comp, filter_plan.glsl).
pub const FILTER_SIGMA: f32 = 1.0;

/// The most à-trous iterations (a kernel of 2^8 pixels).
pub const MAX_FILTER_ITERATIONS: u32 = 8;

settings_group! {
    /// The adaptive à-trous filter.
    pub struct FilterSettings {
        /// À-trous iterations (§5); 0 = no filter.
        /// Each iteration doubles its reach; the footprint follows the cell size.
        filter_iterations: u32 = 5, StillImage, paper keep, range 0..=MAX_FILTER_ITERATIONS;
        /// Ours: the filter also smooths young cells' noise over more than a cell and stops where neighbours
        /// differ by more than the cells' noise (`FILTER_SIGMA`). Off: the paper's filter (bounded by the cell
        /// footprint).
        variance_filter: bool = true, StillImage, paper (false);
    }
}

impl FilterSettings {
    pub fn write_gpu(&self, g: &mut FrameGlobals) {
        g.filter_iterations = self.filter_iterations;
        if self.filter_iterations > 0 {
            g.flags |= gpu::FLAG_FILTER;
        }
        g.filter_sigma = if self.variance_filter { FILTER_SIGMA } else { 0.0 };
    }
}
