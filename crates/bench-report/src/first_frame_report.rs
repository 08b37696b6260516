//! The "First frame against the paper's mode, per addition" section of docs/benchmarks.md, from
//! `scripts/bench-first-frame.sh`'s results (`docs/bench/first_frame/<config>_<scene>.json`, `hrtao bench`'s
//! schema): each configuration's first frame from an empty map against the paper's mode, the two renderers
//! alternating in one run (`hrtao bench`'s `time_hrtao`), as the median of the paired ratios.
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use hrtao_core::bench_json::BenchResult;
use hrtao_core::stats::{median, paired_ratio};

use crate::results::load_results;

/// One configuration on one scene: the file name's prefix (`default` or an ablation row's name, `no-near-field`)
/// and the run.
pub struct FirstFrameRun {
    pub config: String,
    pub result: BenchResult,
}

/// Every bench result of `dir` (none when it does not exist) with its configuration, by configuration
/// (`default` first) then scene.
pub fn load(dir: &Path) -> Result<Vec<FirstFrameRun>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut out: Vec<FirstFrameRun> = load_results(dir)?
        .into_iter()
        .filter_map(|(path, result)| {
            let stem = path.file_stem()?.to_str()?;
            let (config, _scene) = stem.split_once('_')?;
            Some(FirstFrameRun {
                config: config.to_string(),
                result,
            })
        })
        .collect();
    out.sort_by(|a, b| {
        (a.config != "default", &a.config, &a.result.scene.label).cmp(&(
            b.config != "default",
            &b.config,
            &b.result.scene.label,
        ))
    });
    Ok(out)
}

/// The run's first frames (whole-frame GPU ms): its median, the paper's, and the median of the paired ratios
/// (None without a paper's run).
pub fn first_frame_ratio(r: &BenchResult) -> Option<(f64, f64, f64)> {
    let paper = r.paper.as_ref()?;
    let ours: Vec<f64> = r.hrtao.first.iter().map(|f| f.gpu_total_ms).collect();
    let theirs: Vec<f64> = paper.first.iter().map(|f| f.gpu_total_ms).collect();
    Some((median(&ours), median(&theirs), paired_ratio(&ours, &theirs)))
}

/// Appends the section (nothing without results).
pub fn section(m: &mut String, runs: &[FirstFrameRun]) -> Result<()> {
    if runs.is_empty() {
        return Ok(());
    }
    let mut scenes: Vec<&str> = runs.iter().map(|r| r.result.scene.label.as_str()).collect();
    scenes.sort();
    scenes.dedup();
    let mut configs: Vec<&str> = runs.iter().map(|r| r.config.as_str()).collect();
    configs.dedup();
    writeln!(m, "## First frame against the paper's mode, per addition\n")?;
    writeln!(
        m,
        "`scripts/bench-first-frame.sh` (`docs/bench/first_frame/`): the first frame from an empty map of our \
         defaults, and of our defaults with one addition off, against `AoSettings::paper()` in the same run, the \
         two renderers alternating (`--repeat 5 --settle 0`). Each cell: our GPU ms / the paper's (medians), \
         then the median of the paired ratios. What each addition buys in MAE is its row of the ablation \
         (docs/algorithm.md).\n"
    )?;
    writeln!(m, "| configuration | {} |", scenes.join(" | "))?;
    writeln!(m, "|---|{}", "---|".repeat(scenes.len()))?;
    for config in configs {
        let mut row = format!("| {config} |");
        for scene in &scenes {
            let cell = runs
                .iter()
                .find(|r| r.config == config && r.result.scene.label == *scene)
                .and_then(|r| first_frame_ratio(&r.result));
            match cell {
                Some((ours, paper, ratio)) => write!(row, " {ours:.0} / {paper:.0} ms, **{ratio:.2}×** |")?,
                None => row.push_str(" – |"),
            }
        }
        writeln!(m, "{row}")?;
    }
    m.push('\n');
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    fn committed() -> Vec<FirstFrameRun> {
        load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/bench/first_frame")).unwrap()
    }

    /// The ratio pairs each of our first frames with the paper's of the same turn: a machine that slows down
    /// between turns moves both frames of a pair, not the ratio (the ratio of the medians would read 1.33 here).
    #[test]
    fn the_ratio_is_the_median_of_the_paired_frames() {
        let mut run = committed().into_iter().next().expect("committed results").result;
        let set = |frames: &mut Vec<hrtao_core::bench_json::FrameRecord>, ms: &[f64]| {
            frames.truncate(1);
            let f = frames[0].clone();
            *frames = ms
                .iter()
                .map(|&gpu_total_ms| hrtao_core::bench_json::FrameRecord {
                    gpu_total_ms,
                    ..f.clone()
                })
                .collect();
        };
        set(&mut run.hrtao.first, &[200.0, 400.0, 900.0]);
        set(&mut run.paper.as_mut().unwrap().first, &[100.0, 300.0, 450.0]);
        let (ours, paper, ratio) = first_frame_ratio(&run).unwrap();
        assert_eq!((ours, paper, ratio), (400.0, 300.0, 2.0));
        let mut m = String::new();
        section(
            &mut m,
            &[FirstFrameRun {
                config: "default".into(),
                result: run,
            }],
        )
        .unwrap();
        assert!(m.contains("| default | 400 / 300 ms, **2.00×** |"), "{m}");
    }

    /// Every committed configuration has a row, `default` first, each scene a column.
    #[test]
    fn the_committed_results_make_the_table() {
        let runs = committed();
        assert!(runs.iter().any(|r| r.config == "default"));
        let mut m = String::new();
        section(&mut m, &runs).unwrap();
        let rows: Vec<&str> = m
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| configuration"))
            .collect();
        assert!(rows[0].starts_with("| default |"), "{m}");
        for r in &runs {
            assert!(
                rows.iter().any(|l| l.starts_with(&format!("| {} |", r.config))),
                "{} missing:\n{m}",
                r.config
            );
        }
    }
}
