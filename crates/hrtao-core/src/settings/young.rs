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
/// Level blend: the λ of the Wiener weight d²/(d² + λ v) that shrinks a young cell toward its coarser level.
pub const LEVEL_BLEND_LAMBDA: f32 = 1.0;
/// Pooled residual: the λ of the Wiener weight r²/(r² + λ v) of the 3x3 same-surface residual.
pub const POOLED_RESIDUAL_LAMBDA: f32 = 16.0;
/// Contact detail: the scale of the gain fitted each frame (1 = the fit).
pub const CONTACT_DETAIL_GAIN: f32 = 1.0;
/// Linear cells: the λ that shrinks a cell's AO slope against its noise.
const CELL_GRADIENT_LAMBDA: f32 = 2.0;

settings_group! {
    /// The first frames of a young map.
    pub struct YoungMapSettings {
        /// Adaptive sampling: pixels whose cells take rays trace a quarter of their budget, then the rest goes
        /// to them in proportion to the noise their cells still have. Off: every pixel traces its budget.
        adaptive_rays: bool = true, StillImage, paper (false);
        /// Near-field control variate: a pixel that traced rays corrects its cell estimate by its own near-open
        /// fraction minus its cells' (rays that hit nothing within r_n), restoring contact shadows a cell
        /// averages away (`NEAR_WEIGHT`, `NEAR_FRACTION`).
        near_field: bool = true, StillImage, paper (false);
        /// Level blend: a young finest cell's AO is shrunk toward the next coarser level's where they agree
        /// within its noise (`LEVEL_BLEND_LAMBDA`).
        level_blend: bool = true, StillImage, paper (false);
        /// Pooled residual: a young cell's AO is corrected by the residual of the rays traced this frame by the
        /// pixel and its 3x3 same-surface neighbours (`POOLED_RESIDUAL_LAMBDA`).
        pooled_residual: bool = true, StillImage, paper (false);
        /// Contact detail: the detail of the screen-space obscurance, with a gain fitted each frame to the
        /// traced rays, is added to a young cell's AO (`CONTACT_DETAIL_GAIN`).
        contact_detail: bool = true, StillImage, paper (false);
        /// Linear cells: each cell keeps the least-squares slope of its AO across the cell and the resolve
        /// evaluates that line at the pixel (`CELL_GRADIENT_LAMBDA`). Cells keep their offset sums only while on.
        linear_cells: bool = false, WholeMap, paper (false);
    }
}

impl YoungMapSettings {
    pub fn write_gpu(&self, g: &mut FrameGlobals) {
        let on = |b: bool, v: f32| if b { v } else { 0.0 };
        g.near_weight = on(self.near_field, NEAR_WEIGHT);
        g.near_fraction = NEAR_FRACTION;
        g.level_blend = on(self.level_blend, LEVEL_BLEND_LAMBDA);
        g.pooled_residual = on(self.pooled_residual, POOLED_RESIDUAL_LAMBDA);
        g.contact_detail = on(self.contact_detail, CONTACT_DETAIL_GAIN);
        g.cell_gradient = on(self.linear_cells, CELL_GRADIENT_LAMBDA);
    }
}
