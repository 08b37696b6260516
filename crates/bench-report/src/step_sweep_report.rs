//! The "Tessellation for the eye" part of the STEP section of docs/benchmarks.md, from
//! `scripts/step-tessellation-sweep.sh`'s results (`docs/bench/step/sweep_*.json`, schema `hrtao-step-sweep/1`):
//! per file, each tessellation's triangles, AO and shaded MAE against the finest, load and BVH times, with the
//! default's and the fine choice's rows named, and what the default saves against the fine one.
use std::fmt::Write as _;
use std::path::Path;

use crate::report::table_header;
use anyhow::Result;
use hrtao_scene::CadTessellation;
use serde::Deserialize;

pub const SWEEP_SCHEMA: &str = "hrtao-step-sweep/1";

/// One tessellation of a file.
#[derive(Clone, Debug, Deserialize)]
pub struct Row {
    pub relative: f64,
    pub angular_deg: f64,
    pub instanced_triangles: u64,
    pub unique_triangles: u64,
    pub ao_mae: f64,
    pub shaded_mae: f64,
    pub load_ms: f64,
    pub bvh_ms: f64,
}

/// One file's sweep.
#[derive(Clone, Debug, Deserialize)]
pub struct Sweep {
    pub file: String,
    pub frames: u32,
    pub width: u32,
    pub height: u32,
    pub rows: Vec<Row>,
}

/// Every sweep of `dir`, by file name (none when the directory does not exist).
pub fn load(dir: &Path) -> Result<Vec<Sweep>> {
    let mut out: Vec<Sweep> = crate::results::load_typed(dir, SWEEP_SCHEMA, "sweep")?;
    out.sort_by(|a, b| a.file.cmp(&b.file));
    Ok(out)
}

fn is(row: &Row, t: &CadTessellation) -> bool {
    (row.relative - t.relative).abs() < 1e-9 && (row.angular_deg - t.angular_deg).abs() < 1e-9
}

/// The finest tessellation of a sweep: its reference.
fn reference(s: &Sweep) -> Option<&Row> {
    s.rows.iter().max_by_key(|r| r.instanced_triangles)
}

/// The section (nothing without sweeps).
pub fn section(m: &mut String, sweeps: &[Sweep]) -> Result<()> {
    let Some(s0) = sweeps.first() else {
        return Ok(());
    };
    let (default, fine) = (CadTessellation::default(), CadTessellation::FINE);
    writeln!(m, "### Tessellation for the eye: the sweep behind the default\n")?;
    writeln!(
        m,
        "B-rep faces carry OpenCASCADE's surface normals (one per node of each face's triangulation), so curved \
         faces shade smoothly at any tessellation and the triangles need only keep silhouettes and AO true. \
         `scripts/step-tessellation-sweep.sh` renders each file at a list of deflections (linear as a fraction of \
         each part's bounding-box diagonal, angular in degrees), the default HRTAO mode with AO, {} still frames \
         at {}×{} from a fixed camera, and compares each image with the finest over the pixels the model covers \
         in either: the linear AO (`--ao-out`) and the shaded image with its normals (`--out`, RGB / 255). Load \
         is the process's `load_ms` (worker start, read, transfer, tessellation, scene) and BVH the BLAS + TLAS \
         build, both on a shared CPU (noisy). Results in `docs/bench/step/`.\n",
        s0.frames, s0.width, s0.height
    )?;
    for s in sweeps {
        let finest = reference(s).map(|r| r.instanced_triangles);
        writeln!(m, "**`{}`**\n", s.file)?;
        table_header(m, "linear (× diagonal) | angular | triangles (instanced) | unique | AO MAE | shaded MAE | load ms | BLAS+TLAS ms")?;
        for r in &s.rows {
            let name = if Some(r.instanced_triangles) == finest {
                " reference"
            } else if is(r, &default) {
                " **default**"
            } else if is(r, &fine) {
                " fine"
            } else {
                ""
            };
            writeln!(
                m,
                "| {}{name} | {}° | {} | {} | {:.4} | {:.4} | {:.0} | {:.1} |",
                r.relative,
                r.angular_deg,
                r.instanced_triangles,
                r.unique_triangles,
                r.ao_mae,
                r.shaded_mae,
                r.load_ms,
                r.bvh_ms
            )?;
        }
        writeln!(m)?;
    }
    writeln!(
        m,
        "The default, **{} % of each part's size and {}°** (`CadTessellation::default()`), against the fine \
         choice ({} %, {}°: `CadTessellation::FINE`, `--deflection {} --angular-deflection {}`, or the Load \
         options panel):\n",
        default.relative * 100.0,
        default.angular_deg,
        fine.relative * 100.0,
        fine.angular_deg,
        fine.relative,
        fine.angular_deg
    )?;
    table_header(m, "file | triangles default / fine | share | AO MAE default / fine | shaded MAE default / fine | BLAS+TLAS ms default / fine | load ms default / fine")?;
    for s in sweeps {
        let (Some(d), Some(f)) = (
            s.rows.iter().find(|r| is(r, &default)),
            s.rows.iter().find(|r| is(r, &fine)),
        ) else {
            continue;
        };
        writeln!(
            m,
            "| `{}` | {} / {} | {:.0} % | {:.4} / {:.4} | {:.4} / {:.4} | {:.1} / {:.1} | {:.0} / {:.0} |",
            s.file,
            d.instanced_triangles,
            f.instanced_triangles,
            100.0 * d.instanced_triangles as f64 / f.instanced_triangles.max(1) as f64,
            d.ao_mae,
            f.ao_mae,
            d.shaded_mae,
            f.shaded_mae,
            d.bvh_ms,
            f.bvh_ms,
            d.load_ms,
            f.load_ms
        )?;
    }
    writeln!(m)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(relative: f64, angular_deg: f64, tris: u64, ao: f64) -> Row {
        Row {
            relative,
            angular_deg,
            instanced_triangles: tris,
            unique_triangles: tris,
            ao_mae: ao,
            shaded_mae: ao,
            load_ms: 100.0,
            bvh_ms: 1.0,
        }
    }

    /// The finest row is the reference, the default's and the fine choice's rows are named, and the summary
    /// gives the default's share of the fine choice's triangles.
    #[test]
    fn a_sweep_names_its_rows_and_sums_up_the_default() {
        let (d, f) = (CadTessellation::default(), CadTessellation::FINE);
        let sweep = Sweep {
            file: "part.step".into(),
            frames: 32,
            width: 640,
            height: 360,
            rows: vec![
                row(0.0002, 5.0, 9000, 0.0),
                row(f.relative, f.angular_deg, 4000, 0.0001),
                row(d.relative, d.angular_deg, 1000, 0.0003),
                row(0.1, 90.0, 500, 0.002),
            ],
        };
        let mut m = String::new();
        section(&mut m, &[sweep]).unwrap();
        assert!(m.contains("| 0.0002 reference | 5° | 9000 |"), "{m}");
        assert!(
            m.contains(&format!(
                "| {} **default** | {}° | 1000 |",
                d.relative, d.angular_deg
            )),
            "{m}"
        );
        assert!(
            m.contains(&format!("| {} fine | {}° | 4000 |", f.relative, f.angular_deg)),
            "{m}"
        );
        assert!(
            m.contains("| `part.step` | 1000 / 4000 | 25 % | 0.0003 / 0.0001 |"),
            "{m}"
        );
        let mut empty = String::new();
        section(&mut empty, &[]).unwrap();
        assert!(empty.is_empty());
    }
}
