//! What the command-line tests share: `hrtao` run with the validation layer, and rod's 160×90 reference view
//! (the committed test scene and camera).
#![allow(dead_code)]
use std::ffi::OsStr;
use std::fmt::Debug;
use std::process::{Command, Output};

/// `hrtao ARGS` with the validation layer on and the ray backend as the arguments say (HRTAO_RAY_BACKEND unset).
pub fn hrtao<S: AsRef<OsStr> + Debug>(args: &[S]) -> Output {
    hrtao_with(args, &[])
}

/// `hrtao`, with `env` set too.
pub fn hrtao_with<S: AsRef<OsStr> + Debug>(args: &[S], env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(args)
        .env("HRTAO_VALIDATION", "1")
        .env_remove("HRTAO_RAY_BACKEND")
        .envs(env.iter().copied())
        .output()
        .expect("run hrtao")
}

/// `hrtao ARGS`, asserted successful (its output in the message otherwise).
pub fn hrtao_ok<S: AsRef<OsStr> + Debug>(args: &[S]) -> Output {
    hrtao_ok_with(args, &[])
}

/// `hrtao_ok`, with `env` set too.
pub fn hrtao_ok_with<S: AsRef<OsStr> + Debug>(args: &[S], env: &[(&str, &str)]) -> Output {
    let out = hrtao_with(args, env);
    assert!(
        out.status.success(),
        "hrtao {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Whether `hrtao` can trace with ray queries on this machine's device (`hrtao devices --ray-backend query`
/// succeeds): false on a GPU that traces with pipelines only, or under `HRTAO_HIDE_RAY_QUERY=1`. Then prints why
/// `test` (the test or the part of it that needs ray queries) is skipped, with the device listing's verdict. A
/// machine where `hrtao devices` finds no usable device at all is not a reason to skip: true, and the test fails
/// as before.
pub fn ray_queries_or_skip(test: &str) -> bool {
    let forced = hrtao(&["devices", "--ray-backend", "query"]);
    if forced.status.success() || !hrtao(&["devices"]).status.success() {
        return true;
    }
    let listing = String::from_utf8_lossy(&forced.stdout);
    let why: Vec<&str> = listing
        .lines()
        .filter(|l| l.starts_with("  ") && l.contains("): "))
        .map(str::trim)
        .collect();
    eprintln!("skipped: {test}: no device with ray queries ({})", why.join("; "));
    false
}

/// `render` of rod's 160×90 reference view (its committed camera, R = 10) at 8 rays per pixel, then `extra`.
pub fn rod_view(extra: &[&str]) -> Vec<String> {
    // The scene tests' `test_scene("rod")` and its reference camera (testdata/refs/index.json).
    let testdata = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata");
    let scene = testdata.join("scenes/rod_assembly/rod.glb");
    let camera = testdata.join("refs/rod_160x90.camera.json");
    let mut args: Vec<String> = [
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--camera",
        camera.to_str().unwrap(),
        "--radius",
        "10",
        "--rays",
        "8",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

/// `hrtao bench` of `scene` at 64×36 with the least work that still runs every part (1 repetition, 4 rays per
/// pixel and 8 at most, 16 reference rays, 2 HRTAO frames), `orbit` navigation and `settle` static frames, then
/// `extra`.
pub fn tiny_bench<'a>(
    scene: &'a str,
    (orbit, settle): (&'a str, &'a str),
    extra: &[&'a str],
) -> Vec<&'a str> {
    let args: [&[&'a str]; 4] = [
        &["bench", "--scene", scene, "--width", "64", "--height", "36"],
        &[
            "--orbit", orbit, "--repeat", "1", "--settle", settle, "--rays", "4",
        ],
        &["--max-rays", "8", "--ref-rays", "16", "--hrtao-frames", "2"],
        extra,
    ];
    args.concat()
}
