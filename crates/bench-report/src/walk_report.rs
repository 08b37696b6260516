//! The "Walking against orbiting" section of docs/benchmarks.md, from `scripts/bench-walk.sh`'s results
//! (`docs/bench/walk/<mode>_building_<run>.json`, the viewer runs' schema `hrtao-viewer-run/1`): per mode, the
//! median over runs of a run's median moving frame, and the walk's over each orbit's as ratios of those medians.
//! Walking traces its gravity and collision rays in the frames it renders anyway and reads their answers a frame
//! later: its moving frames should cost what an orbit's of the same view do. The orbit in a room (`room_orbit`)
//! is that one: every pixel shows geometry, as while walking; the fitted view's orbit (`orbit`) shows the
//! building in about half its pixels, and background pixels take no AO work.
use std::collections::BTreeMap;
use std::fmt::Write as _;

use anyhow::Result;

use crate::report::table_header;
use crate::viewer_report::ViewerRun;
use hrtao_core::stats::median;

/// The section (nothing without results).
pub fn section(m: &mut String, runs: &[ViewerRun]) -> Result<()> {
    if runs.is_empty() {
        return Ok(());
    }
    let mut by_mode: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for r in runs {
        by_mode
            .entry(&r.version)
            .or_default()
            .push(r.median_moving_wall_ms);
    }
    writeln!(m, "## Walking against orbiting\n")?;
    writeln!(
        m,
        "`scripts/bench-walk.sh` runs one build's `hrtao view --walk-path` through the generated two-storey IFC \
         building (into a wall, through the door, up the stair; the walk of `tests/building.rs`), `--orbit 180` \
         from a camera in one of its rooms (`room_orbit`: every pixel shows geometry, as while walking) and \
         `--orbit 180` of the fitted view (`orbit`: the building fills about half the view, and background pixels \
         take no AO work), alternating, at 1280×800 with the panel. Each cell is the median over the runs of a \
         run's median moving frame; the ratio rows divide walking's by each orbit's: the walk's measure is the \
         one against the orbit of the same view, `room_orbit`.\n"
    )?;
    table_header(m, "mode | runs | moving frame, ms")?;
    let med: BTreeMap<&str, f64> = by_mode.iter().map(|(k, v)| (*k, median(v))).collect();
    for (mode, v) in &by_mode {
        writeln!(m, "| {mode} | {} | {:.1} |", v.len(), med[mode])?;
    }
    for orbit in ["room_orbit", "orbit"] {
        if let (Some(w), Some(o)) = (med.get("walk"), med.get(orbit)) {
            writeln!(m, "| walk / {orbit} | | {:.2}× |", w / o)?;
        }
    }
    writeln!(m)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(version: &str, moving: f64) -> ViewerRun {
        ViewerRun {
            version: version.into(),
            scene: "building".into(),
            median_moving_wall_ms: moving,
            converge_s: None,
            median_ui_ms: Default::default(),
        }
    }

    #[test]
    fn the_ratio_divides_the_medians_of_the_runs() {
        let runs = [
            run("walk", 90.0),
            run("orbit", 100.0),
            run("walk", 80.0),
            run("orbit", 120.0),
            run("walk", 70.0),
            run("room_orbit", 160.0),
        ];
        let mut m = String::new();
        section(&mut m, &runs).unwrap();
        assert!(m.contains("| walk | 3 | 80.0 |"), "{m}");
        assert!(m.contains("| orbit | 2 | 110.0 |"), "{m}");
        assert!(m.contains("| walk / orbit | | 0.73× |"), "{m}");
        assert!(m.contains("| walk / room_orbit | | 0.50× |"), "{m}");
        let mut empty = String::new();
        section(&mut empty, &[]).unwrap();
        assert!(empty.is_empty());
    }
}
