//! The "Input latency and still refinement" section of docs/benchmarks.md, from `scripts/bench-latency.sh`'s
//! results (`docs/bench/latency/<version>_<scene>.json`, schema `hrtao-latency/1`): the same benchmark before and
//! after a change, side by side.
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use serde_json::Value;

use crate::report::table_header;
use hrtao_core::stats::median;

pub const LATENCY_SCHEMA: &str = "hrtao-latency/1";

/// One result file: its version (the file name's prefix, e.g. `before`), scene label and content.
pub struct LatencyResult {
    pub version: String,
    pub scene: String,
    pub json: Value,
}

/// Every `<version>_<scene>.json` of `dir` with [`LATENCY_SCHEMA`], by scene then version (`before` first).
pub fn load(dir: &Path) -> Result<Vec<LatencyResult>> {
    let mut out = Vec::new();
    for (path, json) in crate::results::load_schema(dir, LATENCY_SCHEMA)? {
        let name = path.file_stem().and_then(|n| n.to_str()).unwrap_or("");
        let Some((version, _)) = name.split_once('_') else {
            continue;
        };
        let scene = json["scene"].as_str().unwrap_or("?").to_string();
        out.push(LatencyResult {
            version: version.to_string(),
            scene,
            json,
        });
    }
    out.sort_by(|a, b| {
        (&a.scene, a.version != "before", &a.version).cmp(&(&b.scene, b.version != "before", &b.version))
    });
    Ok(out)
}

/// A number in milliseconds, or "–".
fn ms(v: &Value) -> String {
    v.as_f64().map_or("–".into(), |x| format!("{x:.0}"))
}

/// "median / p95 / max" of a summary object.
fn spread(v: &Value) -> String {
    format!("{} / {} / {}", ms(&v["median"]), ms(&v["p95"]), ms(&v["max"]))
}

fn seconds(v: &Value) -> String {
    v.as_f64().map_or("–".into(), |x| format!("{:.1} s", x / 1e3))
}

fn load_avg(j: &Value) -> String {
    j["load_avg_start"][0]
        .as_f64()
        .map_or("–".into(), |x| format!("{x:.1}"))
}

/// The section (nothing without results).
pub fn section(m: &mut String, results: &[LatencyResult]) -> Result<()> {
    if results.is_empty() {
        return Ok(());
    }
    writeln!(m, "## Input latency and still refinement\n")?;
    writeln!(
        m,
        "`scripts/bench-latency.sh [--scene PATH] --orbit 20 --roughness --out JSON` runs `hrtao view` under Xvfb at \
         1280×800 with the panel and sends 20 left drags with xdotool: in each of 2 launches one right after the \
         scene opened, the others 0.3–3 s after the previous drag ended, during still refinement. A drag is a \
         hover and a press, then its motion; it is stamped with CLOCK_MONOTONIC just before the motion is sent \
         (the input that moves the view), and the viewer's `--stats` stamps each frame's presentation and the \
         latest input it answers on the same clock. A drag's latency is the presentation of the first frame that \
         moved with input received after the stamp, minus the stamp. Rows whose JSON says `\"stamp\": \"hover\"` \
         (every row before the version `motion-stamp`) were stamped before the hover, 125 ms of the script's \
         pauses before the motion, and count them. The orbit rows are `hrtao view --orbit 20 --stats` (20 frames \
         of 2°, then still until converged). Roughness is mean |AO − median of the 8 neighbours| over occluded \
         (AO < 0.95) flat pixels, per frame of `--orbit 1 --ao-out` at the view's size. The frame-time target is \
         100 ms. Versions of one scene ran back to back (`load` is the load average at the start).\n"
    )?;
    table_header(m, "scene | version | drag latency, ms (median / p95 / max) | still frame, ms (median / p95 / max) | converged after the last drag | drags that moved nothing | load")?;
    for r in results {
        let j = &r.json;
        if j["latency_ms"].is_null() {
            continue; // an --orbit run alone (the alternating runs below)
        }
        writeln!(
            m,
            "| {} | {}{} | {} | {} | {} | {} | {} |",
            r.scene,
            r.version,
            if j["stamp"] == "hover" {
                " (stamped at the hover)"
            } else {
                ""
            },
            spread(&j["latency_ms"]),
            spread(&j["still_frames"]["wall_ms"]),
            seconds(&j["converge_after_last_drag_ms"]["median"]),
            j["missed_drags"].as_u64().map_or("–".into(), |n| n.to_string()),
            load_avg(j),
        )?;
    }
    writeln!(m)?;
    table_header(m, "scene | version | moving frame, ms (median) | still frame, ms (median / p95 / max) | still frames until converged | time to converge | largest frame after the first image")?;
    for r in results {
        let o = &r.json["orbit"];
        if o.is_null() {
            continue;
        }
        writeln!(
            m,
            "| {} | {} | {} | {} | {} | {} | {} ms |",
            r.scene,
            r.version,
            ms(&o["moving_wall_ms"]["median"]),
            spread(&o["still_wall_ms"]),
            o["still_frames_until_converged"]
                .as_u64()
                .map_or("–".into(), |n| n.to_string()),
            seconds(&o["converge_ms"]),
            ms(&o["max_frame_after_first_ms"]),
        )?;
    }
    writeln!(m)?;
    converge_runs(m, results)?;
    if results.iter().any(|r| !r.json["roughness"].is_null()) {
        table_header(m, "scene | version | roughness: first frame | still frames' largest | converged | largest / converged")?;
        for r in results {
            let g = &r.json["roughness"];
            if g.is_null() {
                continue;
            }
            let f4 = |v: &Value| v.as_f64().map_or("–".into(), |x| format!("{x:.4}"));
            writeln!(
                m,
                "| {} | {} | {} | {} | {} | {} |",
                r.scene,
                r.version,
                f4(&g["first_frame_roughness"]),
                f4(&g["max_still_roughness"]),
                f4(&g["converged_roughness"]),
                g["max_ratio"].as_f64().map_or("–".into(), |x| format!("{x:.2}")),
            )?;
        }
        writeln!(m)?;
    }
    for r in results {
        if let Some(note) = r.json["note"].as_str() {
            writeln!(m, "- {} ({}): {note}", r.scene, r.version)?;
        }
    }
    if results.iter().any(|r| r.json["note"].is_string()) {
        writeln!(m)?;
    }
    Ok(())
}

/// The table of the versions whose `--orbit` runs alternated back to back (`converge_runs_ms`): each run's
/// time to converge and the ratio of medians to the scene's `before-ab` version.
fn converge_runs(m: &mut String, results: &[LatencyResult]) -> Result<()> {
    let runs = |r: &LatencyResult| -> Option<Vec<f64>> {
        let v: Vec<f64> = r.json["converge_runs_ms"]
            .as_array()?
            .iter()
            .filter_map(Value::as_f64)
            .collect();
        (!v.is_empty()).then_some(v)
    };
    let rows: Vec<(&LatencyResult, Vec<f64>)> = results.iter().filter_map(|r| Some((r, runs(r)?))).collect();
    if rows.is_empty() {
        return Ok(());
    }
    writeln!(
        m,
        "Time to converge with the versions' `--orbit 20` runs alternating back to back (a ratio of medians to \
         `before-ab`, the code before the still refinement in slices, is a ratio measured side by side):\n"
    )?;
    table_header(
        m,
        "scene | version | time to converge, each run | median | against before-ab",
    )?;
    for (r, v) in &rows {
        let base = rows
            .iter()
            .find(|(b, _)| b.scene == r.scene && b.version == "before-ab")
            .map(|(_, bv)| median(bv))
            .filter(|b| b.is_finite());
        let med = median(v);
        let each: Vec<String> = v.iter().map(|x| format!("{:.1} s", x / 1e3)).collect();
        writeln!(
            m,
            "| {} | {} | {} | {:.1} s | {} |",
            r.scene,
            r.version,
            each.join(", "),
            med / 1e3,
            base.map_or("–".into(), |b| format!("{:.2}×", med / b)),
        )?;
    }
    writeln!(m)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_results_render_before_then_after() {
        let dir = std::env::temp_dir().join(format!("hrtao-latency-report-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let result = |lat: f64, conv: f64| {
            serde_json::json!({
                "schema": LATENCY_SCHEMA, "scene": "bundled", "load_avg_start": [0.5, 0.4, 0.3],
                "latency_ms": {"median": lat, "p95": lat * 2.0, "max": lat * 3.0},
                "still_frames": {"wall_ms": {"median": 90.0, "p95": 120.0, "max": 200.0}},
                "converge_after_last_drag_ms": {"median": conv}, "missed_drags": 0,
                "orbit": {"moving_wall_ms": {"median": 80.0}, "still_wall_ms": {"median": 400.0, "p95": 450.0, "max": 460.0},
                          "still_frames_until_converged": 66, "converge_ms": conv, "max_frame_after_first_ms": 460.0},
                "roughness": {"first_frame_roughness": 0.0179, "max_still_roughness": 0.0159,
                              "converged_roughness": 0.0071, "max_ratio": 2.25}
            })
            .to_string()
        };
        std::fs::write(dir.join("after_bundled.json"), result(120.0, 30_000.0)).unwrap();
        std::fs::write(dir.join("before_bundled.json"), result(450.0, 27_000.0)).unwrap();
        std::fs::write(dir.join("notes.json"), r#"{"schema": "other"}"#).unwrap();
        let mut noted: serde_json::Value = serde_json::from_str(&result(120.0, 30_000.0)).unwrap();
        noted["note"] = "measured with the old smoothing".into();
        std::fs::write(dir.join("after_bundled.json"), noted.to_string()).unwrap();
        let results = load(&dir).unwrap();
        assert_eq!(results.len(), 2);
        let mut m = String::new();
        section(&mut m, &results).unwrap();
        let before = m.find("| bundled | before | 450 / 900 / 1350 |").expect(&m);
        let after = m.find("| bundled | after | 120 / 240 / 360 |").expect(&m);
        assert!(before < after, "{m}");
        assert!(m.contains("| 27.0 s | 460 ms |"), "{m}");
        assert!(m.contains("| 0.0179 | 0.0159 | 0.0071 | 2.25 |"), "{m}");
        assert!(
            m.contains("- bundled (after): measured with the old smoothing"),
            "{m}"
        );
        assert!(!m.contains("each run"), "no alternating runs, no table: {m}");
        let mut empty = String::new();
        section(&mut empty, &[]).unwrap();
        assert!(empty.is_empty());
    }

    #[test]
    fn alternating_runs_give_a_ratio_of_medians() {
        let row = |version: &str, runs: &[f64]| LatencyResult {
            version: version.into(),
            scene: "san_francisco".into(),
            json: serde_json::json!({"schema": LATENCY_SCHEMA, "converge_runs_ms": runs}),
        };
        let results = [
            row("before-ab", &[60_000.0, 64_000.0]),
            row("head-ab", &[62_000.0, 70_000.0, 68_000.0]),
        ];
        let mut m = String::new();
        section(&mut m, &results).unwrap();
        assert!(
            m.contains("| san_francisco | before-ab | 60.0 s, 64.0 s | 62.0 s | 1.00× |"),
            "{m}"
        );
        assert!(
            m.contains("| san_francisco | head-ab | 62.0 s, 70.0 s, 68.0 s | 68.0 s | 1.10× |"),
            "{m}"
        );
    }
}
