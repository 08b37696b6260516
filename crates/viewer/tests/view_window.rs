//! The interactive viewer in its real window (Xvfb + lavapipe in CI): scripted runs open the bundled scene,
//! render a few frames, save screenshots and exit 0 (non-zero if the validation layer reported anything).
use std::path::{Path, PathBuf};
use std::process::Command;

fn display_available() -> bool {
    let ok = std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if !ok {
        eprintln!("skipping: no DISPLAY (run the tests under `xvfb-run -a`)");
    }
    ok
}

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-view-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run_viewer(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .arg("view")
        .args(args)
        .args(["--no-config", "--exit"])
        .env("HRTAO_VALIDATION", "1")
        .output()
        .expect("run hrtao view");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "hrtao view failed ({}):\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("[vulkan"), "validation messages:\n{stderr}");
}

/// Loads a PNG and checks it is not blank and has AO shading (grey-level variance).
fn check_image(path: &Path, w: u32, h: u32) {
    let img = image::open(path).expect("screenshot PNG").to_luma8();
    assert_eq!((img.width(), img.height()), (w, h), "{}", path.display());
    let px: Vec<f64> = img.pixels().map(|p| p.0[0] as f64).collect();
    let mean = px.iter().sum::<f64>() / px.len() as f64;
    let var = px.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / px.len() as f64;
    let distinct = {
        let mut seen = [false; 256];
        for v in &px {
            seen[*v as usize] = true;
        }
        seen.iter().filter(|s| **s).count()
    };
    assert!(
        var > 50.0,
        "{}: variance {var:.1} (mean {mean:.1}): blank image?",
        path.display()
    );
    assert!(
        distinct > 32,
        "{}: only {distinct} grey levels: no shading?",
        path.display()
    );
}

#[test]
fn scripted_run_renders_and_saves_a_screenshot() {
    if !display_available() {
        return;
    }
    let dir = out_dir("shot");
    let shot = dir.join("view.png");
    let ui = dir.join("window.png");
    run_viewer(&[
        "--size",
        "480x270",
        "--no-panel",
        "--frames",
        "4",
        "--screenshot",
        shot.to_str().unwrap(),
        "--screenshot-ui",
        ui.to_str().unwrap(),
    ]);
    check_image(&shot, 480, 270);
    check_image(&ui, 480, 270);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn scripted_run_survives_a_resize() {
    if !display_available() {
        return;
    }
    let dir = out_dir("resize");
    let shot = dir.join("view.png");
    run_viewer(&[
        "--size",
        "400x240",
        "--no-panel",
        "--frames",
        "5",
        "--resize-at-frame",
        "2",
        "320x300",
        "--screenshot",
        shot.to_str().unwrap(),
        "--screenshot-frames",
        "2",
    ]);
    // The screenshot is taken at the new window size.
    check_image(&shot, 320, 300);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_file_fails_cleanly_in_scripted_mode() {
    if !display_available() {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args([
            "view",
            "/nonexistent/model.glb",
            "--size",
            "200x150",
            "--frames",
            "2",
        ])
        .args(["--no-config", "--exit"])
        .output()
        .expect("run hrtao view");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a missing file must fail the scripted run");
    assert!(stderr.contains("nonexistent"), "{stderr}");
}

/// A user opening a broken file keeps the model they had: the load error is shown, the old scene stays on
/// screen, nothing panics. Representative files of the hostile corpus (crates/scene/src/hostile.rs).
#[test]
fn hostile_files_opened_in_the_viewer_keep_the_previous_scene() {
    if !display_available() {
        eprintln!("skipped: no DISPLAY (the test command runs under xvfb-run)");
        return;
    }
    let dir = out_dir("hostile");
    let cases = hrtao_scene::hostile::write_corpus(&dir.join("corpus")).unwrap();
    let pick = [
        "truncated_glb",
        "json_garbage",
        "nan_position",
        "cyclic_nodes",
        "buffer_claims_gigabytes",
        "obj_bad_index",
    ];
    for case in cases.iter().filter(|c| pick.contains(&c.name)) {
        let shot = dir.join(format!("{}.png", case.name));
        let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .args([
                "view",
                "--size",
                "320x200",
                "--no-panel",
                "--frames",
                "3",
                "--open-at-frame",
                "1",
            ])
            .arg(&case.path)
            .arg("--screenshot")
            .arg(&shot)
            .args(["--no-config", "--exit"])
            .env("HRTAO_VALIDATION", "1")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{}: panic\n{err}", case.name);
        assert!(
            out.status.success(),
            "{}: the viewer must go on with the old scene\n{err}",
            case.name
        );
        assert!(
            err.contains("cannot open"),
            "{}: the load error is reported\n{err}",
            case.name
        );
        check_image(&shot, 320, 200);
    }
}

/// Screenshots to an unwritable place or a full disk give an error message and a clean exit status.
#[test]
fn screenshot_to_unwritable_or_full_destination_fails_cleanly() {
    if !display_available() {
        eprintln!("skipped: no DISPLAY (the test command runs under xvfb-run)");
        return;
    }
    // (The tests run as root, so "unwritable" is a path under a regular file.)
    for dest in ["/dev/null/shot.png", "/dev/full"] {
        let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .args([
                "view",
                "--size",
                "240x160",
                "--no-panel",
                "--frames",
                "2",
                "--screenshot",
                dest,
            ])
            .args(["--no-config", "--exit"])
            .env("HRTAO_VALIDATION", "1")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{dest}: panic\n{err}");
        assert_eq!(out.status.code(), Some(1), "{dest}: exit 1\n{err}");
        assert!(err.contains("screenshot failed"), "{dest}: message\n{err}");
    }
}

/// A viewer started in the background (interactive, not scripted), its log collected line by line; killed when
/// dropped.
/// Tests that send X input (focus, keys) or measure an idle viewer share one display: they run one at a time,
/// so one test's focus changes and key events never reach another test's window.
static X_INPUT: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn x_input_lock() -> std::sync::MutexGuard<'static, ()> {
    X_INPUT.lock().unwrap_or_else(|e| e.into_inner())
}

struct Running {
    child: std::process::Child,
    log: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
}

impl Running {
    fn start(args: &[&str], cwd: &Path) -> Running {
        use std::io::BufRead;
        let mut child = Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .arg("view")
            .args(args)
            .arg("--no-config")
            .current_dir(cwd)
            .env("HRTAO_VALIDATION", "1")
            .env("RUST_LOG", "info")
            .stderr(std::process::Stdio::piped())
            .stdout(std::process::Stdio::null())
            .spawn()
            .expect("start hrtao view");
        let log = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let stderr = child.stderr.take().unwrap();
        let sink = log.clone();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines().map_while(Result::ok) {
                sink.lock().unwrap().push(line);
            }
        });
        Running { child, log }
    }

    fn log_text(&self) -> String {
        self.log.lock().unwrap().join("\n")
    }

    /// Waits until `count` log lines contain `needle`.
    fn wait_for(&mut self, needle: &str, count: usize, timeout: std::time::Duration) {
        let t0 = std::time::Instant::now();
        loop {
            let n = self
                .log
                .lock()
                .unwrap()
                .iter()
                .filter(|l| l.contains(needle))
                .count();
            if n >= count {
                return;
            }
            if let Ok(Some(status)) = self.child.try_wait() {
                panic!(
                    "the viewer exited ({status}) before `{needle}`:\n{}",
                    self.log_text()
                );
            }
            assert!(
                t0.elapsed() < timeout,
                "no `{needle}` (×{count}) within {timeout:?}:\n{}",
                self.log_text()
            );
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
    }

    /// User + system CPU time of the process so far, in seconds (/proc/PID/stat fields 14 and 15).
    fn cpu_seconds(&self) -> f64 {
        let stat = std::fs::read_to_string(format!("/proc/{}/stat", self.child.id())).unwrap();
        // The command name (field 2) is in parentheses and may contain spaces: split after it.
        let rest = &stat[stat.rfind(')').unwrap() + 2..];
        let f: Vec<&str> = rest.split_whitespace().collect();
        let ticks: u64 = f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap();
        ticks as f64 / clock_ticks_per_second()
    }

    fn validation_clean(&self) {
        let log = self.log_text();
        assert!(!log.contains("[vulkan"), "validation messages:\n{log}");
        assert!(!log.contains("panicked"), "panic:\n{log}");
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn clock_ticks_per_second() -> f64 {
    Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .ok()
        .and_then(|o| String::from_utf8_lossy(&o.stdout).trim().parse().ok())
        .unwrap_or(100.0)
}

/// Left alone, the viewer refines the image until it has converged at full resolution and then waits for events:
/// ≤ 5 % of one core over the next 10 s (it used two full cores before).
#[test]
fn a_viewer_left_alone_rests() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("rest");
    let mut v = Running::start(&["--size", "320x200", "--no-panel"], &dir);
    v.wait_for("at rest", 1, std::time::Duration::from_secs(90));
    let log = v.log_text();
    assert!(log.contains("converged"), "{log}");
    // The "opened" toast expires 4 s after the load: one more frame; measure after it.
    std::thread::sleep(std::time::Duration::from_secs(5));
    let (c0, t0) = (v.cpu_seconds(), std::time::Instant::now());
    std::thread::sleep(std::time::Duration::from_secs(10));
    let cpu = 100.0 * (v.cpu_seconds() - c0) / t0.elapsed().as_secs_f64();
    eprintln!("CPU at rest: {cpu:.2} % of one core");
    assert!(cpu <= 5.0, "{cpu:.1} % of one core at rest\n{}", v.log_text());
    v.validation_clean();
    let _ = std::fs::remove_dir_all(&dir);
}

fn xdotool(args: &[&str]) -> String {
    let out = Command::new("xdotool").args(args).output().expect("xdotool");
    assert!(
        out.status.success(),
        "xdotool {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// PNG widths of the screenshots in `dir`, oldest first, once there are `count` of them.
fn wait_for_screenshots(dir: &Path, count: usize, v: &mut Running) -> Vec<u32> {
    let t0 = std::time::Instant::now();
    loop {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default();
        files.retain(|p| p.extension().is_some_and(|e| e == "png"));
        if files.len() >= count {
            files.sort();
            // The PNG is written in one go after rendering; a partly written file fails to decode: retry.
            let widths: Option<Vec<u32>> = files
                .iter()
                .map(|f| image::image_dimensions(f).ok().map(|d| d.0))
                .collect();
            if let Some(w) = widths {
                return w;
            }
        }
        assert!(
            t0.elapsed() < std::time::Duration::from_secs(60),
            "{} of {count} screenshots after 60 s\n{}",
            files.len(),
            v.log_text()
        );
        if let Ok(Some(status)) = v.child.try_wait() {
            panic!("the viewer exited ({status}):\n{}", v.log_text());
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
}

/// Real X key events (xdotool: press and release at once, as a quick tap): F12 saves a screenshot of the 3D view,
/// Tab hides the panel (the screenshot then spans the whole window) and shows it again, whether the viewer is
/// busy refining or at rest, and Tab never leaves a panel widget with the focus that would swallow later keys.
#[test]
fn tab_and_quick_f12_taps_work_with_real_x_events() {
    if !display_available() {
        return;
    }
    assert!(
        Command::new("xdotool").arg("version").output().is_ok(),
        "xdotool is missing: scripts/install-deps.sh installs it"
    );
    let _x = x_input_lock();
    let dir = out_dir("keys");
    let shots = dir.join("screenshots");
    let mut v = Running::start(&["--size", "560x300"], &dir);
    v.wait_for("opened", 1, std::time::Duration::from_secs(60));
    let pid = v.child.id().to_string();
    let window = xdotool(&["search", "--sync", "--onlyvisible", "--pid", &pid]);
    let window = window
        .lines()
        .next()
        .expect("the viewer's window")
        .trim()
        .to_string();
    xdotool(&["windowfocus", "--sync", &window]);
    // While the image is still refining (frames keep coming): Tab, then a quick F12.
    xdotool(&["key", "Tab"]);
    xdotool(&["key", "F12"]);
    let widths = wait_for_screenshots(&shots, 1, &mut v);
    assert_eq!(widths, [560], "panel hidden: the 3D view spans the window");
    // At rest (the loop waits for events): Tab shows the panel again, F12 still acts.
    v.wait_for("at rest", 1, std::time::Duration::from_secs(90));
    xdotool(&["key", "Tab"]);
    xdotool(&["key", "F12"]);
    let widths = wait_for_screenshots(&shots, 2, &mut v);
    assert!(widths[1] < 560, "panel shown again: {widths:?}");
    // A Tab and F12 tapped together (one frame sees both) act together.
    xdotool(&["key", "--delay", "5", "Tab", "F12"]);
    let widths = wait_for_screenshots(&shots, 3, &mut v);
    assert_eq!(widths[2], 560, "{widths:?}");
    v.validation_clean();
    drop(v);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--orbit N --stats FILE`: N moving frames at the reduced scale (never below 0.35 of the view), then still frames
/// until the image has converged, the last one at the full view size.
#[test]
fn scripted_orbit_writes_stats_and_ends_at_full_resolution() {
    if !display_available() {
        return;
    }
    let dir = out_dir("orbit");
    let stats = dir.join("orbit.json");
    run_viewer(&[
        "--size",
        "320x200",
        "--no-panel",
        "--orbit",
        "3",
        "--stats",
        stats.to_str().unwrap(),
    ]);
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let frames = json["frames"].as_array().expect("frames");
    let size = |f: &serde_json::Value, k: &str| -> (u64, u64) {
        (f[k][0].as_u64().unwrap(), f[k][1].as_u64().unwrap())
    };
    let moving: Vec<_> = frames.iter().filter(|f| f["moving"] == true).collect();
    // The first frame (a new camera) and the three orbit steps.
    assert_eq!(moving.len(), 4, "{json}");
    // A software device starts moving at 0.35 of the view (a GPU at full size).
    let software = json["device"].as_str().unwrap_or("").contains("llvmpipe");
    for f in &moving {
        let ((iw, ih), (vw, vh)) = (size(f, "internal"), size(f, "view"));
        assert!(iw <= vw && ih <= vh, "{f}");
        assert!(
            !software || (iw < vw && ih < vh),
            "moving frames at a reduced scale: {f}"
        );
        assert!(iw as f64 >= 0.35 * vw as f64 - 1.0, "not below 0.35: {f}");
        assert!(f["wall_ms"].as_f64().unwrap() > 0.0);
    }
    let last = frames.last().unwrap();
    assert_eq!(last["moving"], false);
    assert_eq!(
        size(last, "internal"),
        size(last, "view"),
        "still frame at full size"
    );
    assert_eq!(size(last, "view"), (320, 200));
    assert!(json["median_moving_wall_ms"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A screenshot larger than the window renders in the background (tiles, each until converged) while the window
/// keeps drawing: the PNG has the asked size and AO shading, and the window drew a frame per slice meanwhile.
/// A shot that cannot be written fails with a message and exit status 1.
#[test]
fn a_big_screenshot_renders_in_the_background_while_the_window_draws() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("background-shot");
    let shot = dir.join("big.png");
    let stats = dir.join("stats.json");
    let t0 = std::time::Instant::now();
    run_viewer(&[
        "--size",
        "240x150",
        "--no-panel",
        "--frames",
        "2",
        "--screenshot",
        shot.to_str().unwrap(),
        "--screenshot-size",
        "280x180",
        "--stats",
        stats.to_str().unwrap(),
    ]);
    println!("background screenshot run: {:.1} s", t0.elapsed().as_secs_f64());
    check_image(&shot, 280, 180);
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let s = &json["screenshot"];
    println!("{s}");
    let tiles = s["tiles"].as_u64().unwrap();
    assert!(
        tiles >= 2,
        "bigger than a viewer frame's work: several tiles\n{s}"
    );
    assert_eq!(s["unconverged_tiles"], 0, "every tile converged\n{s}");
    assert_eq!(s["failed_inserts"], 0, "{s}");
    // A tile converges once anti-aliased (AA_FRAMES = 16 frames at least); the window drew (and rendered) one
    // frame per slice.
    let shot_frames = s["frames"].as_u64().unwrap();
    assert!(shot_frames >= 16 * tiles, "{s}");
    assert!(s["viewer_frames"].as_u64().unwrap() >= shot_frames, "{s}");
    assert!(s["viewer_rendered"].as_u64().unwrap() >= shot_frames, "{s}");
    let frames = json["frames"].as_array().unwrap().len() as u64;
    assert!(frames >= shot_frames + 2, "{frames} frames in the log");

    // An unwritable folder fails at once; a full disk once the image is rendered (on the writer thread).
    for (dest, size) in [("/dev/null/big.png", "3840x2160"), ("/dev/full", "64x40")] {
        let t0 = std::time::Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .args(["view", "--size", "160x100", "--no-panel", "--frames", "1"])
            .args(["--screenshot", dest, "--screenshot-size", size])
            .args(["--no-config", "--exit"])
            .env("HRTAO_VALIDATION", "1")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        println!("{dest}: failed in {:.1} s", t0.elapsed().as_secs_f64());
        assert!(!err.contains("panicked"), "{dest}: panic\n{err}");
        assert_eq!(out.status.code(), Some(1), "{dest}: exit 1\n{err}");
        assert!(err.contains("screenshot failed"), "{dest}: message\n{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
