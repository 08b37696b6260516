//! Walk mode in the real viewer (Xvfb + lavapipe): a scripted walk (`--walk-path`) through a two-storey IFC
//! building that the test makes with IfcOpenShell's API (tests/ifc/make_two_storey.py: millimetres, Z up, a wall
//! with a door, a stair of 17 steps onto the first floor). The walk's gravity and collision rays are traced on the
//! device by the renderer's ray backend; `--stats` records the eye and the floor of every frame. The eye stays
//! 1.7 m above the true floor on the flat, the wall stops the body at its radius, the door lets it through, and the
//! stair takes it to the first floor. Skips, saying why, only when the IfcOpenShell venv is absent.
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::*;

fn python() -> Option<PathBuf> {
    let p = hrtao_scene::ifc_python();
    if p.is_file() {
        Some(p)
    } else {
        println!(
            "skipped: no IfcOpenShell interpreter at {} (install: {})",
            p.display(),
            hrtao_scene::ifc_install_command()
        );
        None
    }
}

/// Runs `hrtao view ARGS --no-config --exit` (`env` added) and returns its log.
fn run_viewer(args: &[&str], env: &[(&str, &str)]) -> String {
    let _display = display_lock();
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .arg("view")
        .args(args)
        .args(["--no-config", "--exit"])
        .env("HRTAO_VALIDATION", "1")
        .env("HRTAO_FRAMES_IN_FLIGHT", FRAMES_IN_FLIGHT)
        .env("RUST_LOG", "info")
        .envs(env.iter().copied())
        .output()
        .expect("run hrtao view");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "hrtao view failed ({}):\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("[vulkan"), "validation messages:\n{stderr}");
    stderr
}

fn building(dir: &Path) -> Option<PathBuf> {
    let python = python()?;
    let path = dir.join("two_storey.ifc");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ifc/make_two_storey.py");
    let out = Command::new(python).arg(script).arg(&path).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    Some(path)
}

/// Per frame of `--stats`: the eye (metres) and the walk's record.
struct Frame {
    eye: [f64; 3],
    floor: Option<f64>,
    blocked: bool,
    moving: bool,
    wall_ms: f64,
}

fn frames(stats: &Path) -> Vec<Frame> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(stats).unwrap()).unwrap();
    json["frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f.get("eye").is_some())
        .map(|f| {
            let e = &f["eye"];
            Frame {
                eye: [0, 1, 2].map(|i| e[i].as_f64().unwrap() / 1000.0),
                floor: f["walk"]["floor"].as_f64().map(|v| v / 1000.0),
                blocked: f["walk"]["blocked"].as_bool().unwrap(),
                moving: f["moving"].as_bool().unwrap(),
                wall_ms: f["wall_ms"].as_f64().unwrap(),
            }
        })
        .collect()
}

#[test]
fn a_scripted_walk_keeps_the_eye_height_stops_at_walls_passes_doors_and_climbs_stairs() {
    if !display_available() {
        return;
    }
    let dir = out_dir("walk");
    let Some(ifc) = building(&dir) else { return };
    // Millimetres, plan coordinates: into the wall at y = 1.5 m (given up after 2 s blocked), then through the
    // door (y 3..4 m), to the foot of the stair and up it onto the first floor.
    let path = dir.join("walk.json");
    std::fs::write(
        &path,
        r#"{"start": [2000, 1500, 1200],
            "waypoints": [[6000, 1500], [2000, 3500], [5500, 3500], [6000, 7300], [12500, 7300]]}"#,
    )
    .unwrap();
    let stats = dir.join("walk-stats.json");
    let log = run_viewer(
        &[
            "--size",
            "480x300",
            "--no-panel",
            ifc.to_str().unwrap(),
            "--walk-path",
            path.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ],
        &[],
    );
    assert!(
        log.contains("scripted walk done: 4 waypoints reached, 1 given up"),
        "{log}"
    );
    let f = frames(&stats);
    assert!(f.len() > 20, "{} walking frames", f.len());
    // Dropped from 1.2 m onto the ground floor, then on the flat: the eye 1.7 m above the true floor.
    let on_ground = |f: &Frame| f.eye[0] < 6.3 && f.floor.is_some_and(|fl| fl.abs() < 0.01);
    // Falling from the start until the eye first comes to 1.7 m; then on the ground floor's flat.
    let landed = f
        .iter()
        .position(|f| on_ground(f) && (f.eye[2] - 1.7).abs() < 0.01)
        .expect("landed");
    let ground: Vec<&Frame> = f[landed..].iter().filter(|f| on_ground(f)).collect();
    assert!(ground.len() > 10);
    assert!(
        f[..landed].iter().all(|f| f.eye[2] >= 1.7 - 1e-3),
        "fell below the eye height"
    );
    for g in &ground {
        assert!(
            (g.eye[2] - 1.7).abs() <= 0.05,
            "eye at {:?} over the ground floor",
            g.eye
        );
    }
    // The wall at x = 4 m stops the body 0.25 m before it (outside the door).
    let before_door = f.iter().take_while(|f| f.eye[0] <= 4.2).collect::<Vec<_>>();
    let nearest = before_door
        .iter()
        .filter(|f| f.eye[1] < 2.9)
        .map(|f| f.eye[0])
        .fold(f64::MIN, f64::max);
    assert!(
        nearest <= 3.75 + 0.002 && nearest > 3.6,
        "the wall: nearest x {nearest}"
    );
    assert!(f.iter().any(|f| f.blocked), "blocked at the wall");
    // Through the door: past the wall with y within the door.
    let through = f.iter().find(|f| f.eye[0] > 4.5).expect("past the wall");
    assert!(
        (3.0..=4.0).contains(&through.eye[1]),
        "through the door at {:?}",
        through.eye
    );
    // Up the stair: the last frames stand on the first floor (3 m), the eye 1.7 m above it.
    let last = f.last().unwrap();
    assert!(last.eye[0] > 12.0, "{:?}", last.eye);
    assert!((last.eye[2] - 4.7).abs() <= 0.05, "upstairs eye {:?}", last.eye);
    assert!(last.floor.is_some_and(|fl| (fl - 3.0).abs() < 0.01));
    let moving: Vec<f64> = f.iter().filter(|f| f.moving).map(|f| f.wall_ms).collect();
    println!(
        "{} walking frames ({} moving, median {:.1} ms)",
        f.len(),
        moving.len(),
        median(moving)
    );
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
