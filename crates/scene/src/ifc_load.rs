//! IFC loading: the file is checked here (guard, STEP header, schema, entity count), then read and tessellated by
//! IfcOpenShell in a Python worker process (`crates/scene/ifc/ifc_worker.py`, embedded in the binary and run by
//! the venv's interpreter that `scripts/install-deps.sh` creates), which streams the frames of [`crate::cad`]:
//! one part per representation (products sharing a mapped representation are instances of one mesh), the
//! spatial tree (project → site → building → storey → element, labelled with names and IFC classes), style
//! colours and the file's length unit (its IfcProject's, also where IfcOpenShell's iterator finds none; a file that
//! declares none is read in metres with a warning in [`Scene::warnings`] and the log). The scene is built as for
//! STEP ([`crate::cad_load::to_scene`]): the file's unit, re-centred when far from the origin (georeferenced
//! coordinates). The worker runs under the same limits as the OpenCASCADE one: address space, CPU seconds
//! (`HRTAO_IFC_CPU_SECONDS`, default 300), killed on Cancel or with the viewer. Before tessellating, it counts
//! what the representation maps expand to (mapped items multiplied through their nesting; a map shared by
//! products counted once, as it stays one mesh): over [`MAX_IFC_ITEMS`] (or [`IFC_ITEM_BYTES`] each within the
//! scene memory limit) the load is refused as too large, naming the count and the cap. A file that does not end
//! with `END-ISO-10303-21;` opens with a warning that the model may be incomplete.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use crate::cad::CAD_ENTITY_BYTES;
use crate::cad_load::{run_worker_command, step_entities, StageClock, WorkerError, WorkerLimits};
use crate::error::SceneError;
use crate::guard::{read_model, LoadOptions};
use crate::scene::{LoadProgress, Scene};

/// The IfcOpenShell release the install script pins (and the worker was written against).
pub const IFCOPENSHELL_VERSION: &str = "0.8.4.post1";

/// The worker script, embedded so that an installed binary needs only the venv.
const WORKER_SCRIPT: &str = include_str!("../ifc/ifc_worker.py");

/// Most entities an IFC file may have (IfcOpenShell keeps every entity in memory, about 1 KiB each).
const MAX_IFC_ENTITIES: u64 = 10_000_000;

/// Address space the worker may use beyond the scene memory limit (Python, NumPy, IfcOpenShell and OCCT
/// libraries, thread stacks and heap arenas).
const WORKER_OVERHEAD: u64 = 2 << 30;

/// Most geometry items the products' representations may expand to, mapped items multiplied through their
/// nesting (counted by the worker before it tessellates: [`crate::MAX_INSTANCES`], as for generated scenes).
const MAX_IFC_ITEMS: u64 = crate::MAX_INSTANCES;

/// Memory an expanded geometry item takes at least (IfcOpenShell's shape, its tessellation, the mesh hand-over):
/// the item cap within the scene memory limit. Must match `ITEM_BYTES` in the worker, which names it.
const IFC_ITEM_BYTES: u64 = 4096;

/// The schemas IfcOpenShell 0.8 reads.
const SCHEMAS: [&str; 4] = ["IFC2X3", "IFC4X3", "IFC4X1", "IFC4"];

/// The command that installs the worker, as errors name it.
pub fn install_command() -> String {
    format!(
        "scripts/install-deps.sh (from the hrtao source), or by hand: python3 -m venv {dir} && {dir}/bin/pip \
         install ifcopenshell=={IFCOPENSHELL_VERSION}",
        dir = default_venv().display()
    )
}

/// `${XDG_DATA_HOME:-$HOME/.local/share}/hrtao/ifc-venv`: where the install script puts the venv
/// (`dirs::data_dir`: an empty or relative `XDG_DATA_HOME` is ignored, as the XDG specification says).
pub fn default_venv() -> PathBuf {
    dirs::data_dir()
        .unwrap_or_else(|| PathBuf::from(".local/share"))
        .join("hrtao/ifc-venv")
}

/// The interpreter that runs the worker: `HRTAO_IFC_PYTHON`, else the venv's `bin/python3`.
pub fn ifc_python() -> PathBuf {
    std::env::var_os("HRTAO_IFC_PYTHON")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| default_venv().join("bin/python3"))
}

fn cpu_seconds() -> u64 {
    std::env::var("HRTAO_IFC_CPU_SECONDS")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(300)
}

pub fn load_ifc(
    path: &Path,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    let started = Instant::now();
    let err = |message: String| SceneError::Cad {
        format: "IFC",
        path: path.to_path_buf(),
        message,
    };
    let (bytes, mut budget) = read_model(path, opts, progress)?;
    let entities = check_header(&bytes).map_err(err)?;
    let cap = MAX_IFC_ENTITIES.min(opts.max_memory / CAD_ENTITY_BYTES);
    if entities > cap {
        return Err(SceneError::TooLarge(format!(
            "{}: {entities} entities, over the cap of {cap} (at most {MAX_IFC_ENTITIES}, and {CAD_ENTITY_BYTES} \
             bytes of IfcOpenShell memory each within the scene memory limit, HRTAO_MAX_SCENE_MB)",
            path.display(),
        )));
    }
    budget.reserve(entities * CAD_ENTITY_BYTES, "IfcOpenShell's entities")?;
    let ends_early = crate::cad_load::ends_early(&bytes);
    // A file cut short is read up to its last whole statement (IfcOpenShell crashes on a string left open).
    let complete = ends_early.then(|| complete_statements(&bytes));
    drop(bytes);
    opts.check_cancel(path)?;
    let python = ifc_python();
    if !python.is_file() {
        return Err(err(format!(
            "IFC files are read by IfcOpenShell in a Python worker, and its interpreter {} does not exist: \
             install it with {}",
            python.display(),
            install_command()
        )));
    }
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut cmd = Command::new(&python);
    // -I: isolated (no PYTHONPATH, no user site, no current folder on the path).
    cmd.arg("-I").arg("-c").arg(WORKER_SCRIPT).arg(&abs);
    // What the representation maps may expand to (ifc_worker.py counts it before tessellating).
    let max_items = MAX_IFC_ITEMS.min(opts.max_memory / IFC_ITEM_BYTES).max(1);
    cmd.env("HRTAO_IFC_MAX_ITEMS", max_items.to_string());
    if let Some(n) = complete {
        cmd.env("HRTAO_IFC_COMPLETE_BYTES", n.to_string());
    }
    let limits = WorkerLimits {
        kernel: "IfcOpenShell",
        address_space: opts.max_memory.saturating_add(WORKER_OVERHEAD),
        cpu_seconds: cpu_seconds(),
    };
    let mut stages = StageClock::new();
    stages.mark("spawn");
    let model =
        run_worker_command(cmd, &python, &limits, opts, &mut stages, progress).map_err(|e| match e {
            WorkerError::Cancelled => SceneError::Cancelled(path.display().to_string()),
            WorkerError::Failed(m) if m.contains("IfcOpenShell is not installed") => {
                err(format!("{m} (install: {})", install_command()))
            }
            // The worker's count of mapped items over the cap (ifc_worker.py, `mapped_expansion`).
            WorkerError::Failed(m) if m.contains("geometry items") && m.contains("over the cap") => {
                SceneError::TooLarge(format!("{}: {m}", path.display()))
            }
            WorkerError::Failed(m) => err(m),
        })?;
    let read_s = started.elapsed().as_secs_f64();
    // The worker reports 0 (no unit) when the IfcProject's IfcUnitAssignment declares no length unit it can read.
    let no_unit = model.file_unit_m.is_none();
    let mut scene = crate::cad_load::to_scene(path, model).map_err(err)?;
    if no_unit {
        let warning = no_unit_warning(path, scene.unit_m.unwrap_or(1.0));
        log::warn!("{warning}");
        scene.warnings.push(warning);
    }
    if ends_early {
        let warning = crate::cad_load::ends_early_warning(path);
        log::warn!("{warning}");
        scene.warnings.push(warning);
    }
    // IFC is Z up by its schema (IfcGeometricRepresentationContext's world coordinate system).
    scene.up = Some(crate::UpAxis::Z);
    stages.mark("scene");
    log::info!(
        "{}",
        crate::cad::loaded_summary(path, &scene, "IfcOpenShell", read_s)
    );
    Ok(scene)
}

/// The warning for a file whose project declares no length unit, its coordinates taken in `unit_m` metres.
fn no_unit_warning(path: &Path, unit_m: f64) -> String {
    let unit = if unit_m == 1.0 {
        "metres".to_string()
    } else {
        format!("units of {unit_m} m")
    };
    format!(
        "{}: the IFC file declares no length unit (no LENGTHUNIT in its IfcProject's IfcUnitAssignment); its \
         coordinates are taken as {unit}, so its size may be wrong",
        path.display()
    )
}

/// The entity count of an IFC file in the STEP physical format, or why it is not one IfcOpenShell reads.
fn check_header(bytes: &[u8]) -> Result<u64, String> {
    if bytes.starts_with(b"PK\x03\x04") {
        return Err("an ifcZIP archive: unzip it and open the .ifc inside".into());
    }
    if bytes.trim_ascii_start().starts_with(b"<") {
        return Err("ifcXML is not read: export the model as .ifc (STEP physical file)".into());
    }
    let head = &bytes[..bytes.len().min(64 << 10)];
    let schema = schema(head);
    let entities = step_entities(bytes).map_err(|e| format!("not an IFC file: {e}"))?;
    match schema {
        None => Err("no FILE_SCHEMA in the header: not an IFC file".into()),
        Some(s) if !SCHEMAS.iter().any(|k| s.to_ascii_uppercase().starts_with(k)) => Err(format!(
            "schema {s}, not IFC: IfcOpenShell reads {}",
            SCHEMAS.join(", ")
        )),
        Some(_) => Ok(entities),
    }
}

/// The length of the file's whole statements: up to the last `;` outside a string (`'…'`, where `''` is a quote)
/// and outside a comment (`/* … */`).
fn complete_statements(bytes: &[u8]) -> usize {
    let (mut in_string, mut in_comment, mut end) = (false, false, 0);
    let mut k = 0;
    while k < bytes.len() {
        let b = bytes[k];
        if in_comment {
            if b == b'*' && bytes.get(k + 1) == Some(&b'/') {
                in_comment = false;
                k += 1;
            }
        } else if b == b'\'' {
            in_string = !in_string;
        } else if !in_string {
            if b == b'/' && bytes.get(k + 1) == Some(&b'*') {
                in_comment = true;
                k += 1;
            } else if b == b';' {
                end = k + 1;
            }
        }
        k += 1;
    }
    end
}

/// The first name inside `FILE_SCHEMA(('…'))`.
fn schema(head: &[u8]) -> Option<String> {
    let at = head
        .windows(11)
        .position(|w| w.eq_ignore_ascii_case(b"FILE_SCHEMA"))?;
    let rest = &head[at + 11..];
    let open = rest.iter().position(|&b| b == b'\'')?;
    let len = rest[open + 1..].iter().take(256).position(|&b| b == b'\'')?;
    Some(String::from_utf8_lossy(&rest[open + 1..open + 1 + len]).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str =
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('a','',(''),(''),'','','');\n";

    #[test]
    fn header_checks() {
        let ok = format!("{HEAD}FILE_SCHEMA(('IFC4'));\nENDSEC;\nDATA;\n#1=IFCPROJECT('x',$,$,$,$,$,$,$,$);\n#2=A();\nENDSEC;\nEND-ISO-10303-21;\n");
        assert_eq!(check_header(ok.as_bytes()).unwrap(), 4);
        let step = ok.replace("IFC4", "AP214_AUTOMOTIVE_DESIGN");
        assert!(check_header(step.as_bytes())
            .unwrap_err()
            .contains("schema AP214"));
        let none = ok.replace("FILE_SCHEMA(('IFC4'));\n", "");
        assert!(check_header(none.as_bytes())
            .unwrap_err()
            .contains("no FILE_SCHEMA"));
        assert!(check_header(b"garbage").unwrap_err().contains("not an IFC file"));
        assert!(check_header(b"PK\x03\x04zip").unwrap_err().contains("ifcZIP"));
        assert!(check_header(b"<?xml version='1.0'?>")
            .unwrap_err()
            .contains("ifcXML"));
        let header_only = format!("{HEAD}FILE_SCHEMA(('IFC2X3'));\nENDSEC;\nEND-ISO-10303-21;\n");
        assert!(check_header(header_only.as_bytes())
            .unwrap_err()
            .contains("no DATA"));
    }

    #[test]
    fn whole_statements_end_outside_strings_and_comments() {
        let head = "ISO-10303-21;\nDATA;\n#1=A('x;y','it''s;');\n/* a; */";
        assert_eq!(complete_statements(head.as_bytes()), head.find("/*").unwrap() - 1);
        let cut = format!("{head}\n#2=B('open;");
        assert_eq!(complete_statements(cut.as_bytes()), head.find("/*").unwrap() - 1);
        assert_eq!(complete_statements(b"no statement"), 0);
    }

    #[test]
    fn install_command_names_the_pinned_version() {
        let c = install_command();
        assert!(
            c.contains("scripts/install-deps.sh") && c.contains("ifcopenshell==0.8.4.post1"),
            "{c}"
        );
    }
}
