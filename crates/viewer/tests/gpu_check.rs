//! `scripts/gpu-check.sh`: a bundle made from this test's build (`HRTAO_BIN`: no release build) refuses this
//! machine's CPU device (lavapipe) with exit status 2 and "not a GPU", then with `--allow-cpu` runs its `run
//! --small` with the bundled Vulkan loader and validation layer, and its report has the device, every check passed
//! with its numbers (the validation renders among them), the benchmark of both HRTAO modes and every step; a glibc
//! older than the bundle needs, a missing python3 and a missing driver are exit status 2 with the need named; the
//! NVIDIA EGL driver file is tried when the GLX one does not load; a step made to hang is killed at its timeout,
//! the report written while it hangs already holds the steps before it, and the final one says it was killed; a
//! bundle over the size limit fails loudly.
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

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

fn report(dir: &Path) -> serde_json::Value {
    let path = dir.join("report.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()))
}

/// The step of that name in a report.
fn step<'a>(report: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    report["steps"]
        .as_array()
        .and_then(|s| s.iter().find(|s| s["name"] == name))
        .unwrap_or_else(|| panic!("no step {name}: {report:#}"))
}

/// Whether `hrtao devices` opens a CPU device here (lavapipe): the refusal is checked only then.
fn opens_a_cpu_device() -> bool {
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .arg("devices")
        .output()
        .expect("hrtao devices");
    let text = String::from_utf8_lossy(&out.stdout);
    text.lines()
        .any(|l| l.starts_with("opened: ") && l.contains("(CPU (software))"))
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
        "lib/x11/libX11.so.6",
        "lib/x11/libXext.so.6",
        "lib/x11/libxcb.so.1",
        "lib/x11/libGLdispatch.so.0",
        "layers/libVkLayer_khronos_validation.so.gz",
        "layers/VkLayer_khronos_validation.json",
        "glibc-needed",
        "gpu-check.sh",
        "gpu_check.py",
        "manifest.json",
    ] {
        assert!(b.join(f).is_file(), "{f} is not in the bundle:\n{log}");
    }
    let needed = std::fs::read_to_string(b.join("glibc-needed")).unwrap();
    assert!(needed.trim().starts_with("2."), "glibc-needed: {needed:?}");

    // Lavapipe is a CPU: refused (exit status 2) without --allow-cpu, the loader's debug output in the report.
    if opens_a_cpu_device() {
        let refused_dir = dir.join("refused");
        let run = Command::new("bash")
            .arg(b.join("gpu-check.sh"))
            .args(["run", "--small", "--out"])
            .arg(&refused_dir)
            .env_remove("HRTAO_BIN")
            .output()
            .expect("run gpu-check.sh run");
        let log = text(&run);
        assert_eq!(run.status.code(), Some(2), "a CPU device was not refused:\n{log}");
        assert!(log.contains("not a GPU"), "{log}");
        let r = report(&refused_dir);
        assert_eq!(r["passed"], false, "{r:#}");
        assert!(
            r["error"]
                .as_str()
                .unwrap()
                .starts_with("not a GPU: hrtao opened llvmpipe"),
            "{r:#}"
        );
        assert!(
            r["checks"].as_array().unwrap().is_empty(),
            "checks ran on a refused device: {r:#}"
        );
        assert_eq!(step(&r, "devices_loader_debug")["status"], "ok", "{r:#}");
        let excerpt = r["loader_debug"]["excerpt"].as_array().unwrap();
        assert!(
            excerpt.iter().any(|l| l.as_str().unwrap().contains("lvp_icd")),
            "the loader's debug output names no driver file: {r:#}"
        );
        assert!(refused_dir.join("loader-debug.log").is_file());
        assert!(std::fs::read_to_string(refused_dir.join("report.md"))
            .unwrap()
            .contains("**not a GPU: "));
    } else {
        eprintln!("this machine opens a GPU: the CPU refusal is not checked here");
    }

    let report_dir = dir.join("out");
    let run = Command::new("bash")
        .arg(b.join("gpu-check.sh"))
        .args(["run", "--small", "--allow-cpu", "--out"])
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
    let report = self::report(&report_dir);
    assert_eq!(report["passed"], true, "{report:#}");
    assert_eq!(report["complete"], true, "{report:#}");
    assert_eq!(report["allow_cpu"], true, "{report:#}");
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
        expected.push(format!("validation_rtao_{b}"));
        expected.push(format!("validation_hrtao_{b}"));
    }
    if backends.len() == 2 {
        expected.push("backends_agree".into());
    }
    expected.sort_unstable();
    assert_eq!(names, expected, "{report:#}");
    for c in checks {
        assert_eq!(c["passed"], true, "{c:#}");
        if c["name"].as_str().unwrap().starts_with("validation_") {
            // Under the bundled layer (a render without it would not pass), no message, finite AO.
            assert_eq!(c["numbers"]["validation_messages"], 0, "{c:#}");
            assert_eq!(c["numbers"]["non_finite"], 0, "{c:#}");
            continue;
        }
        let mae = c["numbers"]["mae"]
            .as_f64()
            .or(c["numbers"]["mae_vs_normal_map"].as_f64());
        assert!(mae.is_some_and(|m| (0.0..1.0).contains(&m)), "{c:#}");
    }
    let stats: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(report_dir.join("validation_hrtao_query.stats.json"))
            .or_else(|_| std::fs::read_to_string(report_dir.join("validation_hrtao_pipeline.stats.json")))
            .unwrap(),
    )
    .unwrap();
    assert_eq!(stats["device"]["validation"], true, "{stats:#}");
    assert!(
        report_dir
            .join("vk-layer/libVkLayer_khronos_validation.so")
            .is_file(),
        "the bundled layer was not unpacked"
    );
    // GPU-assisted validation: on a GPU only (on lavapipe one frame takes minutes), and the report says so.
    let skipped = report["skipped"].as_array().unwrap();
    if device["cpu"] == true {
        assert!(
            skipped.iter().any(|s| s
                .as_str()
                .unwrap()
                .starts_with("validation_gpu_assisted: not run on a CPU")),
            "{report:#}"
        );
    }
    for s in report["steps"].as_array().unwrap() {
        // A backend probe the device refuses (HRTAO_HIDE_RAY_QUERY=1, an NVIDIA GPU: no ray queries).
        let probe = s["name"].as_str().unwrap().starts_with("devices_")
            && s["status"] == "not offered"
            && !backends
                .iter()
                .any(|b| s["name"] == format!("devices_{}", b.as_str().unwrap()));
        if probe {
            continue;
        }
        assert_eq!(s["status"], "ok", "{s:#}");
        assert!(s["seconds"].as_f64().is_some_and(|t| t > 0.0), "{s:#}");
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

    // A glibc older than the bundle needs: exit status 2 before anything runs, the need named.
    std::fs::write(b.join("glibc-needed"), "9.99\n").unwrap();
    let glibc_dir = dir.join("old-glibc");
    let run = Command::new("bash")
        .arg(b.join("gpu-check.sh"))
        .args(["run", "--small", "--allow-cpu", "--out"])
        .arg(&glibc_dir)
        .env_remove("HRTAO_BIN")
        .output()
        .expect("run gpu-check.sh run");
    let log = text(&run);
    assert_eq!(run.status.code(), Some(2), "{log}");
    assert!(log.contains("missing: glibc >= 9.99"), "{log}");
    let r = self::report(&glibc_dir);
    assert!(r["error"].as_str().unwrap().contains("glibc >= 9.99"), "{r:#}");
    assert!(
        !glibc_dir.join("hrtao.log").exists(),
        "hrtao ran on a glibc too old for it"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_step_made_to_hang_is_killed_at_its_timeout_and_the_report_says_so() {
    if tools_missing() {
        return;
    }
    let dir = tmp_dir("hang");
    // The first render of a backend the device offers (HRTAO_HIDE_RAY_QUERY=1: pipelines only).
    let backend = if hrtao_core::context::ray_query_hidden_by_env() {
        "pipeline"
    } else {
        "query"
    };
    let hang = format!("rtao_{backend}");
    let started = Instant::now();
    // The first render hangs (and ignores SIGTERM); every step has 3 s, the run 20 s.
    let child = Command::new("bash")
        .arg(script())
        .args([
            "run",
            "--small",
            "--allow-cpu",
            "--step-timeout",
            "3",
            "--budget",
            "20",
            "--out",
        ])
        .arg(&dir)
        .env("HRTAO_BIN", env!("CARGO_BIN_EXE_hrtao"))
        .env("HRTAO_GPU_CHECK_HANG_STEP", &hang)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run gpu-check.sh run");
    // While it hangs, the report already holds what was measured before it: a run killed now would leave it.
    let mut seen_running = None;
    while started.elapsed() < Duration::from_secs(60) && seen_running.is_none() {
        std::thread::sleep(Duration::from_millis(200));
        let Ok(text) = std::fs::read_to_string(dir.join("report.json")) else {
            continue;
        };
        let r: serde_json::Value = serde_json::from_str(&text).expect("report.json is whole at every moment");
        let running = r["steps"]
            .as_array()
            .unwrap()
            .iter()
            .any(|s| s["name"] == hang.as_str() && s["status"] == "running");
        if running {
            seen_running = Some(r);
        }
    }
    let during = seen_running.expect("the report never showed the hanging step running");
    assert_eq!(during["complete"], false, "{during:#}");
    assert_eq!(step(&during, "devices")["status"], "ok", "{during:#}");
    assert!(
        during["device"]["name"].as_str().is_some_and(|n| !n.is_empty()),
        "{during:#}"
    );
    assert!(std::fs::read_to_string(dir.join("report.md"))
        .unwrap()
        .contains("INCOMPLETE"));

    let out = child.wait_with_output().unwrap();
    let elapsed = started.elapsed();
    let log = text(&out);
    assert_eq!(out.status.code(), Some(1), "{log}");
    // 3 s, 5 s of ignored SIGTERM, the steps after it within the 20 s budget, and the start: far from a hang.
    assert!(elapsed < Duration::from_secs(60), "{elapsed:?}\n{log}");
    let r = report(&dir);
    assert_eq!(r["complete"], true, "{r:#}");
    assert_eq!(r["passed"], false, "{r:#}");
    let hung = step(&r, &hang);
    assert_eq!(hung["status"], "timeout", "{r:#}");
    assert_eq!(hung["note"], "killed at its timeout of 3 s (SIGKILL)", "{r:#}");
    assert!(
        hung["hang_hook"]
            .as_str()
            .unwrap()
            .contains("HRTAO_GPU_CHECK_HANG_STEP"),
        "{r:#}"
    );
    let seconds = hung["seconds"].as_f64().unwrap();
    assert!((3.0..15.0).contains(&seconds), "{r:#}");
    // The hanging process is gone, not left behind.
    let pid = hung["pid"].as_u64().unwrap();
    assert!(
        !Path::new(&format!("/proc/{pid}")).exists(),
        "the hung step's process {pid} is still there"
    );
    let check = r["checks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == format!("rtao_vs_cycles_{backend}"))
        .unwrap_or_else(|| panic!("{r:#}"));
    assert_eq!(check["passed"], false, "{check:#}");
    assert!(
        check["note"].as_str().unwrap().contains("killed at its timeout"),
        "{check:#}"
    );
    // The budget: no step ran past it; those it left out are listed as not run.
    let steps = r["steps"].as_array().unwrap();
    assert!(
        steps.iter().any(|s| s["status"] == "skipped"
            && s["note"]
                .as_str()
                .unwrap()
                .contains("time budget of 20 s was spent")),
        "{r:#}"
    );
    assert!(steps.iter().all(|s| s["status"] != "running"), "{r:#}");
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        md.contains(&format!("| {hang} | timeout |")) && md.contains("killed at its timeout of 3 s"),
        "{md}"
    );
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
    let report = self::report(&dir);
    assert_eq!(report["passed"], false);
    assert!(
        report["error"].as_str().unwrap().contains("no-such-icd.json"),
        "{report:#}"
    );
    // The device listing again with the loader's debug output, which says why.
    let excerpt = report["loader_debug"]["excerpt"].as_array().unwrap();
    assert!(
        excerpt.iter().any(|l| {
            let l = l.as_str().unwrap();
            l.contains("no-such-icd.json") && l.contains("ERROR")
        }),
        "{report:#}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn nvidia_glx_driver_that_does_not_load_falls_back_to_its_egl_library() {
    if tools_missing() {
        return;
    }
    // A stand-in NVIDIA install: the GLX library its driver file names is absent (as when libX11 is missing, it
    // does not load); the EGL library beside it is lavapipe's driver under NVIDIA's name.
    let lvp = [
        "/usr/share/vulkan/icd.d/lvp_icd.json",
        "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json",
    ]
    .into_iter()
    .find(|f| Path::new(f).is_file());
    let Some(lvp) = lvp else {
        eprintln!("skipping: no lavapipe driver file");
        return;
    };
    let lvp: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(lvp).unwrap()).unwrap();
    // The file names the library bare (found on the linker's path) or by its path.
    let name = lvp["ICD"]["library_path"].as_str().unwrap();
    let Some(lvp_lib) = ["", "/usr/lib/x86_64-linux-gnu", "/usr/lib64", "/usr/lib"]
        .into_iter()
        .map(|d| Path::new(d).join(name))
        .find(|p| p.is_absolute() && p.is_file())
    else {
        eprintln!("skipping: lavapipe's library {name} not found");
        return;
    };
    let dir = tmp_dir("egl");
    let nvidia = dir.join("nvidia");
    std::fs::create_dir_all(&nvidia).unwrap();
    std::os::unix::fs::symlink(lvp_lib, nvidia.join("libEGL_nvidia.so.0")).unwrap();
    let icd = nvidia.join("nvidia_icd.json");
    let glx = nvidia.join("libGLX_nvidia.so.0");
    std::fs::write(
        &icd,
        serde_json::json!({"file_format_version": "1.0.0",
            "ICD": {"library_path": glx, "api_version": "1.3.277"}})
        .to_string(),
    )
    .unwrap();
    let out_dir = dir.join("out");
    // A budget of 8 s: the device steps, then the rest is cut (this test is about the driver).
    let run = Command::new("bash")
        .arg(script())
        .args(["run", "--small", "--allow-cpu", "--budget", "8", "--out"])
        .arg(&out_dir)
        .env("HRTAO_BIN", env!("CARGO_BIN_EXE_hrtao"))
        .env("VK_DRIVER_FILES", &icd)
        .output()
        .expect("run gpu-check.sh run");
    let log = text(&run);
    let r = report(&out_dir);
    let driver = &r["driver"];
    let files = driver["nvidia_icds"].as_array().unwrap();
    assert_eq!(files.len(), 1, "{r:#}");
    assert_eq!(files[0]["loads"], false, "{r:#}");
    assert!(
        files[0]["error"].as_str().unwrap().contains("libGLX_nvidia.so.0"),
        "{r:#}"
    );
    assert_eq!(driver["icd_fallback"], "egl", "{log}\n{r:#}");
    let egl = out_dir.join("nvidia_egl_icd.json");
    assert_eq!(driver["VK_DRIVER_FILES"], egl.to_str().unwrap(), "{r:#}");
    let written: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&egl).unwrap()).unwrap();
    assert_eq!(
        written["ICD"]["library_path"],
        nvidia.join("libEGL_nvidia.so.0").to_str().unwrap()
    );
    assert_eq!(step(&r, "devices")["status"], "failed", "{r:#}");
    assert_eq!(step(&r, "devices_egl")["status"], "ok", "{r:#}");
    assert!(
        r["device"]["name"].as_str().unwrap().contains("llvmpipe"),
        "{r:#}"
    );
    assert!(
        std::fs::read_to_string(out_dir.join("report.md"))
            .unwrap()
            .contains("its EGL library was used"),
        "{log}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_machine_without_python3_is_told_so() {
    // The run needs only bash, dirname and mkdir before it looks for python3: a PATH of those alone.
    let (Some(dirname), Some(mkdir), Some(bash)) = (on_path("dirname"), on_path("mkdir"), on_path("bash"))
    else {
        eprintln!("skipping: dirname, mkdir or bash not found");
        return;
    };
    let dir = tmp_dir("no-python");
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::os::unix::fs::symlink(dirname, bin.join("dirname")).unwrap();
    std::os::unix::fs::symlink(mkdir, bin.join("mkdir")).unwrap();
    let out_dir = dir.join("out");
    let run = Command::new(bash)
        .arg(script())
        .args(["run", "--small", "--out"])
        .arg(&out_dir)
        .env("PATH", &bin)
        .env("HRTAO_BIN", env!("CARGO_BIN_EXE_hrtao"))
        .output()
        .expect("run gpu-check.sh run");
    let log = text(&run);
    assert_eq!(run.status.code(), Some(2), "{log}");
    assert!(log.contains("missing: python3 (3.6 or newer)"), "{log}");
    let r = report(&out_dir);
    assert!(
        r["error"].as_str().unwrap().starts_with("missing: python3"),
        "{r:#}"
    );
    assert_eq!(r["passed"], false);
    let _ = std::fs::remove_dir_all(dir);
}
