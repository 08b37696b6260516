//! `--stats FILE`: one record per rendered frame of a scripted run (wall and GPU time, internal and view size,
//! whether the camera moved), written as JSON when the run ends.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use super::shot::ShotSummary;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameStat {
    /// The whole frame on the CPU clock: UI, the renderer's passes, the blit, egui, present.
    pub wall_ms: f64,
    /// The renderer's passes by GPU timestamps (0 when the device has none).
    pub gpu_ms: f64,
    pub internal: [u32; 2],
    pub view: [u32; 2],
    pub moving: bool,
    /// Rays traced this frame.
    pub rays: u64,
}

#[derive(Serialize)]
struct StatsFile<'a> {
    device: &'a str,
    scene: &'a str,
    frames: &'a [FrameStat],
    median_moving_wall_ms: Option<f64>,
    median_still_wall_ms: Option<f64>,
    /// A background screenshot (--screenshot-size) written during the run.
    screenshot: Option<&'a ShotSummary>,
}

pub struct StatsLog {
    path: PathBuf,
    pub frames: Vec<FrameStat>,
    pub screenshot: Option<ShotSummary>,
}

impl StatsLog {
    pub fn new(path: PathBuf) -> StatsLog {
        StatsLog {
            path,
            frames: Vec::new(),
            screenshot: None,
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Median wall time of the moving (or still) frames.
    pub fn median_wall_ms(&self, moving: bool) -> Option<f64> {
        median(
            self.frames
                .iter()
                .filter(|f| f.moving == moving)
                .map(|f| f.wall_ms)
                .collect(),
        )
    }

    pub fn write(&self, device: &str, scene: &str) -> Result<()> {
        let file = StatsFile {
            device,
            scene,
            frames: &self.frames,
            median_moving_wall_ms: self.median_wall_ms(true),
            median_still_wall_ms: self.median_wall_ms(false),
            screenshot: self.screenshot.as_ref(),
        };
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let text = serde_json::to_string_pretty(&file)?;
        std::fs::write(&self.path, text).with_context(|| format!("cannot write {}", self.path.display()))
    }
}

pub fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_moving_and_still_frames() {
        let mut log = StatsLog::new("x.json".into());
        for (ms, moving) in [
            (10.0, true),
            (30.0, true),
            (20.0, true),
            (5.0, false),
            (7.0, false),
        ] {
            log.frames.push(FrameStat {
                wall_ms: ms,
                gpu_ms: 0.0,
                internal: [1, 1],
                view: [1, 1],
                moving,
                rays: 0,
            });
        }
        assert_eq!(log.median_wall_ms(true), Some(20.0));
        assert_eq!(log.median_wall_ms(false), Some(6.0));
        assert_eq!(median(Vec::new()), None);
    }
}
