//! What a new user meets first, in the real window (Xvfb + lavapipe): a file that cannot be opened says which
//! file and why on the last line, and an `--orbit` run saves the window capture it was asked for.
use std::process::Command;

mod common;
use common::*;

/// `hrtao view /no/such.step --exit`: a non-zero exit whose last stderr line names the path and the OS's reason
/// (before: "hrtao: error: no scene could be opened", the reason only in a WARN line above it).
#[test]
fn a_missing_file_names_the_path_and_the_reason_on_the_last_line() {
    let _display = display_lock();
    if !display_available() {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(["view", "/no/such.step", "--size", "200x150"])
        .args(["--no-config", "--exit"])
        .output()
        .expect("run hrtao view");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a missing file must fail:\n{stderr}");
    let last = stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("");
    assert!(
        last.contains("/no/such.step") && last.contains("No such file or directory"),
        "the last line names the file and the reason: {last:?}\n{stderr}"
    );
}

/// `--orbit 1 --screenshot-ui X --exit` writes X once the orbit has converged (it exited 0 without it).
#[test]
fn an_orbit_run_writes_its_window_capture() {
    if !display_available() {
        return;
    }
    let dir = out_dir("orbit-ui");
    let shot = dir.join("window.png");
    let stats = dir.join("stats.json");
    let (shot_arg, stats_arg) = (shot.to_str().unwrap(), stats.to_str().unwrap());
    let args = [
        "--size",
        "320x200",
        "--orbit",
        "1",
        "--no-panel",
        "--screenshot-ui",
        shot_arg,
    ];
    let stderr = scripted_run(&[&args[..], &["--stats", stats_arg]].concat(), &[]);
    let img = image::open(&shot)
        .unwrap_or_else(|e| panic!("{}: {e}\n{stderr}", shot.display()))
        .to_rgb8();
    assert_eq!((img.width(), img.height()), (320, 200));
    // The capture comes after convergence: the stats' last frame says so.
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let last = json["frames"].as_array().and_then(|f| f.last()).cloned().unwrap();
    assert_eq!(last["converged"], true, "{last}");
    // The image shows the model: many grey levels, not a blank window.
    let mut seen = [false; 256];
    for p in img.pixels() {
        seen[p.0[1] as usize] = true;
    }
    assert!(seen.iter().filter(|s| **s).count() > 32, "a blank capture");
}
