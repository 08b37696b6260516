//! The first frames of a young map (ours, docs/algorithm.md): while cells hold few rays, these bring back the
//! detail finer than the cells and cut their noise. They run only in frames of a young map (`Renderer`'s
//! `young_map`): a new map, a new view, the first still frames.
use super::settings_group;
use crate::gpu::FrameGlobals;

/// Near-field control variate: the weight β of a pixel's own near-open fraction minus its cells'.
pub const NEAR_WEIGHT: f32 = 1.0;
/// The near radius r_n as a fraction of R (smaller radii make the near-open fraction curve within a cell where
/// the AO does not, which biases the correction).
pub const NEAR_FRACTION: f32 = 0.5;
/// Pooled residual: the λ of the Wiener weight r²/(r² + λ v) of the 3x3 same-surface residual.
pub const POOLED_RESIDUAL_LAMBDA: f32 = 16.0;
/// Contact detail: the scale of the gain fitted each frame (1 = the fit).
pub const CONTACT_DETAIL_GAIN: f32 = 1.0;

settings_group! {
    /// The first frames of a young map.
    pub struct YoungMapSettings {
        /// While the hash map is young, pixels trace a quarter of the ray budget first and the rest goes to
        /// the cells that are still noisy. Off: every pixel traces the same number of rays (the paper).
        adaptive_rays: bool = true, StillImage, paper (false);
        /// Each pixel corrects its cell's AO with its own rays that hit within half the AO radius, restoring
        /// contact shadows a cell averages away, where its neighbours' rays agree (a control variate:
        /// `NEAR_WEIGHT`, `NEAR_FRACTION`). Off: the paper's cells.
        near_field: bool = true, StillImage, paper (false);
        /// While a cell is young, each pixel is corrected by the rays it and its neighbours on the same
        /// surface traced this frame, where they differ from the cell by more than their noise
        /// (`POOLED_RESIDUAL_LAMBDA`).
        pooled_residual: bool = true, StillImage, paper (false);
        /// While cells are young, the creases and contacts the G-buffer shows around a pixel, finer than its
        /// cells, darken it by a gain fitted each frame to the rays the pixels traced (`CONTACT_DETAIL_GAIN`).
        contact_detail: bool = true, StillImage, paper (false);
    }
}

impl YoungMapSettings {
    pub fn write_gpu(&self, g: &mut FrameGlobals) {
        let on = |b: bool, v: f32| if b { v } else { 0.0 };
        g.near_weight = on(self.near_field, NEAR_WEIGHT);
        g.near_fraction = NEAR_FRACTION;
        g.pooled_residual = on(self.pooled_residual, POOLED_RESIDUAL_LAMBDA);
        g.contact_detail = on(self.contact_detail, CONTACT_DETAIL_GAIN);
    }
}
