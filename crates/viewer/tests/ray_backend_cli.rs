//! `--ray-backend query|pipeline` in `hrtao render`, `hrtao bench` and `hrtao view`: each runs with each backend,
//! validation silent, the device reports the backend it traced with, and per-pixel RTAO renders the same image by
//! both (the backends trace the same rays: crates/hrtao-core/tests/ray_backends.rs compares every tracing pass).
//! Where the device has no ray queries (a pipelines-only GPU, or `HRTAO_HIDE_RAY_QUERY=1`, which makes any device
//! look like one: `hiding_ray_queries_leaves_the_pipelines`) the ray-query runs are skipped with a message
//! (`cli::ray_queries_or_skip`).
mod cli;
/// The test data helpers of the scene crate's tests (`testdata/`), shared rather than copied.
#[path = "../../scene/tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::process::Command;

fn tmp_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-ray-backend-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn read_pfm(path: &std::path::Path) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap();
    // Three header lines: "Pf", "W H", scale (negative: little-endian).
    let mut lines = 0;
    let mut at = 0;
    while lines < 3 {
        if bytes[at] == b'\n' {
            lines += 1;
        }
        at += 1;
    }
    let header = String::from_utf8_lossy(&bytes[..at]).to_string();
    assert!(
        header.lines().nth(2).unwrap().trim().starts_with('-'),
        "little-endian PFM"
    );
    bytes[at..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// The backends this machine's device runs: both, or pipelines alone where it has no ray queries (the skip said
/// for `test`).
fn backends(test: &str) -> &'static [&'static str] {
    if cli::ray_queries_or_skip(&format!("{test} by ray queries")) {
        &["query", "pipeline"]
    } else {
        &["pipeline"]
    }
}

/// Per-pixel RTAO by the two backends: the same 8 rays per pixel, compiled apart. On lavapipe bit-equal; a GPU's
/// compiler may round a ray's setup differently by an ulp, which changes the verdict of a ray only where it grazes
/// an edge (crates/hrtao-core/tests/ray_backends.rs, `RTAO_DIFFERING`): so at most 1 % of the pixels (144 of
/// 160×90) may differ by more than 1e-4, and the MAE stays within 0.002 (such a pixel moves by 1/8). Rays that are
/// really wrong (another sequence or radius, missed hits) change most of the occluded pixels.
#[test]
fn render_with_each_backend_gives_the_same_per_pixel_rtao() {
    if !cli::ray_queries_or_skip("per-pixel RTAO by ray queries against pipelines") {
        return;
    }
    let dir = tmp_dir();
    let mut images = Vec::new();
    for backend in ["query", "pipeline"] {
        let pfm = dir.join(format!("rod-{backend}.pfm"));
        let stats = dir.join(format!("rod-{backend}.json"));
        cli::hrtao_ok(
            &cli::rod_view(&[
                "--mode",
                "rtao",
                "--frames",
                "2",
                "--ray-backend",
                backend,
                "--out",
                dir.join(format!("rod-{backend}.png")).to_str().unwrap(),
                "--ao-out",
                pfm.to_str().unwrap(),
                "--stats",
                stats.to_str().unwrap(),
            ])
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
        );
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(
            v["device"]["ray_backend"], backend,
            "{backend}: the device's backend in the stats"
        );
        assert_eq!(v["validation_messages"], 0, "{backend}: validation messages");
        images.push(read_pfm(&pfm));
    }
    let n = 160 * 90;
    assert_eq!((images[0].len(), images[1].len()), (n, n));
    let differences: Vec<f32> = images[0]
        .iter()
        .zip(&images[1])
        .map(|(a, b)| (a - b).abs())
        .collect();
    let differing = differences.iter().filter(|&&d| d > 1e-4).count();
    let mae = differences.iter().sum::<f32>() / n as f32;
    eprintln!("per-pixel RTAO: {differing} of {n} pixels differ, MAE {mae:.5}");
    assert!(
        differing * 100 <= n && mae <= 0.002,
        "per-pixel RTAO differs between the backends in {differing} of {n} pixels, MAE {mae}"
    );
    // Rod's view at 160×90 shows 697 occluded pixels (AO < 0.999; lavapipe): more than 4× the 144 that may differ,
    // so a backend that is wrong in most of them cannot pass.
    let occluded = images[0].iter().filter(|&&a| a < 0.999).count();
    assert!(
        occluded > 4 * n / 100,
        "occlusion enough for a wrong backend to show: {occluded} pixels"
    );
}

#[test]
fn bench_runs_with_each_backend() {
    let dir = tmp_dir();
    let scene = common::test_scene("rod");
    for &backend in backends("bench") {
        let json = dir.join(format!("bench-{backend}.json"));
        let extra = ["--ray-backend", backend, "--json", json.to_str().unwrap()];
        cli::hrtao_ok(&cli::tiny_bench(scene.to_str().unwrap(), ("2", "1"), &extra));
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(
            v["device"]["ray_backend"], backend,
            "{backend}: the device's backend in the bench"
        );
        assert_eq!(v["validation_messages"], 0, "{backend}: validation messages");
        let nav = v["hrtao"]["nav"].as_array().unwrap();
        assert_eq!(nav.len(), 2, "{backend}: navigation frames");
        assert!(
            nav.iter().all(|f| f["rays"].as_f64().unwrap() > 0.0),
            "{backend}: rays traced"
        );
    }
}

#[test]
fn an_unknown_backend_is_refused() {
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(["render", "--ray-backend", "magic"])
        .output()
        .expect("run hrtao");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("query, pipeline"));
}

/// Whether there is a display (the window tests run under xvfb-run); says the test skips when there is not.
fn display_or_skip() -> bool {
    let there = std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if !there {
        eprintln!("skipped: no display");
    }
    there
}

/// The viewer's scripted run with each backend (where a display is: the window tests run under xvfb-run): it
/// exits 0 (a scripted run exits 1 on any validation message) and saves its screenshot.
#[test]
fn view_runs_with_each_backend() {
    if !display_or_skip() {
        return;
    }
    let dir = tmp_dir();
    for &backend in backends("view") {
        let shot = dir.join(format!("view-{backend}.png"));
        cli::hrtao_ok(&[
            "view",
            "--no-config",
            "--size",
            "160x90",
            "--no-panel",
            "--frames",
            "3",
            "--ray-backend",
            backend,
            "--screenshot",
            shot.to_str().unwrap(),
            "--exit",
        ]);
        let meta = std::fs::metadata(&shot).unwrap_or_else(|e| panic!("{backend}: no screenshot: {e}"));
        assert!(meta.len() > 1000, "{backend}: screenshot of {} bytes", meta.len());
    }
}

/// The backend saved in the preferences (the panel's "Rays" choice) opens the device at the next start; the
/// command line's wins over it.
#[test]
fn the_viewer_opens_the_device_with_the_saved_backend() {
    if !display_or_skip() {
        return;
    }
    let dir = tmp_dir();
    let config = dir.join("viewer.json");
    std::fs::write(&config, r#"{ "ray_backend": "pipeline" }"#).unwrap();
    let mut cases = vec![(None, "pipeline")];
    if cli::ray_queries_or_skip("the command line's ray queries over the saved pipelines") {
        cases.push((Some("query"), "query"));
    }
    for (forced, traced) in cases {
        let mut args = vec![
            "view",
            "gen:box",
            "--config",
            config.to_str().unwrap(),
            "--size",
            "160x90",
            "--no-panel",
            "--frames",
            "2",
            "--exit",
        ];
        if let Some(f) = forced {
            args.extend(["--ray-backend", f]);
        }
        let out = cli::hrtao_ok(&args);
        let log = String::from_utf8_lossy(&out.stderr);
        assert!(
            log.contains(&format!("rays traced by {traced}")),
            "saved pipeline, forced {forced:?}: {log}"
        );
    }
    // The saved choice is kept as it was (the run rewrote the file with the viewer's state).
    let saved: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&config).unwrap()).unwrap();
    assert_eq!(saved["ray_backend"], "pipeline");
}

/// `HRTAO_HIDE_RAY_QUERY=1` makes the device look like a GPU that traces with ray-tracing pipelines only, for
/// every context of the process: `hrtao devices` lists no ray queries (the device it opens traces by pipelines;
/// with ray queries forced no device is usable, and the listing says they are hidden), and `hrtao render` picks
/// the pipelines by itself and renders validation-clean.
#[test]
fn hiding_ray_queries_leaves_the_pipelines() {
    if !cli::hrtao(&["devices", "--ray-backend", "pipeline"])
        .status
        .success()
    {
        eprintln!("skipped: hiding ray queries: the device has no ray-tracing pipelines to fall back on");
        return;
    }
    let hidden = [("HRTAO_HIDE_RAY_QUERY", "1")];
    let text = |o: &std::process::Output| {
        format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    };
    let out = cli::hrtao_with(&["devices"], &hidden);
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    let opened = t
        .lines()
        .find(|l| l.starts_with("opened: "))
        .expect("the device opened");
    assert!(opened.ends_with("rays traced by pipeline"), "{t}");
    assert!(!t.contains("traced by query"), "{t}");

    let out = cli::hrtao_with(&["devices", "--ray-backend", "query"], &hidden);
    let t = text(&out);
    assert!(!out.status.success(), "ray queries forced while hidden: {t}");
    let listed: Vec<&str> = t
        .lines()
        .filter(|l| l.starts_with("  ") && l.contains("): "))
        .collect();
    assert!(!listed.is_empty(), "{t}");
    for l in &listed {
        assert!(
            l.contains("lacks rayQuery") && l.contains("hidden by HRTAO_HIDE_RAY_QUERY")
                || l.contains("not usable") && !l.contains("rayQuery"),
            "every device is listed without ray queries: {l}\n{t}"
        );
    }
    assert!(
        listed
            .iter()
            .any(|l| l.contains("hidden by HRTAO_HIDE_RAY_QUERY")),
        "{t}"
    );
    assert!(t.contains("chosen: none"), "{t}");

    let dir = tmp_dir();
    let stats = dir.join("hidden.json");
    let args = cli::rod_view(&[
        "--mode",
        "rtao",
        "--frames",
        "1",
        "--out",
        dir.join("hidden.png").to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    let out = cli::hrtao_with(&args, &hidden);
    assert!(out.status.success(), "{}", text(&out));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(v["device"]["ray_backend"], "pipeline", "{v:#}");
    assert_eq!(v["validation_messages"], 0);
}
