//! The "GPU results" section of docs/benchmarks.md, from `scripts/gpu-check.sh run`'s report copied to
//! `docs/bench/gpu/report.json` (schema `hrtao-gpu-check/1`): the device, each check with its numbers and each
//! benchmark's key timings. Every other figure of the page comes from a CPU device (lavapipe); this section says
//! so plainly when no GPU report is there, rather than leaving the page silent about GPUs.
use std::fmt::Write as _;
use std::path::Path;

use crate::report::table_header;
use anyhow::{Context, Result};
use serde_json::Value;

/// Schema of the report `scripts/gpu_check.py` writes.
pub const SCHEMA: &str = "hrtao-gpu-check/1";

/// The report at `path`, or None when there is none; a file of another schema is an error (a wrong file copied
/// there must not pass for no measurement).
pub fn load(path: &Path) -> Result<Option<Value>> {
    if !path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let v: Value = serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    anyhow::ensure!(
        v["schema"].as_str() == Some(SCHEMA),
        "{}: schema {} is not {SCHEMA}",
        path.display(),
        v["schema"]
    );
    Ok(Some(v))
}

fn num(v: &Value, digits: usize) -> String {
    match v.as_f64() {
        Some(x) if v.is_f64() => format!("{x:.digits$}"),
        Some(x) => format!("{x}"),
        None => "–".into(),
    }
}

/// A check's figures that say whether it passed: the error against its limit, or the map's overload counters.
fn check_numbers(n: &Value) -> String {
    let mut parts = Vec::new();
    if n.get("mae").is_some() {
        parts.push(format!(
            "MAE {} (limit {})",
            num(&n["mae"], 4),
            num(&n["limit"], 3)
        ));
    }
    if n.get("failed_inserts").is_some() && n.get("capacity").is_some() {
        parts.push(format!(
            "{} cells: {} failed inserts, load {}, MAE against the normal map {} (limit {})",
            num(&n["capacity"], 0),
            num(&n["failed_inserts"], 0),
            num(&n["max_load_factor"], 3),
            num(&n["mae_vs_normal_map"], 4),
            num(&n["mae_limit"], 3)
        ));
    }
    if n.get("non_finite").is_some() {
        parts.push(format!(
            "AO in [{}, {}], {} non-finite",
            num(&n["min"], 3),
            num(&n["max"], 3),
            num(&n["non_finite"], 0)
        ));
    }
    parts.join("; ")
}

/// The section: the report's tables, or the line saying nothing was measured yet.
pub fn section(m: &mut String, report: Option<&Value>) -> Result<()> {
    writeln!(m, "## GPU results\n")?;
    let Some(r) = report else {
        writeln!(
            m,
            "Not measured yet: run `scripts/gpu-check.sh` on a GPU machine (`scripts/gpu-check.sh bundle` here, then \
             `gpu-check.sh run` from the bundle there) and copy its `report.json` to `docs/bench/gpu/report.json`.\n"
        )?;
        return Ok(());
    };
    let d = &r["device"];
    let s = |v: &Value| v.as_str().unwrap_or("?").to_string();
    let backends: Vec<String> = d["ray_backends"]
        .as_array()
        .map(|a| a.iter().map(s).collect())
        .unwrap_or_default();
    writeln!(
        m,
        "`scripts/gpu-check.sh run` on {} ({}), driver {}, Vulkan {}, on {}; rays traced by {} (checked: {}); \
         checks at {}{}, benchmarks without the error measurements. Overall: **{}**.\n",
        s(&d["name"]),
        s(&d["kind"]),
        s(&d["driver"]),
        s(&d["api_version"]),
        s(&r["date"]),
        s(&d["default_ray_backend"]),
        backends.join(" and "),
        s(&r["size"]),
        if r["small"] == true { " (--small)" } else { "" },
        if r["passed"] == true { "passed" } else { "failed" }
    )?;
    if let Some(e) = r["error"].as_str() {
        writeln!(m, "The run stopped: {e}\n")?;
    }
    let checks = r["checks"].as_array().cloned().unwrap_or_default();
    if !checks.is_empty() {
        table_header(m, "check | result | figures")?;
        for c in &checks {
            writeln!(
                m,
                "| {} | {} | {} |",
                s(&c["name"]),
                if c["passed"] == true { "pass" } else { "**fail**" },
                check_numbers(&c["numbers"])
            )?;
        }
        writeln!(m)?;
    }
    let benches = r["benches"].as_array().cloned().unwrap_or_default();
    if !benches.is_empty() {
        writeln!(
            m,
            "`hrtao bench` medians: *ours* is HRTAO with our additions, *paper* the paper's behaviour, *RTAO* \
             per-pixel ray-traced AO at the same rays per pixel; GPU ms from timestamp queries, wall ms per frame.\n"
        )?;
        writeln!(
            m,
            "| scene | size | mode | first frame, GPU ms | navigation frame, GPU ms | navigation frame, wall ms |"
        )?;
        writeln!(m, "|---|---|---|---:|---:|---:|")?;
        for b in &benches {
            for (key, name) in [("ours", "ours"), ("paper", "paper"), ("rtao", "RTAO")] {
                let t = &b["modes"][key];
                writeln!(
                    m,
                    "| {} | {}×{} | {name} | {} | {} | {} |",
                    s(&b["scene"]),
                    num(&b["width"], 0),
                    num(&b["height"], 0),
                    num(&t["first_frame_gpu_ms"], 2),
                    num(&t["nav_frame_gpu_ms"], 2),
                    num(&t["nav_frame_wall_ms"], 2)
                )?;
            }
        }
        writeln!(m)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_a_report_the_section_says_not_measured() {
        let mut m = String::new();
        section(&mut m, None).unwrap();
        assert!(m.starts_with("## GPU results\n"));
        assert!(
            m.contains("Not measured yet: run `scripts/gpu-check.sh` on a GPU machine"),
            "{m}"
        );
        assert!(load(Path::new("/nonexistent/report.json")).unwrap().is_none());
    }

    #[test]
    fn a_report_renders_its_checks_and_benchmarks() {
        let report = serde_json::json!({
            "schema": SCHEMA, "date": "2026-01-02 03:04 UTC", "small": false, "size": "640x360", "passed": true,
            "device": {"name": "Some GPU", "kind": "discrete GPU", "driver": "drv 1", "api_version": "1.3.0",
                       "default_ray_backend": "pipeline", "ray_backends": ["pipeline"]},
            "checks": [
                {"name": "rtao_vs_cycles_pipeline", "passed": true,
                 "numbers": {"mae": 0.0061, "limit": 0.02, "non_finite": 0, "min": 0.05, "max": 1.0}},
                {"name": "hash_map_overload", "passed": true,
                 "numbers": {"capacity": 1024, "failed_inserts": 500, "max_load_factor": 1.0,
                             "mae_vs_normal_map": 0.03, "mae_limit": 0.15, "non_finite": 0, "min": 0.05, "max": 1.0}}
            ],
            "benches": [{"scene": "sf", "width": 1920, "height": 1080, "modes": {
                "ours": {"first_frame_gpu_ms": 1.5, "nav_frame_gpu_ms": 0.75, "nav_frame_wall_ms": 1.0},
                "paper": {"first_frame_gpu_ms": 1.25, "nav_frame_gpu_ms": 0.5, "nav_frame_wall_ms": 0.8},
                "rtao": {"first_frame_gpu_ms": 2.0, "nav_frame_gpu_ms": 2.0, "nav_frame_wall_ms": 2.5}}}]
        });
        let mut m = String::new();
        section(&mut m, Some(&report)).unwrap();
        assert!(m.contains("on Some GPU (discrete GPU), driver drv 1"), "{m}");
        assert!(m.contains("**passed**"), "{m}");
        assert!(
            m.contains("| rtao_vs_cycles_pipeline | pass | MAE 0.0061 (limit 0.020)"),
            "{m}"
        );
        assert!(m.contains("1024 cells: 500 failed inserts, load 1.000"), "{m}");
        assert!(
            m.contains("| sf | 1920×1080 | ours | 1.50 | 0.75 | 1.00 |"),
            "{m}"
        );
        assert!(
            m.contains("| sf | 1920×1080 | paper | 1.25 | 0.50 | 0.80 |"),
            "{m}"
        );
        assert!(!m.contains("Not measured yet"));
    }

    #[test]
    fn a_file_of_another_schema_is_an_error() {
        let dir = std::env::temp_dir().join(format!("hrtao-gpu-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("report.json");
        std::fs::write(&path, r#"{"schema": "hrtao-bench/1"}"#).unwrap();
        assert!(load(&path).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
