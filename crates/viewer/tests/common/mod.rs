//! What the window tests share: the display check, output folders, xdotool, the X input lock and a viewer
//! running in the background with its log collected, screenshots and a box model to look at.
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../../../scene/tests/common/mod.rs"]
pub mod scene_common;

/// Window tests run with two frames in flight (`HRTAO_FRAMES_IN_FLIGHT`; a software device's default is one),
/// so that lavapipe and the validation layer exercise the frames' overlap.
pub const FRAMES_IN_FLIGHT: &str = "2";

pub fn display_available() -> bool {
    let ok = std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if !ok {
        eprintln!("skipping: no DISPLAY (run the tests under `xvfb-run -a`)");
    }
    ok
}

pub fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-view-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn xdotool(args: &[&str]) -> String {
    let out = Command::new("xdotool").args(args).output().expect("xdotool");
    assert!(
        out.status.success(),
        "xdotool {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A viewer started in the background (interactive, not scripted), its log collected line by line; killed when
/// dropped.
/// The tests of a binary share one display. Tests that send X input (focus, keys, the pointer) or measure an
/// idle viewer hold it alone (`x_input_lock`), so one test's focus changes and key events never reach another
/// test's window; tests that only open windows hold it shared (`display_lock`, taken by `Running` itself), so no
/// window of theirs maps over an input test's window while it takes the pointer (a drag that went to another
/// test's window moved nothing in its own).
pub static X_DISPLAY: std::sync::RwLock<()> = std::sync::RwLock::new(());

thread_local! {
    /// This test's thread holds the display, alone or shared (a test's helpers may ask again: a second shared
    /// hold behind a waiting writer would deadlock).
    static HOLDS_X_DISPLAY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The display held by this thread (see `X_DISPLAY`); released when dropped.
pub enum DisplayGuard {
    Alone(#[allow(dead_code)] std::sync::RwLockWriteGuard<'static, ()>),
    Shared(#[allow(dead_code)] std::sync::RwLockReadGuard<'static, ()>),
}

impl Drop for DisplayGuard {
    fn drop(&mut self) {
        HOLDS_X_DISPLAY.with(|h| h.set(false));
    }
}

/// The display held alone, for X input (see `X_DISPLAY`).
pub fn x_input_lock() -> DisplayGuard {
    assert!(
        !HOLDS_X_DISPLAY.with(|h| h.get()),
        "x_input_lock while this test holds the display"
    );
    let guard = X_DISPLAY.write().unwrap_or_else(|e| e.into_inner());
    HOLDS_X_DISPLAY.with(|h| h.set(true));
    DisplayGuard::Alone(guard)
}

/// The display held shared, for a test that opens windows without input (None where this thread holds it
/// already).
pub fn display_lock() -> Option<DisplayGuard> {
    if HOLDS_X_DISPLAY.with(|h| h.get()) {
        return None;
    }
    let guard = X_DISPLAY.read().unwrap_or_else(|e| e.into_inner());
    HOLDS_X_DISPLAY.with(|h| h.set(true));
    Some(DisplayGuard::Shared(guard))
}

/// `hrtao view ARGS --no-config --exit` (a scripted run) with the validation layer and `env`, the display held
/// shared while it runs.
pub fn scripted_view(args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    let _display = display_lock();
    Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .arg("view")
        .args(args)
        .args(["--no-config", "--exit"])
        .env("HRTAO_VALIDATION", "1")
        .envs(env.iter().copied())
        .output()
        .expect("run hrtao view")
}

/// A scripted run (`scripted_view`) that succeeds without validation messages: its log.
pub fn scripted_run(args: &[&str], env: &[(&str, &str)]) -> String {
    let out = scripted_view(args, env);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "hrtao view failed ({}):\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("[vulkan"), "validation messages:\n{stderr}");
    stderr
}

pub struct Running {
    pub child: std::process::Child,
    pub log: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
    /// Released after the viewer is killed (`Drop`).
    _display: Option<DisplayGuard>,
}

impl Running {
    pub fn start(args: &[&str], cwd: &Path) -> Running {
        Self::start_with(args, cwd, &[])
    }

    /// `start` with environment variables set (Some) or removed (None). F12 saves into `cwd/screenshots` (the
    /// pictures directory) unless `env` names another.
    pub fn start_with(args: &[&str], cwd: &Path, env: &[(&str, Option<&str>)]) -> Running {
        let pictures = cwd.join("screenshots");
        let mut env = env.to_vec();
        if !env.iter().any(|(k, _)| *k == "XDG_PICTURES_DIR") {
            env.push(("XDG_PICTURES_DIR", pictures.to_str()));
        }
        Self::launch(&[&["view"], args].concat(), cwd, &env)
    }

    /// `hrtao ARGS --no-config` (unless ARGS name a `--config` file) in `cwd` with `env` changed, its log
    /// captured.
    pub fn launch(args: &[&str], cwd: &Path, env: &[(&str, Option<&str>)]) -> Running {
        use std::io::BufRead;
        let display = display_lock();
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_hrtao"));
        cmd.args(args);
        if !args.contains(&"--config") {
            cmd.arg("--no-config");
        }
        cmd.current_dir(cwd)
            .env("HRTAO_VALIDATION", "1")
            .env("HRTAO_FRAMES_IN_FLIGHT", FRAMES_IN_FLIGHT)
            .env("RUST_LOG", "info")
            .stderr(std::process::Stdio::piped())
            .stdout(std::process::Stdio::null());
        for (k, v) in env {
            match v {
                Some(v) => cmd.env(k, v),
                None => cmd.env_remove(k),
            };
        }
        let mut child = cmd.spawn().expect("start hrtao view");
        let log = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let stderr = child.stderr.take().unwrap();
        let sink = log.clone();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines().map_while(Result::ok) {
                sink.lock().unwrap().push(line);
            }
        });
        Running {
            child,
            log,
            _display: display,
        }
    }

    pub fn log_text(&self) -> String {
        self.log.lock().unwrap().join("\n")
    }

    /// Waits until `count` log lines contain `needle`.
    pub fn wait_for(&mut self, needle: &str, count: usize, timeout: std::time::Duration) {
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

    /// The centre of the panel control `name` in window pixels, as the viewer last logged it (`HRTAO_UI_PROBE`:
    /// `ui probe: NAME at X,Y WxH`), waiting up to 30 s for a first one.
    pub fn probed(&mut self, name: &str) -> (i32, i32) {
        let needle = format!("ui probe: {name} at ");
        self.wait_for(&needle, 1, std::time::Duration::from_secs(30));
        let log = self.log_text();
        let line = log.lines().rev().find(|l| l.contains(&needle)).unwrap();
        let at = line
            .split(&needle)
            .nth(1)
            .unwrap()
            .split_whitespace()
            .next()
            .unwrap();
        let (x, y) = at.split_once(',').unwrap();
        (x.parse().unwrap(), y.parse().unwrap())
    }

    /// Log lines containing `needle` so far.
    pub fn seen(&self, needle: &str) -> usize {
        self.log
            .lock()
            .unwrap()
            .iter()
            .filter(|l| l.contains(needle))
            .count()
    }

    /// Clicks at window pixel (x, y) until `count` log lines contain `needle`: at most 3 clicks, 20 s each.
    /// (Under heavy load a click on the busy viewer is sometimes not registered; see the issue notes.)
    pub fn click_until(&mut self, window: &str, at: (i32, i32), needle: &str, count: usize) {
        self.click_with_until(window, at, None, needle, count)
    }

    /// `click_until` with a modifier key (xdotool's name, e.g. "shift") held during the click.
    pub fn click_with_until(
        &mut self,
        window: &str,
        (x, y): (i32, i32),
        modifier: Option<&str>,
        needle: &str,
        count: usize,
    ) {
        for attempt in 0..3 {
            xdotool(&[
                "mousemove",
                "--window",
                window,
                "--sync",
                &x.to_string(),
                &y.to_string(),
            ]);
            std::thread::sleep(std::time::Duration::from_millis(200));
            if let Some(m) = modifier {
                // Held over a frame or two of the viewer, as a hand would.
                xdotool(&["keydown", m]);
                std::thread::sleep(std::time::Duration::from_millis(150));
            }
            xdotool(&["click", "1"]);
            if let Some(m) = modifier {
                std::thread::sleep(std::time::Duration::from_millis(150));
                xdotool(&["keyup", m]);
            }
            let t0 = std::time::Instant::now();
            while t0.elapsed() < std::time::Duration::from_secs(20) {
                if self.seen(needle) >= count {
                    if attempt > 0 {
                        eprintln!("`{needle}` after {} clicks", attempt + 1);
                    }
                    // Apart enough from the next click not to make a double click (which sets the pivot).
                    std::thread::sleep(std::time::Duration::from_millis(700));
                    return;
                }
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
        }
        panic!("no `{needle}` (×{count}) after 3 clicks:\n{}", self.log_text());
    }

    /// Finds the viewer's window (by its pid), gives it the keyboard focus and returns its id.
    pub fn focus_window(&self) -> String {
        let pid = self.child.id().to_string();
        let window = xdotool(&["search", "--sync", "--onlyvisible", "--pid", &pid])
            .lines()
            .next()
            .expect("the viewer's window")
            .trim()
            .to_string();
        xdotool(&["windowfocus", "--sync", &window]);
        window
    }

    /// User + system CPU time of the process so far, in seconds (/proc/PID/stat fields 14 and 15).
    pub fn cpu_seconds(&self) -> f64 {
        let stat = std::fs::read_to_string(format!("/proc/{}/stat", self.child.id())).unwrap();
        // The command name (field 2) is in parentheses and may contain spaces: split after it.
        let rest = &stat[stat.rfind(')').unwrap() + 2..];
        let f: Vec<&str> = rest.split_whitespace().collect();
        let ticks: u64 = f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap();
        ticks as f64 / clock_ticks_per_second()
    }

    /// Waits for the viewer to exit by itself (killed after `timeout`).
    pub fn wait_exit(&mut self, timeout: std::time::Duration) -> std::process::ExitStatus {
        let t0 = std::time::Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                return status;
            }
            if t0.elapsed() > timeout {
                let _ = self.child.kill();
                panic!("no exit within {timeout:?}:\n{}", self.log_text());
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
    }

    pub fn validation_clean(&self) {
        let log = self.log_text();
        assert!(!log.contains("[vulkan"), "validation messages:\n{log}");
        assert!(!log.contains("panicked"), "panic:\n{log}");
    }

    /// The end of a test: the log is validation-clean, the viewer is killed and its folder `dir` removed.
    pub fn finish(self, dir: &Path) {
        self.validation_clean();
        drop(self);
        let _ = std::fs::remove_dir_all(dir);
    }

    /// The first log line containing `needle` (which a `wait_for` saw).
    pub fn log_line(&self, needle: &str) -> String {
        let log = self.log_text();
        let line = log.lines().find(|l| l.contains(needle));
        line.unwrap_or_else(|| panic!("no `{needle}` in the log:\n{log}"))
            .to_string()
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub fn clock_ticks_per_second() -> f64 {
    Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .ok()
        .and_then(|o| String::from_utf8_lossy(&o.stdout).trim().parse().ok())
        .unwrap_or(100.0)
}

/// PNG widths of the screenshots in `dir`, oldest first, once there are `count` of them.
pub fn wait_for_screenshots(dir: &Path, count: usize, v: &mut Running) -> Vec<u32> {
    let t0 = std::time::Instant::now();
    loop {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default();
        files.retain(|p| p.extension().is_some_and(|e| e == "png"));
        if files.len() >= count {
            // Oldest first (names share the second: `MODEL-…-SS.png`, then `-2`, `-3`).
            files.sort_by_key(|f| std::fs::metadata(f).and_then(|m| m.modified()).ok());
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

/// `hrtao render ARGS --ao-out PFM` with the validation layer, asserted successful (`what` names the run in the
/// message otherwise): the linear AO image it wrote.
pub fn render_ao_image(args: &[&str], pfm: &Path, what: &str) -> Vec<f32> {
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .arg("render")
        .args(args)
        .arg("--ao-out")
        .arg(pfm)
        .env("HRTAO_VALIDATION", "1")
        .output()
        .expect("run hrtao");
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    hrtao_core::imageio::read_pfm(pfm).unwrap().2
}

/// `hrtao render --mode rtao` of `scene` from `camera` (`rays` per pixel over `frames` frames, AO radius `radius`)
/// into `dir`: the linear AO image.
pub fn render_rtao(
    scene: &Path,
    camera: &Path,
    radius: f32,
    (rays, frames): (u32, u32),
    dir: &Path,
) -> Vec<f32> {
    let pfm = dir.join(format!("{}.pfm", scene.file_name().unwrap().to_string_lossy()));
    let (rays, frames, radius) = (rays.to_string(), frames.to_string(), radius.to_string());
    let args = [
        [
            "--scene",
            scene.to_str().unwrap(),
            "--camera",
            camera.to_str().unwrap(),
        ],
        ["--mode", "rtao", "--rays", &rays],
        ["--frames", &frames, "--radius", &radius],
    ];
    render_ao_image(&args.concat(), &pfm, &scene.display().to_string())
}

/// Writes an ASCII STL of the box from `min` to `max` (12 triangles).
pub fn write_box_stl(path: &Path, min: [f32; 3], max: [f32; 3]) {
    let corners = hrtao_scene::box_corners(min, max);
    let mut s = String::from("solid box\n");
    for t in hrtao_scene::box_triangles() {
        s += " facet normal 0 0 0\n  outer loop\n";
        for p in t.map(|v| corners[v as usize]) {
            s += &format!("   vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s += "  endloop\n endfacet\n";
    }
    s += "endsolid box\n";
    std::fs::write(path, s).unwrap();
}

/// OBJ text of closed, outward-facing boxes (name, min, max), each an object of that name where the name is not
/// empty, their vertices numbered after `first` vertices written before them.
pub fn boxes_obj(boxes: &[(&str, [f32; 3], [f32; 3])], first: usize) -> String {
    let mut s = String::new();
    for (k, (name, min, max)) in boxes.iter().enumerate() {
        if !name.is_empty() {
            s += &format!("o {name}\n");
        }
        for p in hrtao_scene::box_corners(*min, *max) {
            s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
        let base = first + 8 * k + 1;
        for f in hrtao_scene::BOX_FACES.map(|f| f.map(|i| base + i as usize)) {
            s += &format!("f {} {} {} {}\n", f[0], f[1], f[2], f[3]);
        }
    }
    s
}

/// The PNG screenshots in `dir`, oldest first (names share the second: `MODEL-…-SS.png`, then `-2`, `-3`).
pub fn screenshots(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    files.retain(|p| p.extension().is_some_and(|e| e == "png"));
    files.sort_by_key(|f| std::fs::metadata(f).and_then(|m| m.modified()).ok());
    files
}

/// Pixels that differ between two screenshots of the same size by more than `tolerance` in some channel.
pub fn differing_pixels(a: &Path, b: &Path, tolerance: u8) -> usize {
    let (a, b) = (
        image::open(a).unwrap().to_rgb8(),
        image::open(b).unwrap().to_rgb8(),
    );
    assert_eq!(a.dimensions(), b.dimensions());
    a.pixels()
        .zip(b.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > tolerance))
        .count()
}

impl Running {
    /// F12 in `window` and the new screenshot in `dir`/screenshots (the `n`-th of the run).
    pub fn screenshot(&mut self, window: &str, dir: &Path, n: usize) -> PathBuf {
        xdotool(&["key", "--window", window, "F12"]);
        self.wait_for("] screenshot saved", n, std::time::Duration::from_secs(60));
        let shots = screenshots(&dir.join("screenshots"));
        assert_eq!(shots.len(), n, "{shots:?}");
        shots[n - 1].clone()
    }
}

/// The IfcOpenShell venv's interpreter, or `None` (with the reason printed: the IFC tests skip) when it is not
/// installed.
pub fn ifc_python() -> Option<PathBuf> {
    let p = hrtao_scene::ifc_python();
    if p.is_file() {
        Some(p)
    } else {
        println!(
            "skipped: no IfcOpenShell interpreter at {} (install: {})",
            p.display(),
            hrtao_scene::ifc_install_command()
        );
        None
    }
}

/// Writes a building of `storeys` storeys as IFC to `path` with IfcOpenShell's API (tests/ifc/make_building.py, run
/// by `python`): how many products it mapped to shared representations (the script's output).
pub fn make_building(python: &Path, path: &Path, storeys: u32) -> usize {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ifc/make_building.py");
    let storeys = storeys.to_string();
    run_python(python, &[script.as_os_str(), path.as_os_str(), storeys.as_ref()])
        .parse()
        .unwrap()
}

/// `python ARGS`, asserted successful (the arguments and its error output in the message otherwise): its output,
/// trimmed.
pub fn run_python(python: &Path, args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new(python).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// assimp's AC14-FZK-Haus.ifc, from Debian's assimp-testmodels (scripts/fetch-assimp-models.sh).
pub fn fzk_haus() -> PathBuf {
    scene_common::fetched_data("fetch-assimp-models.sh", "apt-get and Debian's assimp-testmodels")
        .join("IFC/AC14-FZK-Haus.ifc")
}
