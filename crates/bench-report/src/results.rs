//! The `hrtao bench` results of a directory (schema `hrtao-bench/1`), read for the report and its sections.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use hrtao_core::bench_json::{BenchResult, SCHEMA};

/// Loads the bench results of `dir` (files with another schema are skipped), scenes first, then by size.
pub fn load_results(dir: &Path) -> Result<Vec<(PathBuf, BenchResult)>> {
    let mut out = Vec::new();
    let entries = std::fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))?;
    for e in entries {
        let path = e?.path();
        if path.extension().and_then(|x| x.to_str()) != Some("json") {
            continue;
        }
        let text = std::fs::read_to_string(&path)?;
        let v: serde_json::Value = match serde_json::from_str(&text) {
            Ok(v) => v,
            Err(_) => continue,
        };
        if v.get("schema").and_then(|s| s.as_str()) != Some(SCHEMA) {
            continue;
        }
        let r: BenchResult =
            serde_json::from_value(v).with_context(|| format!("{}: bad bench result", path.display()))?;
        out.push((path, r));
    }
    out.sort_by(|a, b| {
        (
            a.1.scene.group != "scenes",
            a.1.scene.instanced_triangles,
            &a.1.scene.label,
        )
            .cmp(&(
                b.1.scene.group != "scenes",
                b.1.scene.instanced_triangles,
                &b.1.scene.label,
            ))
    });
    Ok(out)
}

/// Every JSON file of `dir` whose `schema` is `schema`, with its path (none when `dir` does not exist): the
/// results of the scripts' sections (latency, viewer runs).
pub fn load_schema(dir: &Path, schema: &str) -> Result<Vec<(PathBuf, serde_json::Value)>> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(out);
    };
    for e in entries {
        let path = e?.path();
        if path.extension().and_then(|x| x.to_str()) != Some("json") {
            continue;
        }
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path)?)
            .with_context(|| format!("{}: not JSON", path.display()))?;
        if json["schema"].as_str() == Some(schema) {
            out.push((path, json));
        }
    }
    Ok(out)
}

/// Every result of `schema` in `dir` as a `T` (`what` names one in the error of a file that is not), in file
/// order (none when the directory does not exist).
pub fn load_typed<T: serde::de::DeserializeOwned>(dir: &Path, schema: &str, what: &str) -> Result<Vec<T>> {
    load_schema(dir, schema)?
        .into_iter()
        .map(|(path, v)| serde_json::from_value(v).with_context(|| format!("{}: bad {what}", path.display())))
        .collect()
}
