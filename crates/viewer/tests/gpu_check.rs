//! `scripts/gpu-check.sh`: a bundle made from this test's build (`HRTAO_BIN`: no release build) runs its `run
//! --small` on this machine's device with the bundled Vulkan loader, and its report has the device, every check
//! passed with its numbers, and the benchmark of both HRTAO modes; a bundle over the size limit fails loudly.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The program on PATH, if any.
fn on_path(program: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// The bundle step needs binutils (strip, objdump) and the run python3.
fn tools_missing() -> bool {
    let missing: Vec<_> = ["strip", "objdump", "python3"]
        .into_iter()
        .filter(|p| on_path(p).is_none())
        .collect();
    if !missing.is_empty() {
        eprintln!("skipping: {missing:?} not found");
    }
    !missing.is_empty()
}

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-gpu-check-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/gpu-check.sh")
}

/// `gpu-check.sh bundle DIR` with this test's binary and no shared scenes (CI has none: the gearbox only).
fn bundle(dir: &Path, max_mib: Option<&str>) -> Output {
    let mut cmd = Command::new("bash");
    cmd.arg(script())
        .arg("bundle")
        .arg(dir)
        .env("HRTAO_BIN", env!("CARGO_BIN_EXE_hrtao"))
        .env("HRTAO_SHARED", dir.join("no-shared-folder"));
    if let Some(mib) = max_mib {
        cmd.env("GPU_CHECK_MAX_MIB", mib);
    }
    cmd.output().expect("run gpu-check.sh bundle")
}

fn text(out: &Output) -> String {
    format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn a_bundle_runs_its_small_check_and_reports_every_check() {
    if tools_missing() {
        return;
    }
    let dir = tmp_dir("bundle");
    let b = dir.join("bundle");
    let out = bundle(&b, None);
    let log = text(&out);
    assert!(out.status.success(), "bundle failed:\n{log}");
    assert!(log.contains("glibc >= 2."), "the glibc version needed:\n{log}");
    assert!(log.contains("san_francisco and engine skipped"), "{log}");
    for f in [
        "bin/hrtao",
        "lib/libvulkan.so.1",
        "gpu-check.sh",
        "gpu_check.py",
        "manifest.json",
    ] {
        assert!(b.join(f).is_file(), "{f} is not in the bundle:\n{log}");
    }

    let report_dir = dir.join("out");
    let run = Command::new("bash")
        .arg(b.join("gpu-check.sh"))
        .args(["run", "--small", "--out"])
        .arg(&report_dir)
        .env("HRTAO_VALIDATION", "1")
        .env_remove("HRTAO_BIN")
        .output()
        .expect("run gpu-check.sh run");
    let log = text(&run);
    assert!(
        run.status.success(),
        "run --small failed ({}):\n{log}",
        run.status
    );
    assert!(report_dir.join("report.md").is_file());
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["passed"], true, "{report:#}");
    let device = &report["device"];
    assert!(
        !device["name"].as_str().unwrap_or("").is_empty() && device["driver"].is_string(),
        "{device:#}"
    );
    // Lavapipe has both backends: both are checked, and against each other.
    let backends = device["ray_backends"].as_array().unwrap();
    assert!(!backends.is_empty(), "{device:#}");
    assert!(device["properties"]["timestamps"].is_boolean(), "{device:#}");

    let checks = report["checks"].as_array().unwrap();
    let mut names: Vec<&str> = checks.iter().map(|c| c["name"].as_str().unwrap()).collect();
    names.sort_unstable();
    let mut expected = vec!["hash_map_overload".to_string()];
    for b in backends {
        let b = b.as_str().unwrap();
        expected.push(format!("rtao_vs_cycles_{b}"));
        expected.push(format!("hrtao_vs_cycles_{b}"));
    }
    if backends.len() == 2 {
        expected.push("backends_agree".into());
    }
    expected.sort_unstable();
    assert_eq!(names, expected, "{report:#}");
    for c in checks {
        assert_eq!(c["passed"], true, "{c:#}");
        let mae = c["numbers"]["mae"]
            .as_f64()
            .or(c["numbers"]["mae_vs_normal_map"].as_f64());
        assert!(mae.is_some_and(|m| (0.0..1.0).contains(&m)), "{c:#}");
    }
    let overload = checks.iter().find(|c| c["name"] == "hash_map_overload").unwrap();
    assert!(
        overload["numbers"]["failed_inserts"].as_u64().unwrap() > 0,
        "{overload:#}"
    );
    assert_eq!(overload["numbers"]["non_finite"], 0, "{overload:#}");

    let benches = report["benches"].as_array().unwrap();
    assert_eq!(benches.len(), 1, "the gearbox only: {report:#}");
    for mode in ["ours", "paper", "rtao"] {
        let t = &benches[0]["modes"][mode];
        assert!(
            t["first_frame_wall_ms"].as_f64().is_some_and(|v| v > 0.0)
                && t["nav_frame_wall_ms"].as_f64().is_some_and(|v| v > 0.0),
            "{mode}: {t:#}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_bundle_over_the_size_limit_fails_loudly() {
    if tools_missing() {
        return;
    }
    let dir = tmp_dir("limit");
    // The binary alone is several MiB: a 1 MiB limit cannot hold it.
    let out = bundle(&dir.join("bundle"), Some("1"));
    let log = text(&out);
    assert!(!out.status.success(), "a bundle over 1 MiB passed:\n{log}");
    assert!(log.contains("over the limit of 1 MiB"), "{log}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_machine_without_a_vulkan_driver_is_told_what_is_missing() {
    if tools_missing() {
        return;
    }
    let dir = tmp_dir("no-driver");
    // From the repository, as on a machine whose loader finds no driver file.
    let run = Command::new("bash")
        .arg(script())
        .args(["run", "--small", "--out"])
        .arg(&dir)
        .env("HRTAO_BIN", env!("CARGO_BIN_EXE_hrtao"))
        .env("VK_DRIVER_FILES", dir.join("no-such-icd.json"))
        .output()
        .expect("run gpu-check.sh run");
    let log = text(&run);
    assert_eq!(run.status.code(), Some(2), "{log}");
    assert!(log.contains("missing: a Vulkan driver"), "{log}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["passed"], false);
    assert!(
        report["error"].as_str().unwrap().contains("no-such-icd.json"),
        "{report:#}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
