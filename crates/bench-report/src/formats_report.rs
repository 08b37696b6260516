//! The "Compressed files" section of docs/benchmarks.md, from `scripts/bench-formats.sh`'s results
//! (`docs/bench/formats/*.json`, schema `hrtao-format-compare/1`): each compressed file beside its uncompressed
//! twin, the triangles each decodes to, the AO MAE between them from one camera and, where a Cycles reference of
//! the view exists, each one's MAE against it.
use std::fmt::Write as _;
use std::path::Path;

use crate::report::table_header;
use anyhow::Result;
use serde::Deserialize;

pub const FORMAT_SCHEMA: &str = "hrtao-format-compare/1";
pub const OPEN_SCHEMA: &str = "hrtao-format-open/1";

/// One file opened (`scripts/bench-formats.sh`'s IFC row).
#[derive(Clone, Debug, Deserialize)]
pub struct Open {
    pub name: String,
    pub format: String,
    pub file: String,
    pub load_ms: f64,
    pub unique_triangles: u64,
    pub instanced_triangles: u64,
    pub meshes: u64,
    pub instances: u64,
    pub load_average: f64,
}

/// Every open-time result of `dir`, by name.
pub fn load_opens(dir: &Path) -> Result<Vec<Open>> {
    let mut out: Vec<Open> = crate::results::load_typed(dir, OPEN_SCHEMA, "open time")?;
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

/// The open times (nothing without results).
pub fn open_section(m: &mut String, rows: &[Open]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    writeln!(m, "### Opening IFC\n")?;
    writeln!(
        m,
        "`scripts/bench-formats.sh`: the process's `load_ms` of `hrtao render` (the IfcOpenShell worker's start, \
         its tessellation, the transfer, the scene), with the machine's load average at the time.\n"
    )?;
    table_header(
        m,
        "file | format | open ms | meshes | instances | unique triangles | instanced triangles | load",
    )?;
    for r in rows {
        writeln!(
            m,
            "| `{}` | {} | {:.0} | {} | {} | {} | {} | {:.1} |",
            r.file,
            r.format,
            r.load_ms,
            r.meshes,
            r.instances,
            r.unique_triangles,
            r.instanced_triangles,
            r.load_average
        )?;
    }
    writeln!(m)?;
    Ok(())
}

/// One compressed file against its twin.
#[derive(Clone, Debug, Deserialize)]
pub struct Compare {
    pub name: String,
    pub format: String,
    pub file: String,
    pub reference: String,
    pub width: u32,
    pub height: u32,
    pub unique_triangles: u64,
    pub reference_unique_triangles: u64,
    pub instances: u64,
    pub reference_instances: u64,
    pub load_ms: f64,
    pub reference_load_ms: f64,
    pub ao_mae: f64,
    pub covered: u64,
    pub cycles_mae: Option<f64>,
    pub reference_cycles_mae: Option<f64>,
}

/// Every comparison of `dir`, by name (none when the directory does not exist).
pub fn load(dir: &Path) -> Result<Vec<Compare>> {
    let mut out: Vec<Compare> = crate::results::load_typed(dir, FORMAT_SCHEMA, "comparison")?;
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

fn mae(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.4}"))
}

/// The section (nothing without results).
pub fn section(m: &mut String, rows: &[Compare]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    writeln!(m, "### Compressed glTF beside its uncompressed twin\n")?;
    writeln!(
        m,
        "`scripts/bench-formats.sh` renders each compressed file and its uncompressed twin from one camera with \
         per-pixel RTAO (128 rays, one frame: the geometry's own AO, no cache) and compares the AO over the pixels \
         either covers; where the view has a Blender Cycles reference, each file's MAE against it too. Open time: \
         the process's `load_ms` (read, decode, scene) on a shared CPU. Results in `docs/bench/formats/`.\n"
    )?;
    table_header(m, "file | encoding | against | size | unique triangles (twin) | instances (twin) | AO MAE to twin | MAE to Cycles (twin) | open ms (twin)")?;
    for r in rows {
        writeln!(
            m,
            "| `{}` | {} | `{}` | {}×{} | {} ({}) | {} ({}) | {:.4} over {} px | {} ({}) | {:.0} ({:.0}) |",
            r.file,
            r.format,
            r.reference,
            r.width,
            r.height,
            r.unique_triangles,
            r.reference_unique_triangles,
            r.instances,
            r.reference_instances,
            r.ao_mae,
            r.covered,
            mae(r.cycles_mae),
            mae(r.reference_cycles_mae),
            r.load_ms,
            r.reference_load_ms
        )?;
    }
    writeln!(m)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_comparison_becomes_a_row_and_no_results_no_section() {
        let mut m = String::new();
        section(&mut m, &[]).unwrap();
        assert!(m.is_empty());
        let row: Compare = serde_json::from_value(serde_json::json!({
            "schema": FORMAT_SCHEMA, "name": "engine_draco", "format": "Draco", "file": "a.gltf",
            "reference": "b.gltf", "width": 640, "height": 360, "unique_triangles": 65311,
            "reference_unique_triangles": 75730, "instances": 80, "reference_instances": 80, "load_ms": 120.4,
            "reference_load_ms": 60.2, "ao_mae": 0.0055, "covered": 90000, "cycles_mae": 0.0123,
            "reference_cycles_mae": null
        }))
        .unwrap();
        section(&mut m, &[row]).unwrap();
        assert!(m.contains("| `a.gltf` | Draco | `b.gltf` | 640×360 | 65311 (75730) | 80 (80) | 0.0055 over 90000 px | 0.0123 (–) | 120 (60) |"), "{m}");
    }
}
