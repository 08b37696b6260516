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

use common::ifc_python as python;

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

/// `hrtao render --plan STOREY` of `ifc`: the logged cut height (file units) and instances shown.
fn plan(ifc: &Path, storey: &str, out: &Path) -> (f64, usize, usize) {
    let o = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(["render", "--scene", ifc.to_str().unwrap(), "--plan", storey])
        .args([
            "--width", "160", "--height", "90", "--mode", "rtao", "--rays", "2", "--frames", "1",
        ])
        .args(["--out", out.to_str().unwrap()])
        .env("HRTAO_VALIDATION", "1")
        .env("RUST_LOG", "info")
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{log}");
    let line = log
        .lines()
        .find(|l| l.contains("plan view of storey"))
        .expect("the plan's line");
    let z: f64 = line
        .split("section at z = ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let counts = line.split("(file), ").nth(1).unwrap();
    let mut n = counts.split(' ').filter_map(|w| w.parse::<usize>().ok());
    (z, n.next().unwrap(), n.next().unwrap())
}

/// The instances of storey `name`'s subtree that are shown, in the scene as the library loads it.
fn storey_instances(s: &hrtao_scene::Scene, name: &str) -> usize {
    let st = s.storeys.iter().find(|st| st.name == name).expect("the storey");
    let ids = s.tree.subtree_instances(st.node);
    ids.iter().filter(|&&i| s.instances[i as usize].visible).count()
}

#[test]
fn a_storeys_plan_view_shows_its_elements_cut_above_its_elevation() {
    let dir = std::env::temp_dir().join(format!("hrtao-plan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let Some(ifc) = building(&dir) else { return };
    // The generated building (millimetres): the ground floor's slab, 5 walls and 17 steps; the first floor's slab.
    let (z, shown, total) = plan(&ifc, "Ground floor", &dir.join("ground.png"));
    assert_eq!((shown, total), (23, 24));
    assert!((z - 1200.0).abs() < 0.5, "cut at {z}");
    let (z, shown, _) = plan(&ifc, "First floor", &dir.join("first.png"));
    assert_eq!(shown, 1);
    assert!((z - 4200.0).abs() < 0.5, "cut at {z}");
    // AC14-FZK-Haus: its storeys' elevations (IfcOpenShell's) plus 1.2 m, and each storey's own elements.
    let fzk = fzk_haus();
    let py = Command::new(hrtao_scene::ifc_python())
        .arg("-c")
        .arg(
            "import sys, ifcopenshell\nfor s in ifcopenshell.open(sys.argv[1]).by_type('IfcBuildingStorey'):\n    \
             print(f'{s.Name}\\t{s.Elevation}')",
        )
        .arg(&fzk)
        .output()
        .unwrap();
    assert!(py.status.success(), "{}", String::from_utf8_lossy(&py.stderr));
    let storeys: Vec<(String, f64)> = String::from_utf8_lossy(&py.stdout)
        .lines()
        .map(|l| {
            let (n, e) = l.split_once('\t').unwrap();
            (n.to_string(), e.parse().unwrap())
        })
        .collect();
    assert_eq!(storeys.len(), 2, "{storeys:?}");
    let scene = hrtao_scene::load_with(
        fzk.to_str().unwrap(),
        &hrtao_scene::LoadOptions::default(),
        &mut |_| {},
    )
    .unwrap();
    let mut sum = 0;
    for (name, elevation) in &storeys {
        let (z, shown, total) = plan(&fzk, name, &dir.join("fzk.png"));
        println!(
            "AC14-FZK-Haus `{name}` (elevation {elevation} m): cut at {z:.3} m, {shown} of {total} shown"
        );
        assert!((z - (elevation + 1.2)).abs() < 1e-3, "{name}: cut at {z}");
        assert_eq!(shown, storey_instances(&scene, name), "{name}");
        assert!(shown > 10 && shown < total);
        sum += shown;
    }
    assert!(sum <= 110);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The `ui probe: walk eye = X Y Z` lines so far (file coordinates).
fn eyes(v: &Running) -> Vec<[f64; 3]> {
    v.log_text()
        .lines()
        .filter_map(|l| l.split("ui probe: walk eye = ").nth(1))
        .map(|t| {
            let p: Vec<f64> = t.split_whitespace().map(|w| w.parse().unwrap()).collect();
            [p[0], p[1], p[2]]
        })
        .collect()
}

/// Real X input (xdotool) under Xvfb: the Scene section's Plan button of the ground floor shows its plan (the cut
/// logged), Esc restores the view; a double-click on the first floor's slab stands there (walk mode), W held walks
/// at eye height over it, Esc leaves; G enters walk mode again and Esc leaves it.
#[test]
fn walking_and_the_plan_view_follow_real_input() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("building-window");
    let Some(ifc) = building(&dir) else { return };
    let mut v = Running::start_with(
        &["--size", "1000x700", ifc.to_str().unwrap()],
        &dir,
        &[("HRTAO_UI_PROBE", Some("1"))],
    );
    v.wait_for("] opened ", 1, std::time::Duration::from_secs(120));
    let window = v.focus_window();
    std::thread::sleep(std::time::Duration::from_secs(2));
    // The fitted view looks down on the first floor's slab at the view's centre (the view is left of the panel).
    v.probed("storey plan");
    // The panel starts about 50 pixels left of the Up list (its label); the view fills the window left of it.
    let up = v.probed("up axis");
    let log = v.log_text();
    let up_line = log
        .lines()
        .rev()
        .find(|l| l.contains("ui probe: up axis at "))
        .unwrap();
    let up_w: i32 = up_line
        .split_whitespace()
        .last()
        .unwrap()
        .split('x')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let centre = ((up.0 - up_w / 2 - 50) / 2, 350);
    // The ground floor's plan, and back (before the double-click: its selection scrolls the panel to the tree).
    // The button where the panel last laid it out, again at each try (a busy machine may lay it out late).
    let needle = "plan view of storey `Ground floor`: section at z = 1200";
    for _ in 0..4 {
        if v.seen(needle) > 0 {
            break;
        }
        let (x, y) = v.probed("storey plan");
        xdotool(&[
            "mousemove",
            "--window",
            &window,
            "--sync",
            &x.to_string(),
            &y.to_string(),
        ]);
        std::thread::sleep(std::time::Duration::from_millis(300));
        xdotool(&["click", "1"]);
        let t0 = std::time::Instant::now();
        while v.seen(needle) == 0 && t0.elapsed() < std::time::Duration::from_secs(15) {
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
    }
    assert!(
        v.seen(needle) > 0,
        "no plan view after 4 clicks:\n{}",
        v.log_text()
    );
    xdotool(&["key", "--window", &window, "Escape"]);
    v.wait_for("plan view left", 1, std::time::Duration::from_secs(20));
    std::thread::sleep(std::time::Duration::from_secs(1));
    xdotool(&[
        "mousemove",
        "--window",
        &window,
        "--sync",
        &centre.0.to_string(),
        &centre.1.to_string(),
    ]);
    xdotool(&["click", "--repeat", "2", "--delay", "80", "1"]);
    v.wait_for("walk mode on at", 1, std::time::Duration::from_secs(30));
    v.wait_for("ui probe: walk eye = ", 1, std::time::Duration::from_secs(30));
    std::thread::sleep(std::time::Duration::from_secs(2));
    let before = *eyes(&v).last().unwrap();
    xdotool(&["keydown", "--window", &window, "w"]);
    std::thread::sleep(std::time::Duration::from_millis(1500));
    xdotool(&["keyup", "--window", &window, "w"]);
    std::thread::sleep(std::time::Duration::from_secs(2));
    let after = *eyes(&v).last().unwrap();
    let moved = ((after[0] - before[0]).powi(2) + (after[1] - before[1]).powi(2)).sqrt();
    println!("walked from {before:?} to {after:?}: {moved:.0} mm");
    // On the first floor (3 m) at eye height, at walking speed (1.5 s at 1.4 m/s, less the frames' clamps).
    assert!(
        (before[2] - 4700.0).abs() < 50.0 && (after[2] - 4700.0).abs() < 50.0,
        "{before:?} {after:?}"
    );
    assert!(moved > 500.0 && moved < 2500.0, "walked {moved} mm");
    xdotool(&["key", "--window", &window, "Escape"]);
    v.wait_for("walk mode off", 1, std::time::Duration::from_secs(20));
    xdotool(&["key", "--window", &window, "g"]);
    v.wait_for("walk mode on at", 2, std::time::Duration::from_secs(20));
    xdotool(&["key", "--window", &window, "Escape"]);
    v.wait_for("walk mode off", 2, std::time::Duration::from_secs(20));
    v.validation_clean();
}
