//! The command line as a user meets it: value parsers that name the accepted values, a help that hides the
//! scripted-run flags and lists keys and environment variables, `--version` with the commit, `devices`, the
//! bundled scene rendered from anywhere, and `--set-at-frame`.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn hrtao_in(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_hrtao"));
    cmd.args(args).current_dir(dir).env("HRTAO_VALIDATION", "1");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run hrtao")
}

fn hrtao(args: &[&str]) -> Output {
    hrtao_in(Path::new(env!("CARGO_MANIFEST_DIR")), args, &[])
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-cli-args-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `tmp(name)` and a fresh HOME folder in it.
fn tmp_with_home(name: &str) -> (PathBuf, PathBuf) {
    let dir = tmp(name);
    let home = dir.join("home");
    std::fs::create_dir_all(&home).unwrap();
    (dir, home)
}

/// Bad values are refused by the parser (exit status 2, before any file or device is touched), and the message
/// names the option and what it accepts.
#[test]
fn parsers_refuse_bad_values_and_name_what_is_accepted() {
    let cases: &[(&[&str], &[&str])] = &[
        (&["render", "--up", "+w"], &["--up", "x, y, z, -x, -y, -z"]),
        (&["view", "--up", "w"], &["--up", "x, y, z, -x, -y, -z"]),
        (
            &["bench", "--scene", "a.glb", "--auto-camera", "top"],
            &["--auto-camera", "fit, corner"],
        ),
        (
            &["bench", "--scene", "a.glb", "--group", "misc"],
            &["--group", "scenes, scale"],
        ),
        (&["render", "--mode", "fast"], &["--mode", "hrtao, rtao, none"]),
        (
            &["view", "--size", "1280"],
            &["--size", "must look like 1280x720"],
        ),
        (&["view", "--size", "0x720"], &["--size", "within 1..=16384"]),
        (
            &["view", "--screenshot", "a.png", "--screenshot-size", "9x99999"],
            &["--screenshot-size", "16384"],
        ),
        (&["view", "--render-scale", "3"], &["--render-scale", "0.05..=2"]),
        (&["render", "--frames", "0"], &["--frames", "0 is not in 1.."]),
        (
            &["render", "--hash-capacity", "3000"],
            &["--hash-capacity", "power of two"],
        ),
        (
            &["render", "--set", "{\"no_such\": 1}"],
            &["--set", "no setting `no_such`"],
        ),
        (&["render", "--set", "[1, 2]"], &["--set", "not a JSON object"]),
        (&["bench", "--scene", "a.glb", "--repeat", "0"], &["--repeat"]),
        (&["-q", "-v"], &["--quiet", "cannot be used with"]),
    ];
    for (args, wanted) in cases {
        let o = hrtao(args);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {t}");
        for w in *wanted {
            assert!(t.contains(w), "{args:?}: no `{w}` in\n{t}");
        }
    }
    // Accepted spellings: the upper-case axis and the mode aliases of earlier versions.
    let o = hrtao(&["render", "--up", "Z", "--mode", "cells", "--help"]);
    assert!(o.status.success(), "{}", text(&o));
}

/// `--set-at-frame` pairs are checked like `--set` before any work.
#[test]
fn set_at_frame_is_checked_before_rendering() {
    for (args, wanted) in [
        (
            vec!["render", "--set-at-frame", "one", "{}"],
            "--set-at-frame K: `one`",
        ),
        (
            vec!["render", "--set-at-frame", "1", "{\"x\": 1}"],
            "no setting `x`",
        ),
    ] {
        let o = hrtao(&args);
        let t = text(&o);
        assert!(!o.status.success() && t.contains(wanted), "{args:?}: {t}");
        assert!(!t.contains("device:"), "refused before opening a device: {t}");
    }
}

#[test]
fn help_hides_scripted_flags_and_lists_examples_keys_and_environment() {
    for args in [&["--help"][..], &["view", "--help"], &["render", "--help"]] {
        let t = text(&hrtao(args));
        for hidden in ["--resize-at-frame", "--open-at-frame", "--set-at-frame"] {
            assert!(!t.contains(hidden), "{args:?} shows {hidden}");
        }
    }
    let long = text(&hrtao(&["--help"]));
    for w in [
        "Examples:",
        "hrtao model.step",
        "Viewer keys and mouse",
        "Ctrl+Q",
        "F11",
        "Ctrl+1 / Ctrl+3 / Ctrl+7",
        "Environment:",
        "RUST_LOG",
        "HRTAO_MAX_SCENE_MB",
        "HRTAO_DEVICE",
        "HRTAO_VALIDATION",
        "HRTAO_OCCT_CPU_SECONDS",
        "HRTAO_IFC_PYTHON",
        "HRTAO_IFC_CPU_SECONDS",
        "HRTAO_FRAMES_IN_FLIGHT",
        "XDG_PICTURES_DIR",
        "hrtao thumbnail --size 256",
        "x, y, z, -x, -y or -z",
        "walk mode",
        "[FILE]",
    ] {
        assert!(long.contains(w), "--help lacks `{w}`:\n{long}");
    }
    // No line of the help is wider than clap wraps it (100 columns when the output is not a terminal).
    let widest = long.lines().map(|l| l.chars().count()).max().unwrap();
    assert!(widest <= 100, "a {widest}-column line:\n{long}");
    let short = text(&hrtao(&["-h"]));
    assert!(
        short.contains("Examples:") && !short.contains("Environment:"),
        "{short}"
    );
    // Every format in each command's help: tests/formats.rs.
}

#[test]
fn version_names_the_commit() {
    let o = hrtao(&["--version"]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.starts_with(&format!("hrtao {}", env!("CARGO_PKG_VERSION"))),
        "{t}"
    );
    let head = Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    match head {
        // Built from this checkout: the commit (a build older than HEAD would be rebuilt by cargo first).
        Some(h) => assert!(t.contains(&format!("(commit {h})")), "HEAD {h}: {t}"),
        None => assert!(!t.contains("commit"), "no git: no commit claimed: {t}"),
    }
}

/// `devices` lists every device with its verdict and says which one is chosen and by what rule; a --device filter
/// that matches nothing says so for each device and fails.
#[test]
fn devices_lists_every_device_and_the_choice() {
    let o = hrtao(&["devices"]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    let listed: Vec<&str> = t
        .lines()
        .filter(|l| l.starts_with("  ") && l.contains("): "))
        .collect();
    let count: usize = t
        .lines()
        .find_map(|l| {
            l.strip_prefix("Vulkan devices (")?
                .strip_suffix("):")?
                .parse()
                .ok()
        })
        .expect("a device count");
    assert!(count >= 1 && listed.len() == count, "{t}");
    assert_eq!(
        listed.iter().filter(|l| l.ends_with("usable, chosen")).count(),
        1,
        "{t}"
    );
    let chosen = t
        .lines()
        .find(|l| l.starts_with("chosen: "))
        .expect("a chosen line");
    assert!(chosen.contains("the usable device of the best kind"), "{chosen}");
    let opened = t
        .lines()
        .find(|l| l.starts_with("opened: "))
        .expect("the device opened");
    let name = listed
        .iter()
        .find(|l| l.ends_with("usable, chosen"))
        .and_then(|l| l.trim().split_once(": "))
        .map(|(_, rest)| rest.split(" (").next().unwrap().to_string())
        .unwrap();
    assert!(
        opened.contains(&name),
        "the listed choice is the device opened: {t}"
    );

    let o = hrtao(&["devices", "--device", "no such gpu"]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("name does not contain `no such gpu`") && t.contains("chosen: none"),
        "{t}"
    );
}

/// The bundled scene comes from the binary: rendered from `/` with a fresh HOME, the image is written, the
/// scene file is the embedded copy in the cache, and it is byte for byte the repository's asset.
#[test]
fn render_of_the_bundled_scene_needs_no_source_tree() {
    let (dir, home) = tmp_with_home("bundled");
    let png = dir.join("bundled.png");
    let stats = dir.join("stats.json");
    let o = hrtao_in(
        Path::new("/"),
        &[
            "-q",
            "render",
            "--width",
            "64",
            "--height",
            "40",
            "--out",
            png.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ],
        &[("HOME", home.to_str().unwrap()), ("XDG_CACHE_HOME", "")],
    );
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(!t.contains("INFO"), "-q: no info lines: {t}");
    assert_eq!(image::image_dimensions(&png).unwrap(), (64, 40));
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let scene = PathBuf::from(s["scene"].as_str().unwrap());
    assert_eq!(scene, home.join(".cache/hrtao/bundled/default.glb"), "{s}");
    let asset = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/default.glb");
    assert!(std::fs::read(&scene).unwrap() == std::fs::read(asset).unwrap());
    assert_eq!(
        s["settings"]["ao_radius"].as_f64(),
        Some(8.0),
        "the bundled scene's radius"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn mean_ao(path: &Path) -> f64 {
    let (_, _, ao) = hrtao_core::imageio::read_pfm(path).unwrap();
    ao.iter().map(|&v| v as f64).sum::<f64>() / ao.len() as f64
}

/// `--set-at-frame 1 '{"ao_radius": 24}'` after one frame at radius 8: the second frame's AO is that of radius
/// 24 (wider radius, more occlusion: darker), close to a run at 24 from the start, far from the run at 8.
#[test]
fn set_at_frame_changes_the_radius_from_the_next_frame() {
    let dir = tmp("set-at-frame");
    let run = |name: &str, extra: &[&str]| {
        let ao = dir.join(format!("{name}.pfm"));
        let mut args = vec![
            "-q", "render", "--width", "96", "--height", "64", "--frames", "2", "--ao-out",
        ];
        args.push(ao.to_str().unwrap());
        args.extend_from_slice(extra);
        let o = hrtao_in(&dir, &args, &[("HOME", dir.to_str().unwrap())]);
        assert!(o.status.success(), "{name}: {}", text(&o));
        mean_ao(&ao)
    };
    let at_8 = run("r8", &[]);
    let changed = run("r8-then-24", &["--set-at-frame", "1", r#"{"ao_radius": 24}"#]);
    let at_24 = run("r24", &["--radius", "24"]);
    assert!(
        at_24 < at_8 - 0.01,
        "a wider radius occludes more: {at_8} {at_24}"
    );
    let moved = (at_8 - changed) / (at_8 - at_24);
    assert!(
        moved > 0.8 && moved < 1.2,
        "radius 8 {at_8:.4}, 8 then 24 {changed:.4}, 24 {at_24:.4}: moved {moved:.2} of the way"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Relative XDG_* values are ignored, as the XDG Base Directory specification says: with XDG_CACHE_HOME and
/// XDG_DATA_HOME relative, the bundled scene goes to ~/.cache and the IFC worker is looked for under
/// ~/.local/share.
#[test]
fn relative_xdg_directories_are_ignored() {
    let (dir, home) = tmp_with_home("relative-xdg");
    let stats = dir.join("stats.json");
    let env = [
        ("HOME", home.to_str().unwrap()),
        ("XDG_CACHE_HOME", "relative/cache"),
        ("XDG_DATA_HOME", "relative/data"),
        ("HRTAO_IFC_PYTHON", ""),
    ];
    let o = hrtao_in(
        &dir,
        &[
            "-q",
            "render",
            "--width",
            "32",
            "--height",
            "20",
            "--stats",
            stats.to_str().unwrap(),
        ],
        &env,
    );
    assert!(o.status.success(), "{}", text(&o));
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(
        PathBuf::from(s["scene"].as_str().unwrap()),
        home.join(".cache/hrtao/bundled/default.glb")
    );
    assert!(!dir.join("relative").exists());
    // An IFC file is checked, then its worker's interpreter is looked for in the venv under ~/.local/share.
    let ifc = dir.join("wall.ifc");
    std::fs::write(
        &ifc,
        "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('IFC4'));\nENDSEC;\nDATA;\n#1=IFCWALL('x',$,$,$,$,$,$,$,$);\nENDSEC;\n\
         END-ISO-10303-21;\n",
    )
    .unwrap();
    let o = hrtao_in(&dir, &["render", "--scene", ifc.to_str().unwrap()], &env);
    let t = text(&o);
    let venv = home.join(".local/share/hrtao/ifc-venv/bin/python3");
    assert!(
        !o.status.success() && t.contains(&format!("{} does not exist", venv.display())),
        "{t}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
