//! Every file of the hostile corpus through `hrtao render`: a clear error naming the file (exit 1) or a correct
//! image (exit 0, finite AO), never a panic, a hang or an abort. Files whose references lead to devices, FIFOs,
//! directories or outside the model's folder end within seconds under 1 GB of memory, naming the reference, in
//! `render` and in the running viewer (which keeps its scene).
/// The test data helpers of the scene crate's tests (`testdata/`), shared rather than copied.
#[path = "../../scene/tests/common/mod.rs"]
mod common;

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use hrtao_scene::hostile::{write_corpus, Expect};

/// How a bounded child run ended.
struct Run {
    code: Option<i32>,
    stderr: String,
    took: Duration,
    /// Peak resident memory of the child (wait4 rusage), bytes.
    peak_rss: u64,
}

/// Runs `cmd` (stderr captured), killing it after `limit`; the exit status and peak RSS come from wait4.
// The child is reaped by `wait4` (which also gives its rusage), not by `Child::wait`.
#[allow(clippy::zombie_processes)]
fn run_bounded(cmd: &mut Command, limit: Duration, what: &str) -> Run {
    let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let mut pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut pipe, &mut s);
        s
    });
    let pid = child.id() as libc::pid_t;
    let start = Instant::now();
    let (status, usage) = loop {
        let mut status = 0;
        // SAFETY: plain syscall on our own child with out-pointers to locals.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break (status, usage);
        }
        assert!(
            r == 0,
            "{what}: wait4 failed: {}",
            std::io::Error::last_os_error()
        );
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: hrtao did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let took = start.elapsed();
    Run {
        code: libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status)),
        stderr: reader.join().unwrap(),
        took,
        peak_rss: usage.ru_maxrss as u64 * 1024,
    }
}

fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

#[test]
fn hostile_files_give_errors_or_images() {
    let dir = std::env::temp_dir().join(format!("hrtao-hostile-{}", std::process::id()));
    let cases = write_corpus(&dir).unwrap();
    assert!(cases.len() >= 30, "corpus of {} files", cases.len());
    let (mut errors, mut images) = (0, 0);
    let mut table = Vec::new();
    for case in &cases {
        // The loader alone agrees with the expectation.
        let loaded = hrtao_scene::load(case.path.to_str().unwrap(), &mut |_| {});
        assert_eq!(
            loaded.is_ok(),
            case.expect == Expect::Image,
            "{}: loader gave {:?}",
            case.name,
            loaded.err()
        );

        let ao = dir.join(format!("{}.pfm", case.name));
        let run = run_bounded(
            Command::new(env!("CARGO_BIN_EXE_hrtao"))
                .args([
                    "render",
                    "--scene",
                    case.path.to_str().unwrap(),
                    "--width",
                    "48",
                    "--height",
                    "27",
                    "--rays",
                    "2",
                ])
                .args(["--ao-out", ao.to_str().unwrap()])
                .env("HRTAO_VALIDATION", "1"),
            Duration::from_secs(120),
            case.name,
        );
        let stderr = &run.stderr;
        assert!(!stderr.contains("panicked"), "{}: panic\n{stderr}", case.name);
        assert!(
            run.peak_rss < 1 << 30,
            "{}: peak RSS {:.0} MiB",
            case.name,
            mib(run.peak_rss)
        );
        match case.expect {
            Expect::Error => {
                assert_eq!(
                    run.code,
                    Some(1),
                    "{}: expected a clean error exit\n{stderr}",
                    case.name
                );
                let file_name = case.path.file_name().unwrap().to_str().unwrap();
                assert!(
                    stderr.contains(file_name),
                    "{}: the message names the file\n{stderr}",
                    case.name
                );
                if let Some(r) = case.reference {
                    assert!(
                        stderr.contains(r),
                        "{}: the message names the reference `{r}`\n{stderr}",
                        case.name
                    );
                }
                // Errors come from the loader, before any GPU work: no acceleration structure was built.
                assert!(
                    !stderr.contains("acceleration structures"),
                    "{}: the error came after the scene's GPU build\n{stderr}",
                    case.name
                );
                errors += 1;
            }
            Expect::Image => {
                assert_eq!(run.code, Some(0), "{}: expected an image\n{stderr}", case.name);
                let (_, _, data) = hrtao_core::imageio::read_pfm(&ao).unwrap();
                assert!(
                    data.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
                    "{}: AO out of range",
                    case.name
                );
                assert!(
                    !stderr.contains("validation layer reported"),
                    "{}: validation messages\n{stderr}",
                    case.name
                );
                images += 1;
            }
        }
        table.push(format!(
            "{:45} {:>5} {:>8.0} ms {:>7.1} MiB",
            case.name,
            if case.expect == Expect::Error {
                "error"
            } else {
                "image"
            },
            run.took.as_secs_f64() * 1e3,
            mib(run.peak_rss)
        ));
    }
    println!("{}", table.join("\n"));
    println!(
        "{} hostile files: {errors} clear errors, {images} correct images",
        cases.len()
    );
}

/// A real assembly as .gltf + external .bin (the rod, its GLB split) still renders through the guard.
#[test]
fn external_buffer_renders() {
    let dir = std::env::temp_dir().join(format!("hrtao-external-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let gltf = common::split_glb(&common::test_scene("rod"), &dir, "rod_external");
    let ao = dir.join("rod_external.pfm");
    let run = run_bounded(
        Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .args(["render", "--scene", gltf.to_str().unwrap()])
            .args(["--width", "64", "--height", "36", "--rays", "2"])
            .args(["--ao-out", ao.to_str().unwrap()])
            .env("HRTAO_VALIDATION", "1"),
        Duration::from_secs(300),
        "rod_external",
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let (w, h, data) = hrtao_core::imageio::read_pfm(&ao).unwrap();
    assert_eq!((w, h), (64, 36));
    let min = data.iter().cloned().fold(1.0f32, f32::min);
    assert!(min < 0.9, "the rod is drawn with AO (min {min})");
    let _ = std::fs::remove_dir_all(dir);
}

/// Files pointing at devices and FIFOs opened in the running viewer: the error names the reference, the
/// viewer keeps its scene and exits 0, within seconds and under 1 GB.
#[test]
fn viewer_keeps_its_scene_when_a_reference_leads_nowhere() {
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        eprintln!("skipped: no DISPLAY (the test command runs under xvfb-run)");
        return;
    }
    let dir = std::env::temp_dir().join(format!("hrtao-hostile-view-{}", std::process::id()));
    let cases = write_corpus(&dir).unwrap();
    let pick = [
        "buffer_dev_zero",
        "buffer_fifo",
        "buffer_symlink_to_dev_zero",
        "obj_mtllib_fifo",
        "model_is_a_fifo",
    ];
    for case in cases.iter().filter(|c| pick.contains(&c.name)) {
        let run = run_bounded(
            Command::new(env!("CARGO_BIN_EXE_hrtao"))
                .args([
                    "view",
                    "gen:box",
                    "--size",
                    "320x200",
                    "--no-panel",
                    "--frames",
                    "3",
                ])
                .args(["--open-at-frame", "1"])
                .arg(&case.path)
                .args(["--no-config", "--exit"])
                .env("HRTAO_VALIDATION", "1")
                .env("HRTAO_FRAMES_IN_FLIGHT", "2"),
            Duration::from_secs(180),
            case.name,
        );
        let err = &run.stderr;
        assert!(!err.contains("panicked"), "{}: panic\n{err}", case.name);
        assert_eq!(
            run.code,
            Some(0),
            "{}: the viewer goes on with gen:box\n{err}",
            case.name
        );
        assert!(
            err.contains("cannot open"),
            "{}: the load error is reported\n{err}",
            case.name
        );
        if let Some(r) = case.reference {
            assert!(err.contains(r), "{}: names `{r}`\n{err}", case.name);
        }
        assert!(
            run.peak_rss < 1 << 30,
            "{}: {:.0} MiB",
            case.name,
            mib(run.peak_rss)
        );
        println!(
            "viewer {:35} {:>8.0} ms {:>7.1} MiB",
            case.name,
            run.took.as_secs_f64() * 1e3,
            mib(run.peak_rss)
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}
