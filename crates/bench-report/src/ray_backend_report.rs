//! The "Ray queries against ray-tracing pipelines" section of docs/benchmarks.md, from
//! `scripts/bench-ray-backends.sh`'s results (`docs/bench/ray_backend/<backend>_<scene>_<run>.json`, `hrtao
//! bench`'s schema): per scene, the whole first frame and the navigation frame with each way to trace, and the
//! pipeline's cost over the ray queries' as the ratio of the medians over runs that alternated.
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use hrtao_core::bench_json::BenchResult;
use hrtao_core::stats::median;

use crate::report::table_header;
use crate::results::load_results;

/// How a run traced its rays: the device record's `ray_backend` (`query` or `pipeline`).
fn backend(r: &BenchResult) -> Option<&str> {
    r.device.get("ray_backend")?.as_str()
}

/// Every bench result of `dir` (none when it does not exist).
pub fn load(dir: &Path) -> Result<Vec<BenchResult>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    Ok(load_results(dir)?.into_iter().map(|(_, r)| r).collect())
}

/// Medians over a backend's runs of one scene: first frame and navigation frame (wall ms), and the runs.
fn medians(runs: &[&BenchResult]) -> (f64, f64, usize) {
    let first: Vec<f64> = runs.iter().map(|r| r.summary.first_wall_ms).collect();
    let nav: Vec<f64> = runs.iter().map(|r| r.summary.nav_wall_ms).collect();
    (median(&first), median(&nav), runs.len())
}

/// Appends the section (nothing without results).
pub fn section(m: &mut String, results: &[BenchResult]) -> Result<()> {
    if results.is_empty() {
        return Ok(());
    }
    let mut scenes: Vec<&str> = results.iter().map(|r| r.scene.label.as_str()).collect();
    scenes.sort();
    scenes.dedup();
    writeln!(m, "## Ray queries against ray-tracing pipelines\n")?;
    writeln!(
        m,
        "`scripts/bench-ray-backends.sh` (`docs/bench/ray_backend/`): `hrtao bench --ray-backend query|pipeline` \
         at 640×360, 8 rays per pixel, the two backends alternating run by run. Each cell: the median over the \
         runs of each run's median whole-frame wall time (first frame from an empty map; navigation frame of an \
         orbit); the ratio is pipeline over query.\n"
    )?;
    table_header(
        m,
        "scene | runs | first frame: query / pipeline | ratio | navigation frame: query / pipeline | ratio",
    )?;
    for scene in scenes {
        let of = |b: &str| -> Vec<&BenchResult> {
            results
                .iter()
                .filter(|r| r.scene.label == scene && backend(r) == Some(b))
                .collect()
        };
        let (q, p) = (of("query"), of("pipeline"));
        if q.is_empty() || p.is_empty() {
            continue;
        }
        let ((qf, qn, qr), (pf, pn, pr)) = (medians(&q), medians(&p));
        writeln!(
            m,
            "| {scene} | {} | {qf:.0} / {pf:.0} ms | **{:.2}×** | {qn:.0} / {pn:.0} ms | **{:.2}×** |",
            qr.min(pr),
            pf / qf,
            pn / qn
        )?;
    }
    m.push('\n');
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A committed bench result as a run of `backend` with the given first and navigation frames.
    fn run(backend: &str, first: f64, nav: f64) -> BenchResult {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/bench/first_frame");
        let mut r = load_results(&dir).unwrap().remove(0).1;
        r.device["ray_backend"] = serde_json::json!(backend);
        r.summary.first_wall_ms = first;
        r.summary.nav_wall_ms = nav;
        r
    }

    #[test]
    fn each_backend_is_a_median_over_its_runs_and_the_ratio_is_pipeline_over_query() {
        let results = vec![
            run("query", 100.0, 10.0),
            run("pipeline", 150.0, 12.0),
            run("query", 300.0, 30.0),
            run("pipeline", 130.0, 14.0),
            run("query", 120.0, 11.0),
            run("pipeline", 900.0, 13.0),
        ];
        let mut m = String::new();
        section(&mut m, &results).unwrap();
        let label = &results[0].scene.label;
        // Medians: query 120 / 11, pipeline 150 / 13 (the 300 and 900 outliers do not move them).
        assert!(
            m.contains(&format!(
                "| {label} | 3 | 120 / 150 ms | **1.25×** | 11 / 13 ms | **1.18×** |"
            )),
            "{m}"
        );
        // A scene measured with one backend only has no row.
        let mut m = String::new();
        section(&mut m, &results[..1]).unwrap();
        assert!(!m.contains(&format!("| {label} |")), "{m}");
    }
}
