//! What is shown and how: the mode, the shading and the feature edges. Never part of a cell.
use super::{settings_group, Mode};
use crate::gpu::{self, FrameGlobals};

settings_group! {
    /// Display.
    pub struct DisplaySettings {
        /// What the renderer computes and shows. HRTAO: the paper's hashed ray-traced AO (§1-§5). Per-pixel
        /// RTAO: the brute-force baseline (accumulates while nothing moves). Debug views: hash cells (Fig. 3),
        /// LOD used (§4), samples per cell.
        mode: Mode = Mode::Hrtao, StillImage, paper keep;
        /// Base colours (else a uniform grey clay look).
        shaded: bool = true, StillImage, paper keep, label "base colours";
        /// Feature edges over the shading (silhouettes: depth and instance changes; creases: normals meeting at
        /// more than `crease_deg`), as CAD viewports draw them. Never in the AO image.
        edges: bool = true, StillImage, paper keep;
        /// The crease angle of the feature edges, in degrees: faces meeting at more than it draw a crease line.
        crease_deg: f32 = 40.0, StillImage, paper keep, range CREASE_DEG_RANGE, label "crease °", needs "edges";
    }
}

/// The crease angles the feature edges accept, in degrees (`crease_deg`'s range; the loaders' smoothing angle
/// takes the same).
pub const CREASE_DEG_RANGE: std::ops::RangeInclusive<f32> = 0.0..=180.0;

impl DisplaySettings {
    pub fn write_gpu(&self, g: &mut FrameGlobals) {
        g.mode = self.mode.gpu_value();
        if self.shaded {
            g.flags |= gpu::FLAG_SHADED;
        }
        if self.edges {
            g.flags |= gpu::FLAG_EDGES;
        }
        g.crease_cos = self.crease_deg.to_radians().cos();
    }
}
