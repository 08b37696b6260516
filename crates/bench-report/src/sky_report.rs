//! The "Sky light" section of docs/benchmarks.md, from `scripts/bench-sky.sh`'s results
//! (`docs/bench/sky/KEY_MODE_FRAMES.json`, `hrtao render --stats`, MODE `ao` or `ENV_ROT`): per shared scene and
//! view, the sky light's error against its Cycles reference after 1 and 32 frames at 8 rays per pixel, beside the
//! AO mode's first-frame error against its own reference, and the cost of a frame in each mode.
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use serde_json::Value;

use crate::report::table_header;
use hrtao_core::stats::median;

/// One render: its scene key, mode (`ao` or `ENV_ROT`), frames and statistics.
#[derive(Clone, Debug)]
pub struct Run {
    pub key: String,
    pub mode: String,
    pub frames: u32,
    pub stats: Value,
}

/// Every result of `dir` (none when it does not exist), named KEY_MODE_FRAMES.json.
pub fn load(dir: &Path) -> Result<Vec<Run>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut runs = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        let (key, rest) = stem
            .split_once('_')
            .with_context(|| format!("{}: not KEY_MODE_FRAMES", path.display()))?;
        let (mode, frames) = rest
            .rsplit_once('_')
            .with_context(|| format!("{}: not KEY_MODE_FRAMES", path.display()))?;
        let stats: Value = serde_json::from_str(&std::fs::read_to_string(&path)?)
            .with_context(|| format!("reading {}", path.display()))?;
        runs.push(Run {
            key: key.to_string(),
            mode: mode.to_string(),
            frames: frames
                .parse()
                .with_context(|| format!("{}: frames", path.display()))?,
            stats,
        });
    }
    runs.sort_by(|a, b| (&a.key, &a.mode, a.frames).cmp(&(&b.key, &b.mode, b.frames)));
    Ok(runs)
}

fn f(v: &Value, path: &[&str]) -> Option<f64> {
    path.iter().try_fold(v, |v, k| v.get(k))?.as_f64()
}

/// The first frame's wall ms and the median wall ms of the still frames after it.
fn frame_ms(stats: &Value) -> Option<(f64, f64)> {
    let frames = stats.get("frames")?.as_array()?;
    let wall: Vec<f64> = frames.iter().filter_map(|x| x.get("wall_ms")?.as_f64()).collect();
    let (first, still) = wall.split_first()?;
    Some((*first, if still.is_empty() { f64::NAN } else { median(still) }))
}

/// Appends the section (nothing without results).
pub fn section(m: &mut String, runs: &[Run]) -> Result<()> {
    if runs.is_empty() {
        return Ok(());
    }
    let find = |key: &str, mode: &str, frames: u32| {
        runs.iter()
            .find(|r| r.key == key && r.mode == mode && r.frames == frames)
            .map(|r| &r.stats)
    };
    let mut views: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for r in runs.iter().filter(|r| r.mode != "ao") {
        let v = views.entry(r.key.as_str()).or_default();
        if !v.contains(&r.mode.as_str()) {
            v.push(r.mode.as_str());
        }
    }
    writeln!(m, "## Sky light\n")?;
    writeln!(
        m,
        "`scripts/bench-sky.sh` (`docs/bench/sky/`): `hrtao render --environment ENV --environment-rotation ROT` \
         at 640×360, 8 rays per pixel, against Blender Cycles references of the `--light-out` contract \
         (`scripts/make-sky-references.sh --size 640x360`); the AO mode on the same view against its Cycles AO \
         reference. MAE of the light over the pixels the model covers (÷ mean: over the reference's mean there); \
         the AO's over the pixels not open. Frame times: wall ms of the first frame from an empty map and the \
         median of the still frames after it, sky light / AO, from the 32-frame runs.\n"
    )?;
    table_header(m, "scene | environment | rotation | frame 1 MAE (AO's) | ratio | frame 32 MAE | ÷ mean | first frame ms: sky / AO | still frame ms: sky / AO")?;
    for (key, modes) in views {
        let ao1 = find(key, "ao", 1).and_then(|s| f(s, &["ao_error", "mae"]));
        let ao_ms = find(key, "ao", 32).and_then(frame_ms);
        for mode in modes {
            let (env, rot) = mode.rsplit_once('_').unwrap_or((mode, "0"));
            let one = find(key, mode, 1).and_then(|s| f(s, &["light_error", "mae"]));
            let last = find(key, mode, 32);
            let mae32 = last.and_then(|s| f(s, &["light_error", "mae"]));
            let mean = last.and_then(|s| f(s, &["light_error", "reference_mean"]));
            let ms = last.and_then(frame_ms);
            let num =
                |v: Option<f64>, digits: usize| v.map_or("–".to_string(), |v| format!("{v:.digits$}"));
            let ratio = match (one, ao1) {
                (Some(a), Some(b)) if b > 0.0 => format!("{:.2}×", a / b),
                _ => "–".into(),
            };
            let rel = match (mae32, mean) {
                (Some(a), Some(b)) if b > 0.0 => format!("{:.4}", a / b),
                _ => "–".into(),
            };
            let pair = |i: usize| match (ms, ao_ms) {
                (Some(s), Some(a)) => {
                    let (s, a) = if i == 0 { (s.0, a.0) } else { (s.1, a.1) };
                    format!("{s:.0} / {a:.0} ({:.2}×)", s / a)
                }
                _ => "–".into(),
            };
            writeln!(
                m,
                "| {key} | {env} | {rot}° | {} ({}) | {ratio} | {} | {rel} | {} | {} |",
                num(one, 4),
                num(ao1, 4),
                num(mae32, 4),
                pair(0),
                pair(1)
            )?;
        }
    }
    m.push('\n');
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(key: &str, mode: &str, frames: u32, stats: Value) -> Run {
        Run {
            key: key.into(),
            mode: mode.into(),
            frames,
            stats,
        }
    }

    #[test]
    fn a_view_row_sets_the_sky_beside_the_ao() {
        let frames = |first: f64, still: f64| serde_json::json!([{"wall_ms": first}, {"wall_ms": still}, {"wall_ms": still + 10.0}, {"wall_ms": still}]);
        let runs = vec![
            run("rod", "ao", 1, serde_json::json!({"ao_error": {"mae": 0.02}})),
            run(
                "rod",
                "ao",
                32,
                serde_json::json!({"frames": frames(400.0, 100.0)}),
            ),
            run(
                "rod",
                "sky_lobe_64x32_90",
                1,
                serde_json::json!({"light_error": {"mae": 0.03}}),
            ),
            run(
                "rod",
                "sky_lobe_64x32_90",
                32,
                serde_json::json!({"light_error": {"mae": 0.005, "reference_mean": 0.5}, "frames": frames(600.0, 150.0)}),
            ),
        ];
        let mut m = String::new();
        section(&mut m, &runs).unwrap();
        assert!(
            m.contains(
                "| rod | sky_lobe_64x32 | 90° | 0.0300 (0.0200) | 1.50× | 0.0050 | 0.0100 | 600 / 400 (1.50×) | 150 / 100 (1.50×) |"
            ),
            "{m}"
        );
        let mut empty = String::new();
        section(&mut empty, &[]).unwrap();
        assert!(empty.is_empty());
    }
}
