//! What the renderer computes and shows: the paper's HRTAO, the per-pixel baseline, no AO, or a debug view.
use serde::{Deserialize, Serialize};

use crate::gpu;

/// What the renderer computes and shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Brute-force per-pixel ray-traced AO (the baseline), accumulated while nothing changes.
    Rtao,
    /// The paper's hashed ray-traced AO.
    #[default]
    Hrtao,
    /// Shading without AO.
    NoAo,
    /// Debug: hash cell false colours (paper Fig. 3).
    DebugCells,
    /// Debug: LOD used per pixel.
    DebugLod,
    /// Debug: samples per cell heat map.
    DebugSamples,
}

impl Mode {
    pub fn gpu_value(self) -> u32 {
        match self {
            Mode::Rtao => gpu::MODE_RTAO,
            Mode::Hrtao => gpu::MODE_HRTAO,
            Mode::NoAo => gpu::MODE_NO_AO,
            Mode::DebugCells => gpu::MODE_DEBUG_CELLS,
            Mode::DebugLod => gpu::MODE_DEBUG_LOD,
            Mode::DebugSamples => gpu::MODE_DEBUG_SAMPLES,
        }
    }

    /// True when the hash map passes run (HRTAO and its debug views).
    pub fn uses_hash(self) -> bool {
        matches!(
            self,
            Mode::Hrtao | Mode::DebugCells | Mode::DebugLod | Mode::DebugSamples
        )
    }

    pub const ALL: [Mode; 6] = [
        Mode::Hrtao,
        Mode::Rtao,
        Mode::NoAo,
        Mode::DebugCells,
        Mode::DebugLod,
        Mode::DebugSamples,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Mode::Rtao => "per-pixel RTAO",
            Mode::Hrtao => "HRTAO",
            Mode::NoAo => "AO off",
            Mode::DebugCells => "debug: hash cells",
            Mode::DebugLod => "debug: LOD used",
            Mode::DebugSamples => "debug: samples per cell",
        }
    }
}

impl std::str::FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s {
            "rtao" => Mode::Rtao,
            "hrtao" => Mode::Hrtao,
            "none" | "no-ao" => Mode::NoAo,
            "cells" | "debug-cells" => Mode::DebugCells,
            "lod" | "debug-lod" => Mode::DebugLod,
            "samples" | "debug-samples" => Mode::DebugSamples,
            _ => {
                return Err(format!(
                    "unknown mode `{s}` (rtao, hrtao, none, debug-cells, debug-lod, debug-samples)"
                ))
            }
        })
    }
}
