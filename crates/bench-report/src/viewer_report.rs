//! The "The viewer, two builds side by side" section of docs/benchmarks.md, from `scripts/bench-viewer.sh`'s
//! results (`docs/bench/viewer/<version>_<scene>_<run>.json`, schema `hrtao-viewer-run/1`): per scene and
//! build, the medians over runs of the moving frame, the time to converge and the UI's own cost per frame, and
//! the ratio of medians after / before.
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use serde::Deserialize;

use crate::report::table_header;
use hrtao_core::stats::median;

pub const VIEWER_SCHEMA: &str = "hrtao-viewer-run/1";

/// The UI's cost in one frame, milliseconds (medians over a run's frames).
#[derive(Clone, Debug, Default, Deserialize)]
pub struct UiMs {
    /// The UI pass (panels, input, commands).
    pub ui: f64,
    /// After the UI pass until the frame starts: platform output, egui's tessellation, texture uploads.
    pub tessellate: f64,
    /// Recording egui's draw.
    pub egui_record: f64,
    /// vkQueuePresentKHR.
    pub present: f64,
}

impl UiMs {
    pub fn total(&self) -> f64 {
        self.ui + self.tessellate + self.egui_record + self.present
    }
}

/// One run of one build on one scene.
#[derive(Clone, Debug, Deserialize)]
pub struct ViewerRun {
    pub version: String,
    pub scene: String,
    pub median_moving_wall_ms: f64,
    pub converge_s: Option<f64>,
    pub median_ui_ms: UiMs,
}

/// Every result of `dir` with [`VIEWER_SCHEMA`] (none when the directory does not exist).
pub fn load(dir: &Path) -> Result<Vec<ViewerRun>> {
    crate::results::load_typed(dir, VIEWER_SCHEMA, "viewer run")
}

/// The medians over one build's runs of a scene.
struct Medians {
    runs: usize,
    moving_ms: f64,
    converge_s: f64,
    ui: UiMs,
}

fn medians(runs: &[&ViewerRun]) -> Medians {
    let of = |f: &dyn Fn(&ViewerRun) -> f64| median(&runs.iter().map(|r| f(r)).collect::<Vec<_>>());
    Medians {
        runs: runs.len(),
        moving_ms: of(&|r| r.median_moving_wall_ms),
        converge_s: of(&|r| r.converge_s.unwrap_or(f64::NAN)),
        ui: UiMs {
            ui: of(&|r| r.median_ui_ms.ui),
            tessellate: of(&|r| r.median_ui_ms.tessellate),
            egui_record: of(&|r| r.median_ui_ms.egui_record),
            present: of(&|r| r.median_ui_ms.present),
        },
    }
}

/// The section (nothing without results).
pub fn section(m: &mut String, runs: &[ViewerRun]) -> Result<()> {
    if runs.is_empty() {
        return Ok(());
    }
    // scene -> version -> runs; `before` first.
    let mut by_scene: BTreeMap<&str, BTreeMap<(bool, &str), Vec<&ViewerRun>>> = BTreeMap::new();
    for r in runs {
        by_scene
            .entry(&r.scene)
            .or_default()
            .entry((r.version != "before", &r.version))
            .or_default()
            .push(r);
    }
    writeln!(m, "## The viewer, two builds side by side\n")?;
    writeln!(
        m,
        "`BEFORE=old/hrtao scripts/bench-viewer.sh` runs `hrtao view --orbit 40 --stats` (40 frames of orbit, \
         then still until the image converges) at 1280×800 with the panel, alternating between the two builds. \
         Each cell is the median over the runs of a run's median; *converge* is from the first frame to the \
         converged image; *UI* is the UI's own cost per frame: the UI pass (panels, input, commands), then \
         egui's tessellation and texture uploads, recording egui's draw, and presenting. The ratio row divides \
         the last build's medians by `before`'s.\n"
    )?;
    table_header(m, "scene | build | runs | moving frame, ms | converge, s | UI pass, ms | tessellate, ms | egui record, ms | present, ms | UI in all, ms")?;
    for (scene, versions) in &by_scene {
        let rows: Vec<(&str, Medians)> = versions
            .iter()
            .map(|((_, v), runs)| (*v, medians(runs)))
            .collect();
        for (v, md) in &rows {
            writeln!(
                m,
                "| {scene} | {v} | {} | {:.1} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
                md.runs,
                md.moving_ms,
                md.converge_s,
                md.ui.ui,
                md.ui.tessellate,
                md.ui.egui_record,
                md.ui.present,
                md.ui.total()
            )?;
        }
        if let (Some((_, before)), Some((last, after))) =
            (rows.iter().find(|(v, _)| *v == "before"), rows.last())
        {
            if *last != "before" {
                writeln!(
                    m,
                    "| {scene} | {last} / before | | {:.2}× | {:.2}× | | | | | {:.2}× |",
                    after.moving_ms / before.moving_ms,
                    after.converge_s / before.converge_s,
                    after.ui.total() / before.ui.total()
                )?;
            }
        }
    }
    writeln!(m)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(version: &str, moving: f64, converge: f64, ui: f64) -> ViewerRun {
        ViewerRun {
            version: version.into(),
            scene: "bundled".into(),
            median_moving_wall_ms: moving,
            converge_s: Some(converge),
            median_ui_ms: UiMs {
                ui,
                tessellate: 0.5,
                egui_record: 0.1,
                present: 0.0,
            },
        }
    }

    /// Medians over runs per build, and after / before as a ratio of those medians.
    #[test]
    fn the_ratio_row_divides_the_medians_of_the_runs() {
        let runs = [
            run("after", 90.0, 50.0, 1.4),
            run("before", 100.0, 60.0, 2.4),
            run("after", 110.0, 70.0, 1.4),
            run("before", 120.0, 40.0, 2.4),
            run("after", 100.0, 60.0, 1.4),
            run("before", 140.0, 80.0, 2.4),
        ];
        let mut m = String::new();
        section(&mut m, &runs).unwrap();
        let before = m
            .lines()
            .position(|l| l.starts_with("| bundled | before |"))
            .unwrap();
        let after = m
            .lines()
            .position(|l| l.starts_with("| bundled | after |"))
            .unwrap();
        assert!(before < after, "{m}");
        assert!(
            m.contains("| bundled | before | 3 | 120.0 | 60.0 | 2.40 | 0.50 | 0.10 | 0.00 | 3.00 |"),
            "{m}"
        );
        // 100 / 120, 60 / 60, 2.0 / 3.0.
        assert!(
            m.contains("| bundled | after / before | | 0.83× | 1.00× | | | | | 0.67× |"),
            "{m}"
        );
    }

    #[test]
    fn no_results_no_section() {
        let mut m = String::new();
        section(&mut m, &[]).unwrap();
        assert!(m.is_empty());
    }
}
