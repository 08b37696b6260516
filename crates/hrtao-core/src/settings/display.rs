//! What is shown and how: the mode, the shading and the feature edges. Never part of a cell.
use super::{settings_group, Mode};
use crate::gpu::{self, FrameGlobals};

settings_group! {
    /// Display.
    pub struct DisplaySettings {
        /// What the renderer computes and shows.
        mode: Mode = Mode::Hrtao, StillImage, paper keep;
        /// Base colours (else a uniform grey clay look).
        shaded: bool = true, StillImage, paper keep;
        /// Feature edges over the shading (silhouettes: depth and instance changes; creases: normals meeting at
        /// more than `crease_deg`), as CAD viewports draw them. Never in the AO image.
        edges: bool = true, StillImage, paper keep;
        /// The crease angle of the feature edges, in degrees.
        crease_deg: f32 = 40.0, StillImage, paper keep;
    }
}

/// The crease angles the feature edges accept, in degrees (the panel's slider spans the same range).
pub const CREASE_DEG_RANGE: std::ops::RangeInclusive<f32> = 0.0..=180.0;

impl DisplaySettings {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.crease_deg.is_finite() && CREASE_DEG_RANGE.contains(&self.crease_deg)) {
            return Err(format!(
                "crease angle must be in {}..={} degrees, got {}",
                CREASE_DEG_RANGE.start(),
                CREASE_DEG_RANGE.end(),
                self.crease_deg
            ));
        }
        Ok(())
    }

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
