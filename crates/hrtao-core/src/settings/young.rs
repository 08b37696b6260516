//! The first frames of a young map (ours, docs/algorithm.md): while cells hold few rays, these bring back the
//! detail finer than the cells and cut their noise. They run only in frames of a young map
//! (`WorldHashMap::young`): a new map, a new view, the first still frames. Each is one switch here, one file in
//! `crate::additions` (when it runs) and one shader file (its GPU code and tuning constants).
use super::settings_group;

settings_group! {
    /// The first frames of a young map.
    pub struct YoungMapSettings {
        /// While the hash map is young, pixels trace a quarter of the ray budget first and the rest goes to
        /// the cells that are still noisy. Off: every pixel traces the same number of rays (the paper).
        adaptive_rays: bool = true, StillImage, paper (false);
        /// Each pixel corrects its cell's AO with its own rays that hit within half the AO radius, restoring
        /// contact shadows a cell averages away, where its neighbours' rays agree (a control variate,
        /// near_field.glsl). Off: the paper's cells.
        near_field: bool = true, StillImage, paper (false);
        /// While a cell is young, each pixel is corrected by the rays it and its neighbours on the same
        /// surface traced this frame, where they differ from the cell by more than their noise
        /// (pooled_residual.glsl).
        pooled_residual: bool = true, StillImage, paper (false);
        /// While cells are young, the creases and contacts the G-buffer shows around a pixel, finer than its
        /// cells, darken it by a gain fitted each frame to the rays the pixels traced (contact_detail.glsl).
        contact_detail: bool = true, StillImage, paper (false);
    }
}
