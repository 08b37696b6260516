//! IFC through the IfcOpenShell worker (a Python process run by the venv `scripts/install-ifc.sh` makes, which
//! `scripts/test.sh` runs through `scripts/install-deps.sh`): assimp's AC14-FZK-Haus.ifc with its spatial tree and
//! shared representations (counted with IfcOpenShell's own API), its AO against IfcOpenShell's own glTF export, a
//! building generated with IfcOpenShell's API, length units (a millimetre project beside an IfcProjectLibrary, a
//! file with no unit), the hostile IFC corpus, a missing interpreter, and a worker that is killed or runs out of
//! CPU time, in `render` and in the viewer's window. Each test skips, saying why, only when the venv is absent.
mod common;

use common::{fzk_haus as fzk, ifc_python as python};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use hrtao_scene::hostile::{write_ifc_corpus, Expect};
use hrtao_scene::{LoadOptions, Scene, SceneError};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-ifc-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn load(path: &Path) -> Result<Scene, SceneError> {
    hrtao_scene::load_with(path.to_str().unwrap(), &LoadOptions::default(), &mut |_| {})
}

/// Runs a Python snippet with the venv's interpreter; its stdout.
fn py(python: &Path, code: &str, args: &[&str]) -> String {
    let args: Vec<&std::ffi::OsStr> = ["-c", code]
        .into_iter()
        .chain(args.iter().copied())
        .map(|a| a.as_ref())
        .collect();
    common::run_python(python, &args)
}

/// Products whose body is an IfcMappedItem (a placed representation map), counted with IfcOpenShell's API.
const MAPPED: &str = "import sys, ifcopenshell\nf = ifcopenshell.open(sys.argv[1])\n\
print(sum(1 for p in f.by_type('IfcProduct') if p.Representation and not p.is_a('IfcOpeningElement') \
for r in p.Representation.Representations if r.RepresentationIdentifier == 'Body' \
for i in r.Items if i.is_a('IfcMappedItem')))";

/// Instances of meshes placed more than once.
fn shared_instances(s: &Scene) -> usize {
    hrtao_scene::cad::shared_meshes(s).iter().map(|(_, n)| n).sum()
}

fn children_named<'a>(s: &'a Scene, node: u32, class: &str) -> Vec<(u32, &'a str)> {
    s.tree.nodes[node as usize]
        .children
        .iter()
        .map(|&c| (c, s.tree.nodes[c as usize].name.as_str()))
        .filter(|(_, n)| n.ends_with(&format!("({class})")))
        .collect()
}

#[test]
fn fzk_haus_opens_with_its_storeys_and_shared_representations() {
    let Some(python) = python() else { return };
    let path = fzk();
    let t0 = Instant::now();
    let s = load(&path).unwrap();
    println!("AC14-FZK-Haus.ifc opened in {:.2?}", t0.elapsed());
    let storeys_py = py(
        &python,
        "import sys, ifcopenshell\nf = ifcopenshell.open(sys.argv[1])\n\
         print('|'.join(sorted(s.Name for s in f.by_type('IfcBuildingStorey'))))",
        &[path.to_str().unwrap()],
    );
    let site = s
        .tree
        .nodes
        .iter()
        .position(|n| n.name.ends_with("(IfcSite)"))
        .expect("a site node") as u32;
    let buildings = children_named(&s, site, "IfcBuilding");
    assert_eq!(buildings.len(), 1, "{buildings:?}");
    let mut storeys: Vec<String> = children_named(&s, buildings[0].0, "IfcBuildingStorey")
        .iter()
        .map(|(_, n)| n.trim_end_matches(" (IfcBuildingStorey)").to_string())
        .collect();
    storeys.sort();
    assert_eq!(storeys.len(), 2, "{storeys:?}");
    assert_eq!(storeys.join("|"), storeys_py);
    let mapped: usize = py(&python, MAPPED, &[path.to_str().unwrap()]).parse().unwrap();
    let shared = shared_instances(&s);
    println!(
        "{} meshes, {} instances; {shared} instances of shared meshes, {mapped} mapped products (IfcOpenShell)",
        s.meshes.len(),
        s.instances.len()
    );
    assert_eq!(shared, mapped);
    assert_eq!(s.unit_m, Some(1.0));
}

/// `hrtao render` of `scene`: per-pixel RTAO, 64 rays × 16 frames, 320×180 from `camera`; the linear AO image.
fn render_ao(scene: &Path, camera: &Path, radius: f32, dir: &Path) -> Vec<f32> {
    common::render_rtao(scene, camera, radius, (64, 16), dir)
}

/// IfcOpenShell's glTF serializer (Y up: IFC's (x, y, z) is its (x, z, −y)), the products the worker draws (no
/// openings, no spaces).
const GLTF_EXPORT: &str = "import sys, ifcopenshell, ifcopenshell.geom\nf = ifcopenshell.open(sys.argv[1])\n\
s = ifcopenshell.geom.settings()\ns.set('use-world-coords', False)\ns.set('weld-vertices', False)\n\
ss = ifcopenshell.geom.serializer_settings()\n\
w = ifcopenshell.geom.serializers.gltf(sys.argv[2], s, ss)\nw.setFile(f)\nw.writeHeader()\n\
it = ifcopenshell.geom.iterator(s, f, 1, exclude=('IfcOpeningElement', 'IfcSpace'))\nassert it.initialize()\n\
while True:\n    w.write(it.get())\n    if not it.next(): break\nw.finalize()";

#[test]
fn fzk_haus_ao_matches_ifcopenshells_gltf_export() {
    let Some(python) = python() else { return };
    let path = fzk();
    let dir = tmp("ao");
    let glb = dir.join("fzk.glb");
    py(
        &python,
        GLTF_EXPORT,
        &[path.to_str().unwrap(), glb.to_str().unwrap()],
    );
    let s = load(&path).unwrap();
    let exported = load(&glb).unwrap();
    let (b, g) = (s.bounds(), exported.bounds());
    println!("IFC bounds {b:?} (origin {:?}), glTF bounds {g:?}", s.origin);
    let y_up = |v: glam::Vec3| glam::Vec3::new(v.x, v.z, -v.y);
    let (g_min, g_max) = (y_up(b.min).min(y_up(b.max)), y_up(b.min).max(y_up(b.max)));
    assert!(
        (g_min - g.min).abs().max_element() < 0.01 && (g_max - g.max).abs().max_element() < 0.01,
        "the export is the IFC scene turned Y up"
    );
    let (centre, size) = ((b.min + b.max) / 2.0, (b.max - b.min).length());
    let eye = centre + glam::Vec3::new(0.7, -0.9, 0.45).normalize() * size * 0.9;
    let camera = |name: &str, eye: glam::Vec3, target: glam::Vec3, up: [i32; 3]| {
        let path = dir.join(name);
        let json = serde_json::json!({"eye": eye.to_array(), "target": target.to_array(), "up": up,
            "fov_y_deg": 45, "width": 320, "height": 180});
        std::fs::write(&path, json.to_string()).unwrap();
        path
    };
    let ifc_camera = camera("fzk.camera.json", eye, centre, [0, 0, 1]);
    let gltf_camera = camera("fzk-y-up.camera.json", y_up(eye), y_up(centre), [0, 1, 0]);
    let radius = size / 20.0;
    let ifc = render_ao(&path, &ifc_camera, radius, &dir);
    let reference = render_ao(&glb, &gltf_camera, radius, &dir);
    let occluded = reference.iter().filter(|&&v| v < 0.9).count();
    assert!(occluded > 1000, "the view shows occlusion ({occluded} pixels)");
    let e = hrtao_core::metrics::ao_error(&ifc, &reference);
    println!(
        "AC14-FZK-Haus.ifc against IfcOpenShell's glTF: MAE {:.4} over {} pixels",
        e.mae, e.pixels
    );
    assert!(e.mae <= 0.01, "MAE {}", e.mae);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_building_made_with_ifcopenshells_api_opens_with_its_instances() {
    let Some(python) = python() else { return };
    let dir = tmp("generated");
    let path = dir.join("generated.ifc");
    assert_eq!(common::make_building(&python, &path, 24), 24);
    let s = load(&path).unwrap();
    let shared = hrtao_scene::cad::shared_meshes(&s);
    assert_eq!(shared.len(), 1, "{shared:?}");
    assert_eq!(shared[0].1, 24, "{shared:?}");
    // Two walls (one cut by its opening), the slab and the columns, each an instance.
    let names: Vec<&str> = s.instances.iter().map(|i| i.name.as_str()).collect();
    for want in [
        "Wall 1 (IfcWall)",
        "Wall 2 (IfcWall)",
        "Floor slab (IfcSlab)",
        "Column 24 (IfcColumn)",
    ] {
        assert!(names.contains(&want), "{want} in {names:?}");
    }
    assert!(
        !names.iter().any(|n| n.contains("IfcOpeningElement")),
        "{names:?}"
    );
    let storey = s
        .tree
        .nodes
        .iter()
        .position(|n| n.name == "Ground floor (IfcBuildingStorey)")
        .expect("the storey") as u32;
    assert_eq!(s.tree.subtree_instances(storey).len(), s.instances.len());
    let _ = std::fs::remove_dir_all(dir);
}

/// Writes `make_library_units.py`'s model in `mode` to `path`; the wall's true length in metres.
fn make_library_units(python: &Path, path: &Path, mode: &str) -> f32 {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ifc/make_library_units.py");
    let out = Command::new(python)
        .arg(script)
        .arg(path)
        .arg(mode)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).trim().parse().unwrap()
}

/// The extent of a scene's bounds in metres (what the Properties panel shows as dimensions).
fn extent_m(s: &Scene) -> glam::Vec3 {
    let b = s.bounds();
    (b.max - b.min) * s.unit_m.expect("a unit") as f32
}

/// A millimetre project with an IfcProjectLibrary beside it (IfcOpenShell's iterator then finds no unit and reads
/// the coordinates as metres) opens at its true size, in millimetres, without a warning, whichever of the project
/// and the library comes first in the file.
#[test]
fn a_millimetre_project_with_a_project_library_opens_at_its_true_size() {
    let Some(python) = python() else { return };
    let dir = tmp("library-units");
    for mode in ["library-after", "library-first"] {
        let path = dir.join(format!("{mode}.ifc"));
        let length = make_library_units(&python, &path, mode);
        let s = load(&path).unwrap();
        let e = extent_m(&s);
        println!("{mode}: unit {:?}, bounds {:?}, {e} m", s.unit_m, s.bounds());
        assert_eq!(s.unit_m, Some(0.001), "{mode}");
        assert!(
            (e - glam::Vec3::new(length, 0.2, 3.0)).abs().max_element() < 1e-3,
            "{mode}: the wall is {length} × 0.2 × 3 m, the scene {e} m"
        );
        assert!(s.warnings.is_empty(), "{mode}: {:?}", s.warnings);
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// A file that declares no length unit opens in metres with a warning in the scene (the viewer's toast) and in
/// `hrtao render`'s log, not silently.
#[test]
fn an_ifc_without_a_unit_opens_in_metres_with_a_warning() {
    let Some(python) = python() else { return };
    let dir = tmp("no-unit");
    let path = dir.join("no-unit.ifc");
    let length = make_library_units(&python, &path, "no-unit");
    let s = load(&path).unwrap();
    let e = extent_m(&s);
    assert_eq!(s.unit_m, Some(1.0));
    assert!(
        (e - glam::Vec3::new(length, 0.2, 3.0)).abs().max_element() < 1e-3,
        "{e}"
    );
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(w.contains("no length unit") && w.contains("metres"), "{w}");
    let (out, _) = render_small(&path, &[("RUST_LOG", "warn")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr
            .lines()
            .any(|l| l.contains("WARN") && l.contains("no length unit")),
        "render logs the warning:\n{stderr}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

fn render_small(scene: &Path, env: &[(&str, &str)]) -> (Output, Duration) {
    let png = scene.with_extension("png");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_hrtao"));
    cmd.args(["render", "--scene", scene.to_str().unwrap()])
        .args(["--width", "96", "--height", "64", "--rays", "2"])
        .args(["--out", png.to_str().unwrap()])
        .env("HRTAO_VALIDATION", "1");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let t0 = Instant::now();
    let out = cmd.output().unwrap();
    (out, t0.elapsed())
}

#[test]
fn hostile_ifc_files_give_clear_errors_within_10_s() {
    if python().is_none() {
        return;
    }
    let dir = tmp("hostile");
    let mut table = Vec::new();
    for case in write_ifc_corpus(&dir).unwrap() {
        let (out, took) = render_small(&case.path, &[("HRTAO_MAX_SCENE_MB", "512")]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let file = case.path.file_name().unwrap().to_str().unwrap();
        table.push(format!("{}: {:?} in {took:.2?}", case.name, out.status.code()));
        assert!(!stderr.contains("panicked"), "{}: {stderr}", case.name);
        match case.expect {
            Expect::Image => assert!(out.status.success(), "{}: {stderr}", case.name),
            Expect::Error => {
                assert!(
                    out.status.code() == Some(1) && stderr.contains(file),
                    "{}: a clear error naming the file\n{stderr}",
                    case.name
                );
                assert!(took < Duration::from_secs(10), "{}: {took:?}", case.name);
                let line = stderr
                    .lines()
                    .rev()
                    .find(|l| l.contains(file))
                    .unwrap_or_default();
                table.push(format!("    {line}"));
            }
        }
    }
    println!("{}", table.join("\n"));
    let _ = std::fs::remove_dir_all(dir);
}

/// Too many entities for the scene memory limit is refused by counting, before the worker starts.
#[test]
fn entity_count_over_the_memory_limit_is_refused_before_the_worker() {
    let dir = tmp("cap");
    let path = dir.join("many.ifc");
    let mut body = hrtao_scene::hostile::ifc_box("IFC4", "");
    let extra: String = (100..70_000)
        .map(|i| format!("#{i}=IFCCARTESIANPOINT((0.,0.,0.));\n"))
        .collect();
    body = body.replace("ENDSEC;\nEND-ISO", &format!("{extra}ENDSEC;\nEND-ISO"));
    std::fs::write(&path, body).unwrap();
    let o = LoadOptions {
        max_memory: 64 << 20,
        ..Default::default()
    };
    let e = hrtao_scene::load_with(path.to_str().unwrap(), &o, &mut |_| {}).unwrap_err();
    assert!(
        matches!(&e, SceneError::TooLarge(m) if m.contains("entities, over the cap")),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn without_the_worker_the_error_names_the_install_command() {
    let dir = tmp("absent");
    let path = dir.join("box.ifc");
    std::fs::write(&path, hrtao_scene::hostile::ifc_box("IFC4", "")).unwrap();
    let (out, _) = render_small(
        &path,
        &[("HRTAO_IFC_PYTHON", "/nonexistent/hrtao-ifc-venv/bin/python3")],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("box.ifc")
            && stderr.contains("scripts/install-deps.sh")
            && stderr.contains(&format!(
                "pip install ifcopenshell=={}",
                hrtao_scene::IFCOPENSHELL_VERSION
            )),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// The worker's test hook makes it spin (then it meets its CPU-seconds limit) or sleep (then the test kills it):
/// either way `hrtao render` exits 1 with an error naming the file and what happened, not a crash.
#[test]
fn a_worker_killed_or_out_of_cpu_time_is_an_error() {
    if python().is_none() {
        return;
    }
    let dir = tmp("kill");
    let path = dir.join("box.ifc");
    std::fs::write(&path, hrtao_scene::hostile::ifc_box("IFC4", "")).unwrap();
    let (out, took) = render_small(
        &path,
        &[
            ("HRTAO_IFC_WORKER_TEST_HOOK", "spin"),
            ("HRTAO_IFC_CPU_SECONDS", "1"),
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("box.ifc") && stderr.contains("CPU time limit"),
        "{stderr}"
    );
    assert!(took < Duration::from_secs(30), "{took:?}");

    let png = dir.join("box.png");
    let child = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args([
            "render",
            "--scene",
            path.to_str().unwrap(),
            "--width",
            "96",
            "--height",
            "64",
        ])
        .args(["--out", png.to_str().unwrap()])
        .env("HRTAO_IFC_WORKER_TEST_HOOK", "sleep")
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let mut killed = false;
    while !killed && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(200));
        for entry in std::fs::read_dir("/proc").unwrap().flatten() {
            let Ok(pid) = entry.file_name().to_string_lossy().parse::<i32>() else {
                continue;
            };
            let stat = std::fs::read_to_string(entry.path().join("stat")).unwrap_or_default();
            let ppid = stat
                .rsplit(')')
                .next()
                .and_then(|r| r.split_whitespace().nth(1))
                .and_then(|p| p.parse::<u32>().ok());
            let cmd = std::fs::read(entry.path().join("cmdline")).unwrap_or_default();
            if ppid == Some(child.id()) && String::from_utf8_lossy(&cmd).contains("box.ifc") {
                // SAFETY: kill(2) on the worker of the `hrtao` this test started.
                unsafe { libc::kill(pid, libc::SIGKILL) };
                killed = true;
            }
        }
    }
    assert!(killed, "the worker ran");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("box.ifc") && stderr.contains("killed"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let _ = std::fs::remove_dir_all(dir);
}

/// The pid of a child of `parent` whose command line contains `needle`.
fn child_process(parent: u32, needle: &str) -> Option<i32> {
    std::fs::read_dir("/proc").ok()?.flatten().find_map(|entry| {
        let pid = entry.file_name().to_string_lossy().parse::<i32>().ok()?;
        let stat = std::fs::read_to_string(entry.path().join("stat")).ok()?;
        let ppid = stat
            .rsplit(')')
            .next()?
            .split_whitespace()
            .nth(1)?
            .parse::<u32>()
            .ok()?;
        let cmd = std::fs::read(entry.path().join("cmdline")).ok()?;
        (ppid == parent && String::from_utf8_lossy(&cmd).contains(needle)).then_some(pid)
    })
}

/// The window (under Xvfb) shows gen:box and opens an IFC file from the Recent menu (real X input); the test kills the
/// IfcOpenShell worker while it reads. The viewer keeps running with gen:box on screen and shows the error in a
/// toast; it still answers input (F12 saves a screenshot of gen:box).
#[test]
fn the_window_survives_a_killed_worker_with_an_error_toast() {
    if python().is_none() || !common::display_available() {
        return;
    }
    let _x = common::x_input_lock();
    let dir = common::out_dir("ifc-kill");
    let path = dir.join("box.ifc");
    std::fs::write(&path, hrtao_scene::hostile::ifc_box("IFC4", "")).unwrap();
    // Opened as a user would: File ▸ Recent, where the preferences remember it.
    let config = dir.join("viewer.json");
    std::fs::write(
        &config,
        serde_json::json!({ "recent": [std::fs::canonicalize(&path).unwrap()] }).to_string(),
    )
    .unwrap();
    let mut v = common::Running::start_with(
        &[
            "gen:box",
            "--size",
            "640x400",
            "--config",
            config.to_str().unwrap(),
        ],
        &dir,
        &[
            ("HRTAO_UI_PROBE", Some("1")),
            ("HRTAO_IFC_WORKER_TEST_HOOK", Some("sleep")),
        ],
    );
    v.wait_for("] opened gen:box", 1, Duration::from_secs(60));
    let window = v.focus_window();
    let menu = v.probed("recent");
    v.click_until(&window, menu, "ui probe: recent 1 at ", 1);
    let entry = v.probed("recent 1");
    v.click_until(&window, entry, "] opening ", 2);
    let t0 = Instant::now();
    let worker = loop {
        if let Some(pid) = child_process(v.child.id(), "box.ifc") {
            break pid;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60) && v.child.try_wait().unwrap().is_none(),
            "no worker ran:\n{}",
            v.log_text()
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    // SAFETY: kill(2) on the worker of the viewer this test started.
    unsafe { libc::kill(worker, libc::SIGKILL) };
    v.wait_for("ui probe: toast = ", 1, Duration::from_secs(30));
    v.wait_for("killed", 1, Duration::from_secs(30));
    let toast = v
        .log_text()
        .lines()
        .rev()
        .find(|l| l.contains("ui probe: toast = "))
        .unwrap()
        .to_string();
    assert!(
        toast.contains("box.ifc") && toast.contains("killed"),
        "the toast names the file and what happened: {toast}"
    );
    assert!(v.child.try_wait().unwrap().is_none(), "the viewer runs on");
    common::xdotool(&["key", "--window", &window, "F12"]);
    v.wait_for("] screenshot saved", 1, Duration::from_secs(60));
    let shot = &common::screenshots(&dir.join("screenshots"))[0];
    assert!(
        shot.file_name().unwrap().to_string_lossy().starts_with("gen_box"),
        "the open scene is still gen:box: {shot:?}"
    );
    let img = image::open(shot).unwrap().to_rgb8();
    let corner = *img.get_pixel(0, 0);
    let model = img
        .pixels()
        .filter(|p| p.0.iter().zip(corner.0).any(|(a, b)| a.abs_diff(b) > 60))
        .count();
    assert!(model > 500, "gen:box is still on screen ({model} pixels)");
    v.validation_clean();
    let _ = std::fs::remove_dir_all(dir);
}
