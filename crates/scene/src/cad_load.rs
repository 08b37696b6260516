//! STEP and IGES loading: the file is checked here (guard, format, entity count), then read and tessellated by
//! OpenCASCADE in a worker process of hrtao's own binary (`hrtao occt-worker`, the viewer crate's
//! `occt_worker.rs`), which streams progress and hands back unique parts and the product structure
//! ([`crate::cad`]). A crash, endless loop or runaway allocation inside the kernel ends the worker, not the
//! viewer: the worker runs with an address-space and a CPU-time limit, a higher OOM score than the viewer, and is
//! killed on Cancel or when the viewer dies.
//!
//! The scene keeps the file's own length unit: OCCT hands back millimetres, which are scaled to the unit the file
//! declares (inches stay inches), and [`Scene::unit_m`] says what that unit is.
//!
//! Colours: a colour set on a part's faces wins; else a colour set on the occurrence (or the nearest enclosing
//! assembly occurrence); else the part's own colour; else [`DEFAULT_BASE_COLOR`]. An occurrence with its own
//! colour gets its own copy of the part's mesh, recoloured, shared by the occurrences of that colour.

use std::collections::HashMap;
use std::io::BufReader;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use glam::{DMat4, DVec3, Vec3};

use crate::aabb::Aabb;
use crate::cad::{read_frame, CadModel, Frame, CAD_ENTITY_BYTES, MAX_CAD_ENTITIES};
use crate::error::SceneError;
use crate::guard::{read_model, CadFormat, CadOptions, LoadOptions};
use crate::scene::{
    recentre_origin, relative_transform, Instance, LoadProgress, Mesh, Primitive, Scene, DEFAULT_BASE_COLOR,
};
use crate::tree::NodeTree;

/// Address space the worker may use beyond the scene memory limit (OCCT's libraries and heap arenas).
const WORKER_OVERHEAD: u64 = 1 << 30;

pub fn load_cad(
    path: &Path,
    format: CadFormat,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    let started = Instant::now();
    let err = |message: String| SceneError::Cad {
        format: format.name(),
        path: path.to_path_buf(),
        message,
    };
    let (bytes, mut budget) = read_model(path, opts, progress)?;
    let entities = match format {
        CadFormat::Step => step_entities(&bytes).map_err(err)?,
        CadFormat::Iges => iges_entities(&bytes).map_err(err)?,
    };
    let cap = MAX_CAD_ENTITIES.min(opts.max_memory / CAD_ENTITY_BYTES);
    if entities > cap {
        return Err(SceneError::TooLarge(format!(
            "{}: {entities} entities, over the cap of {cap} (at most {MAX_CAD_ENTITIES}, and {} bytes of \
             kernel memory each within the scene memory limit, HRTAO_MAX_SCENE_MB)",
            path.display(),
            CAD_ENTITY_BYTES
        )));
    }
    budget.reserve(entities * CAD_ENTITY_BYTES, "the kernel's entities")?;
    let metadata = match format {
        CadFormat::Step => crate::cad_header::step_header(&bytes),
        CadFormat::Iges => crate::cad_header::iges_header(&bytes),
    };
    let ends_early = format == CadFormat::Step && ends_early(&bytes);
    drop(bytes);
    opts.check_cancel(path)?;
    let mut stages = StageClock::new();
    let model = run_worker(path, format, opts, &mut stages, progress).map_err(|e| match e {
        WorkerError::Cancelled => SceneError::Cancelled(path.display().to_string()),
        WorkerError::Failed(m) => err(m),
    })?;
    let read_s = started.elapsed().as_secs_f64();
    let mut scene = to_scene(path, model).map_err(err)?;
    scene.metadata = metadata;
    if ends_early {
        let warning = ends_early_warning(path);
        log::warn!("{warning}");
        scene.warnings.push(warning);
    }
    stages.mark("scene");
    log::info!(
        "{}",
        crate::cad::loaded_summary(path, &scene, "OpenCASCADE", read_s)
    );
    log::info!("{}: {}", path.display(), stages.summary());
    Ok(scene)
}

/// Entities in a STEP file's DATA sections (an upper bound: statements ending in `;`), or why it is no STEP file.
pub(crate) fn step_entities(bytes: &[u8]) -> Result<u64, String> {
    let start = bytes.trim_ascii_start();
    if !start.starts_with(b"ISO-10303-21") {
        return Err(
            "not a STEP file: it does not start with ISO-10303-21 (the STEP physical file header)".into(),
        );
    }
    let Some(data) = find(bytes, b"DATA;").or_else(|| find(bytes, b"DATA(")) else {
        return Err("no DATA section: the file has a header but no entities".into());
    };
    let data = data + 5;
    let n = bytes[data..].iter().filter(|&&b| b == b';').count() as u64;
    if n <= 2 || find(&bytes[data..], b"#").is_none() {
        return Err("the DATA section holds no entity".into());
    }
    Ok(n)
}

/// Whether a STEP physical file (STEP, IFC) lacks its closing `END-ISO-10303-21;` (looked for in its last
/// KiB): it was cut short, and what the kernel reads of it may be incomplete.
pub(crate) fn ends_early(bytes: &[u8]) -> bool {
    let tail = &bytes[bytes.len().saturating_sub(1024)..];
    find(tail, b"END-ISO-10303-21;").is_none()
}

/// The warning for a file that [`ends_early`], as the viewer's toast and the log show it.
pub(crate) fn ends_early_warning(path: &Path) -> String {
    format!(
        "{}: the file ends early: the model may be incomplete (it does not end with END-ISO-10303-21;)",
        path.display()
    )
}

/// Entities of an IGES file (two directory-entry lines each), or why it is no IGES file.
fn iges_entities(bytes: &[u8]) -> Result<u64, String> {
    let mut sections = [0u64; 5];
    for line in bytes.split(|&b| b == b'\n') {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.len() < 73 {
            continue;
        }
        if let Some(k) = b"SGDPT".iter().position(|&c| c == line[72]) {
            sections[k] += 1;
        }
    }
    if sections[1] == 0 || sections[2] == 0 {
        return Err("not an IGES file: no global (G) and directory (D) sections in 80-column lines".into());
    }
    Ok(sections[2] / 2)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// When each stage of a load began: the worker's start, its `read`, `transfer` and `tessellate` stages (each
/// announced by the worker's first progress frame of the stage), the model's arrival and the scene built.
pub(crate) struct StageClock {
    start: Instant,
    marks: Vec<(&'static str, Instant)>,
}

impl StageClock {
    pub(crate) fn new() -> StageClock {
        StageClock {
            start: Instant::now(),
            marks: Vec::new(),
        }
    }

    /// Marks the start of `stage` (only its first mark counts).
    pub(crate) fn mark(&mut self, stage: &'static str) {
        if !self.marks.iter().any(|(s, _)| *s == stage) {
            self.marks.push((stage, Instant::now()));
        }
    }

    /// "worker start 40 ms, STEP read 60 ms, …": each span from its mark to the next.
    pub(crate) fn summary(&self) -> String {
        let name = |s: &'static str| match s {
            "spawn" => "checks before the worker",
            "read" => "worker start-up",
            "transfer" => "file read and parsed",
            "tessellate" => "XCAF transfer",
            "model" => "tessellation and hand-over",
            "scene" => "scene built",
            other => other,
        };
        let mut out = Vec::new();
        let mut prev = self.start;
        for (stage, at) in &self.marks {
            out.push(format!(
                "{} {:.0} ms",
                name(stage),
                at.duration_since(prev).as_secs_f64() * 1e3
            ));
            prev = *at;
        }
        out.join(", ")
    }
}

pub(crate) enum WorkerError {
    Cancelled,
    Failed(String),
}

/// Runs `WORKER occt-worker FORMAT RELATIVE ABSOLUTE ANGULAR_DEG PATH` and reads its frames until the model.
fn run_worker(
    path: &Path,
    format: CadFormat,
    opts: &LoadOptions,
    stages: &mut StageClock,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<CadModel, WorkerError> {
    stages.mark("spawn");
    let cad: &CadOptions = &opts.cad;
    let Some(worker) = cad.worker.clone() else {
        return Err(WorkerError::Failed(
            "no OpenCASCADE worker to run: the loader needs the path of the hrtao binary (LoadOptions::cad.worker)"
                .into(),
        ));
    };
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut cmd = Command::new(&worker);
    cmd.arg("occt-worker")
        .arg(format.name().to_ascii_lowercase())
        .arg(cad.tessellation.relative.to_string())
        .arg(cad.tessellation.absolute.to_string())
        .arg(cad.tessellation.angular_deg.to_string())
        .arg(&abs);
    let limits = WorkerLimits {
        kernel: "OpenCASCADE",
        address_space: opts.max_memory.saturating_add(WORKER_OVERHEAD),
        cpu_seconds: cad.cpu_seconds,
    };
    run_worker_command(cmd, &worker, &limits, opts, stages, progress)
}

/// What a worker process may take, and the kernel it runs (named in errors).
pub(crate) struct WorkerLimits {
    pub kernel: &'static str,
    pub address_space: u64,
    pub cpu_seconds: u64,
}

/// Starts `cmd` (a worker writing [`crate::cad`] frames to its stdout) under `limits` and reads its frames until
/// the model; a crash, a kill or a limit reached is an error naming the kernel.
pub(crate) fn run_worker_command(
    mut cmd: Command,
    program: &Path,
    limits: &WorkerLimits,
    opts: &LoadOptions,
    stages: &mut StageClock,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<CadModel, WorkerError> {
    let kernel = limits.kernel;
    let address_space = limits.address_space;
    let cpu_seconds = limits.cpu_seconds;
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit());
    // SAFETY: only async-signal-safe system calls between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            let limit = |res, soft: u64, hard: u64| {
                let r = libc::rlimit {
                    rlim_cur: soft as libc::rlim_t,
                    rlim_max: hard as libc::rlim_t,
                };
                libc::setrlimit(res, &r)
            };
            limit(libc::RLIMIT_AS, address_space, address_space);
            limit(libc::RLIMIT_CPU, cpu_seconds, cpu_seconds + 5);
            // The worker dies with the process that started it.
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
            Ok(())
        });
    }
    let mut child = cmd.spawn().map_err(|e| {
        WorkerError::Failed(format!(
            "cannot start the {kernel} worker {}: {e}",
            program.display()
        ))
    })?;
    let stdout = child.stdout.take().expect("piped stdout");
    let (tx, rx) = mpsc::channel();
    let max_payload = opts.max_memory;
    let reader = std::thread::spawn(move || {
        let mut r = BufReader::new(stdout);
        let mut reserve = |n: u64| {
            if n > max_payload {
                Err(format!(
                    "the tessellation takes {:.1} MiB, over the scene memory limit of {:.1} MiB \
                     (HRTAO_MAX_SCENE_MB; a coarser tessellation takes less)",
                    n as f64 / (1 << 20) as f64,
                    max_payload as f64 / (1 << 20) as f64
                ))
            } else {
                Ok(())
            }
        };
        loop {
            let f = read_frame(&mut r, &mut reserve);
            let end = !matches!(f, Ok(Some(Frame::Progress { .. })));
            if tx.send(f).is_err() || end {
                break;
            }
        }
    });
    let finish = |child: &mut std::process::Child, kill: bool| {
        if kill {
            let _ = child.kill();
        }
        child.wait()
    };
    let result = loop {
        if opts.cancel.load(std::sync::atomic::Ordering::Relaxed) {
            let _ = finish(&mut child, true);
            break Err(WorkerError::Cancelled);
        }
        match rx.recv_timeout(Duration::from_millis(50)) {
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
            Ok(Ok(Some(Frame::Progress { stage, fraction }))) => {
                let stage = match stage.as_str() {
                    "read" => {
                        stages.mark("read");
                        "kernel"
                    }
                    "transfer" => "transfer",
                    "tessellate" => "tessellate",
                    _ => "kernel",
                };
                if stage != "kernel" {
                    stages.mark(stage);
                }
                progress(LoadProgress {
                    stage,
                    done: (fraction.clamp(0.0, 1.0) * 1000.0) as u64,
                    total: 1000,
                })
            }
            Ok(Ok(Some(Frame::Model(m)))) => {
                stages.mark("model");
                let _ = finish(&mut child, false);
                break Ok(m);
            }
            Ok(Ok(Some(Frame::Error(m)))) => {
                let _ = finish(&mut child, false);
                break Err(WorkerError::Failed(m));
            }
            Ok(Err(e)) => {
                let status = finish(&mut child, true);
                break Err(WorkerError::Failed(
                    died(status, kernel, cpu_seconds).unwrap_or(e),
                ));
            }
            Ok(Ok(None)) | Err(mpsc::RecvTimeoutError::Disconnected) => {
                let status = finish(&mut child, false);
                break Err(WorkerError::Failed(
                    died(status, kernel, cpu_seconds)
                        .unwrap_or_else(|| format!("the {kernel} worker ended without a model")),
                ));
            }
        }
    };
    let _ = reader.join();
    result
}

/// Why the worker ended, if it did not end normally.
fn died(status: std::io::Result<std::process::ExitStatus>, kernel: &str, cpu_seconds: u64) -> Option<String> {
    let status = status.ok()?;
    if let Some(sig) = status.signal() {
        let why = match sig {
            libc::SIGKILL => {
                "killed (SIGKILL: by the user, Cancel, or the system being out of memory)".to_string()
            }
            libc::SIGXCPU => format!("stopped at its CPU time limit of {cpu_seconds} s (SIGXCPU)"),
            libc::SIGSEGV => format!("crashed inside {kernel} (SIGSEGV)"),
            libc::SIGABRT => format!("aborted inside {kernel}, probably out of memory (SIGABRT)"),
            s => format!("ended by signal {s}"),
        };
        return Some(format!(
            "the {kernel} worker was {why} before handing back the model"
        ));
    }
    (!status.success()).then(|| format!("the {kernel} worker failed ({status})"))
}

/// Builds the scene: one mesh per part (and per recoloured occurrence), one instance per placed occurrence, the
/// tree from the product structure, coordinates in the file's unit and re-centred when far from the origin.
pub(crate) fn to_scene(path: &Path, model: CadModel) -> Result<Scene, String> {
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut scene = Scene::new(name.clone());
    let model_m = if model.model_unit_m > 0.0 && model.model_unit_m.is_finite() {
        model.model_unit_m
    } else {
        1e-3
    };
    let unit_m = model.file_unit_m.unwrap_or(model_m);
    let scale = model_m / unit_m;
    scene.unit_m = Some(unit_m);
    let part_mesh = |i: usize, p: &crate::cad::CadPart, color: Option<[f32; 4]>| Mesh {
        name: if p.name.is_empty() {
            format!("part {}", i + 1)
        } else {
            p.name.clone()
        },
        primitives: p
            .primitives
            .iter()
            .map(|q| {
                let positions = q
                    .positions
                    .iter()
                    .map(|v| (Vec3::from(*v) * scale as f32).to_array())
                    .collect();
                let base_color = match (q.face_color, color, q.color) {
                    (true, _, Some(c)) => c,
                    (_, Some(c), _) => c,
                    (_, None, Some(c)) => c,
                    _ => DEFAULT_BASE_COLOR,
                };
                // The unit scale is uniform: directions stay as the kernel gave them.
                Primitive::new(positions, q.indices.clone(), base_color).with_normals(q.normals.clone())
            })
            .collect(),
    };
    for (i, p) in model.parts.iter().enumerate() {
        scene.meshes.push(part_mesh(i, p, None));
    }
    let bounds: Vec<Aabb> = scene.meshes.iter().map(Mesh::local_bounds).collect();
    // World placements in f64, in the file's unit.
    let worlds: Vec<DMat4> = model
        .nodes
        .iter()
        .map(|n| {
            let mut m = DMat4::from_cols_array(&n.world);
            m.w_axis = (m.w_axis.truncate() * scale).extend(1.0);
            m
        })
        .collect();
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for (n, w) in model.nodes.iter().zip(&worlds) {
        if let Some(b) = n
            .part
            .and_then(|p| bounds.get(p as usize))
            .filter(|b| !b.is_empty())
        {
            let c = w.transform_point3(((b.min + b.max) * 0.5).as_dvec3());
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    let origin = recentre_origin((lo + hi) * 0.5);
    scene.origin = origin.to_array();
    let mut recoloured: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    let mut tree = NodeTree::default();
    for (id, (n, w)) in model.nodes.iter().zip(&worlds).enumerate() {
        if n.parent.is_some_and(|p| p as usize >= id) {
            return Err(format!("node {id} comes before its parent"));
        }
        let label = if n.name.is_empty() {
            format!("node {}", id + 1)
        } else {
            n.name.clone()
        };
        let node = tree.add(label.clone(), n.parent);
        let Some(part) = n.part else {
            // An IFC storey's node carries its placement's height (ifc_worker.py).
            if let Some(name) = label
                .strip_suffix(" (IfcBuildingStorey)")
                .or((label == "IfcBuildingStorey").then_some(""))
            {
                scene.storeys.push(crate::Storey {
                    name: if name.is_empty() {
                        label.clone()
                    } else {
                        name.to_string()
                    },
                    node,
                    elevation: (w.w_axis.z - origin.z) as f32,
                });
            }
            continue;
        };
        let Some(p) = model.parts.get(part as usize) else {
            return Err(format!("node {id} places unknown part {part}"));
        };
        let mesh = match n.color {
            Some(c) if p.primitives.iter().any(|q| !q.face_color) => {
                let key = (part, c.map(f32::to_bits));
                *recoloured.entry(key).or_insert_with(|| {
                    scene.meshes.push(part_mesh(part as usize, p, Some(c)));
                    scene.meshes.len() as u32 - 1
                })
            }
            _ => part,
        };
        tree.nodes[node as usize]
            .instances
            .push(scene.instances.len() as u32);
        scene.instances.push(Instance {
            mesh,
            transform: relative_transform(w, origin),
            name: label,
            visible: n.visible,
        });
    }
    scene.tree = tree;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_entity_scan() {
        assert!(step_entities(b"garbage").unwrap_err().contains("ISO-10303-21"));
        let header = b"ISO-10303-21;\nHEADER;\nFILE_NAME('x');\nENDSEC;\nEND-ISO-10303-21;\n";
        assert!(step_entities(header).unwrap_err().contains("no DATA"));
        let ok = b"ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A();\n#2=B(#1);\n#3=C();\nENDSEC;\nEND-ISO-10303-21;\n";
        assert_eq!(step_entities(ok).unwrap(), 5);
        assert!(!ends_early(ok));
        assert!(!ends_early(b"END-ISO-10303-21;\r\n\n"));
        assert!(ends_early(&ok[..ok.len() - 20]));
        assert!(ends_early(b""));
    }

    /// A closed cylinder (radius 10, height 20 mm, axis z) as the kernel hands it back: the side with radial
    /// normals, the caps with axial ones, every triangle wound toward its normals' side (out of the solid).
    fn cylinder_part(segments: u32) -> crate::cad::CadPart {
        use crate::cad::CadPrimitive;
        let ring = |z: f32| -> Vec<[f32; 3]> {
            (0..segments)
                .map(|k| {
                    let a = std::f32::consts::TAU * k as f32 / segments as f32;
                    [10.0 * a.cos(), 10.0 * a.sin(), z]
                })
                .collect()
        };
        let mut side = CadPrimitive::default();
        for z in [0.0, 20.0] {
            for p in ring(z) {
                side.positions.push(p);
                side.normals
                    .push(Vec3::new(p[0], p[1], 0.0).normalize().to_array());
            }
        }
        for k in 0..segments {
            let (a, b) = (k, (k + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            side.indices.extend([a, b, d, a, d, c]);
        }
        let cap = |z: f32, up: bool| {
            let indices = (1..segments - 1).flat_map(|k| if up { [0, k, k + 1] } else { [0, k + 1, k] });
            CadPrimitive::new(ring(z), indices.collect()).with_normals(vec![
                [
                    0.0,
                    0.0,
                    if up { 1.0 } else { -1.0 }
                ];
                segments as usize
            ])
        };
        crate::cad::CadPart {
            name: "cylinder".into(),
            primitives: vec![side, cap(0.0, false), cap(20.0, true)],
        }
    }

    /// The kernel's normals reach the scene unscaled (an inch file scales positions by 1/25.4) and unit length, and
    /// a part placed mirrored still shades outward: with the instance transform applied as the renderer does it
    /// (the cofactor matrix, the normal turned to the side of the face normal that faces the camera), every
    /// vertex normal seen from outside points out of the solid, radial on the side and axial on the caps.
    #[test]
    fn normals_survive_units_and_mirrored_placement() {
        use crate::cad::{CadModel, CadNode};
        let node = |name: &str, world: DMat4| CadNode {
            name: name.into(),
            parent: None,
            part: Some(0),
            world: world.to_cols_array(),
            color: None,
            visible: true,
        };
        let mirrored = DMat4::from_translation(DVec3::new(60.0, 0.0, 0.0))
            * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0))
            * DMat4::from_rotation_x(0.7);
        let model = CadModel {
            parts: vec![cylinder_part(24)],
            nodes: vec![node("plain", DMat4::IDENTITY), node("mirrored", mirrored)],
            model_unit_m: 1e-3,
            file_unit_m: Some(0.0254),
        };
        let scene = to_scene(Path::new("cyl.step"), model.clone()).unwrap();
        let mesh = &scene.meshes[0];
        for (q, k) in mesh.primitives.iter().zip(&model.parts[0].primitives) {
            assert_eq!(q.normals, k.normals, "normals unscaled");
            assert!(
                (q.positions[0][0] - k.positions[0][0] / 25.4).abs() < 1e-5,
                "positions in inches"
            );
        }
        assert_eq!(scene.instances.len(), 2);
        for inst in &scene.instances {
            let m = inst.transform;
            let (c0, c1, c2) = (m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate());
            let cof = glam::Mat3::from_cols(c1.cross(c2), c2.cross(c0), c0.cross(c1));
            let axis = m.transform_vector3(Vec3::Z).normalize();
            let base = m.transform_point3(Vec3::ZERO);
            let mut checked = 0;
            for (pi, q) in mesh.primitives.iter().enumerate() {
                for t in q.indices.chunks(3) {
                    let w: Vec<Vec3> = t
                        .iter()
                        .map(|&i| m.transform_point3(Vec3::from(q.positions[i as usize])))
                        .collect();
                    let mut face = (w[1] - w[0]).cross(w[2] - w[0]).normalize();
                    // A camera outside the solid, on the triangle's outer side (the centroid pushed away from
                    // the axis or past the cap).
                    let centre = (w[0] + w[1] + w[2]) / 3.0;
                    let from_axis = centre - base - axis * (centre - base).dot(axis);
                    let outward = match pi {
                        0 => from_axis.normalize(),
                        1 => -axis,
                        _ => axis,
                    };
                    let eye = centre + outward * 100.0;
                    if face.dot(eye - centre) < 0.0 {
                        face = -face;
                    }
                    for (&i, p) in t.iter().zip(&w) {
                        let s = (cof * Vec3::from(q.normals[i as usize])).normalize();
                        let s = if s.dot(face) < 0.0 { -s } else { s };
                        let want = match pi {
                            0 => (*p - base - axis * (*p - base).dot(axis)).normalize(),
                            1 => -axis,
                            _ => axis,
                        };
                        assert!(
                            s.dot(want) > 0.999,
                            "{}: primitive {pi}, vertex {i}: {s} instead of {want}",
                            inst.name
                        );
                        // Not merely turned to the camera: the raw cofactor normal agrees with the winding.
                        let raw = cof * Vec3::from(q.normals[i as usize]);
                        let wound = (w[1] - w[0]).cross(w[2] - w[0]);
                        assert!(raw.dot(wound) > 0.0, "{}: normal against the winding", inst.name);
                        checked += 1;
                    }
                }
            }
            assert!(checked > 100);
        }
    }

    #[test]
    fn iges_entity_scan() {
        let line = |c: char| format!("{:72}{c}{:>7}\n", "x", 1);
        let f = [line('S'), line('G'), line('D'), line('D'), line('P'), line('T')].concat();
        assert_eq!(iges_entities(f.as_bytes()).unwrap(), 1);
        assert!(iges_entities(b"hello").unwrap_err().contains("not an IGES"));
    }
}
