//! The instruments of the latency benchmark (scripts/bench-latency.sh) in the real window (Xvfb + lavapipe):
//! `--stats` stamps each frame's presentation and the input it answers on CLOCK_MONOTONIC, `--exit-after` ends a
//! user-like run once it rests, `--ao-out` writes the view's AO per frame with its roughness.
use std::path::{Path, PathBuf};
use std::time::Duration;

mod common;
use common::*;

/// CLOCK_MONOTONIC in milliseconds: the clock the viewer stamps frames with (and Python's time.monotonic()).
fn monotonic_ms() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    assert_eq!(unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) }, 0);
    ts.tv_sec as f64 * 1e3 + ts.tv_nsec as f64 * 1e-6
}

/// A user-like run (`--exit-after EXIT_AFTER --stats STATS`, no panel) of the bundled scene, opened, its window
/// focused (raw input, device events, reaches the viewer while its window has the focus); the window's id.
fn start_user_run(dir: &Path, exit_after: &str, stats: &Path) -> (Running, String) {
    let args = [
        "--size",
        "400x260",
        "--no-panel",
        "--exit-after",
        exit_after,
        "--stats",
    ];
    let mut v = Running::launch(
        &[&["view"], &args[..], &[stats.to_str().unwrap()]].concat(),
        dir,
        &[],
    );
    v.wait_for("] opened ", 1, Duration::from_secs(60));
    let window = v.focus_window();
    (v, window)
}

/// The run exits by itself (`--exit-after`) with status 0 at its rest, validation-clean.
fn ends_at_rest(v: &mut Running) {
    let status = v.wait_exit(Duration::from_secs(120));
    let log = v.log_text();
    assert!(status.success(), "hrtao view failed ({status}):\n{log}");
    v.validation_clean();
    assert!(log.contains("at rest"), "{log}");
}

fn read_stats(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("stats JSON")).expect("valid JSON")
}

/// A drag sent with xdotool while the view refines is answered by a frame that says so: `input` with
/// `input_last_ms` after the monotonic stamp of the drag's motion (its `input_ms` may be the press before it) and
/// `presented_ms` after that; the frames before it answer no input.
/// `--exit-after` then ends the run at its rest, with the converged frame marked and the stats written.
#[test]
fn a_drag_is_answered_by_a_frame_stamped_after_it() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("drag");
    let stats = dir.join("stats.json");
    let start = monotonic_ms();
    let (mut v, window) = start_user_run(&dir, "4", &stats);
    // A moment into the still refinement, then one left drag (orbit) in the view.
    std::thread::sleep(Duration::from_millis(300));
    // A hover, then the button held over several frames as a hand does it (pressed and released within one or two
    // frames of the busy viewer, egui sees a click or a drag without motion): 20 moves 75 ms apart. The hover and
    // the press move nothing; the motion (stamped just before its command) is the input that moves the view.
    let hover = monotonic_ms();
    xdotool(&[
        "mousemove",
        "--window",
        &window,
        "150",
        "130",
        "sleep",
        "0.05",
        "mousedown",
        "1",
        "sleep",
        "0.075",
    ]);
    let mut drag: Vec<String> = Vec::new();
    for k in 1..=20 {
        if k > 1 {
            drag.extend(["sleep".into(), "0.075".into()]);
        }
        drag.extend(["mousemove".into(), "--window".into(), window.clone()]);
        drag.extend([(150 + 5 * k).to_string(), (130 + k / 4).to_string()]);
    }
    drag.extend(["mouseup".into(), "1".into()]);
    let stamp = monotonic_ms();
    xdotool(&drag.iter().map(String::as_str).collect::<Vec<_>>());
    ends_at_rest(&mut v);

    let s = read_stats(&stats);
    let frames = s["frames"].as_array().unwrap();
    assert!(frames.len() >= 3, "{} frames", frames.len());
    // The first still image after opening is drawn in slices on a software device: the first frame's wall time
    // counts the scene's install, and the frame-time target skips it; its device time sets the first lattice
    // (with no estimate, whole frames came first, ~2 s each at 800x800, whenever the install frame outlasted the
    // moving window so that no moving frame followed it: timing-dependent, seen with the panel at 1280x800).
    // (The rule itself is replayed on a controlled clock in view/pacer's tests; here, whatever the device and its
    // speed: a first still image in whole frames is one whose frames fit the slice target, half the frame-time
    // target the stats record: 50 ms on a CPU, half a display refresh on a GPU.)
    // A frame's cost: its wall time less its wait for the swapchain's image (a display's refresh).
    let cost =
        |f: &serde_json::Value| f["wall_ms"].as_f64().unwrap() - f["cpu_ms"]["acquire"].as_f64().unwrap();
    let slice_target = 0.5
        * s["target_ms"]
            .as_f64()
            .expect("the stats give the frame-time target");
    let first_still = frames.iter().find(|f| f["still"] == true).expect("a still frame");
    assert!(
        first_still["slices"].as_u64().unwrap() > 1 || cost(first_still) <= slice_target * 1.5,
        "the first still image in whole frames over the slice target: {first_still}"
    );
    let presented: Vec<f64> = frames
        .iter()
        .map(|f| f["presented_ms"].as_f64().unwrap())
        .collect();
    assert!(
        presented[0] > start && presented.windows(2).all(|w| w[1] > w[0]),
        "presentation times rise from the start ({start}): {presented:?}"
    );
    let answered: Vec<usize> = (0..frames.len())
        .filter(|&i| frames[i]["input"] == true)
        .collect();
    let moved = frames.iter().filter(|f| f["moving"] == true).count();
    let first = *answered.first().unwrap_or_else(|| {
        panic!(
            "no frame answers the drag ({} frames, {moved} moving)",
            frames.len()
        )
    });
    let f = &frames[first];
    let input_ms = f["input_ms"].as_f64().unwrap();
    let input_last_ms = f["input_last_ms"].as_f64().unwrap();
    assert!(
        input_ms >= hover && input_last_ms >= stamp && presented[first] > input_last_ms,
        "hover {hover}, motion {stamp}, input {input_ms} .. {input_last_ms}, presented {}",
        presented[first]
    );
    assert_eq!(f["moving"], true, "the answering frame moved the camera");
    // The view renders no frame that neither moves nor refines the still image: between the drag's motions and
    // in the moments after its release (`Motion::settling`) it keeps the moving image, which such a frame would
    // only refine at the moving scale, to be replaced by the still image (and input would wait for it).
    let idle: Vec<usize> = (0..frames.len())
        .filter(|&i| frames[i]["moving"] == false && frames[i]["still"] == false)
        .collect();
    assert!(idle.is_empty(), "frames refining the moving image: {idle:?}");
    // Frames presented before the motion answer no input (the hover and the press move nothing).
    assert!(frames
        .iter()
        .filter(|f| f["presented_ms"].as_f64().unwrap() < stamp)
        .all(|f| f["input"] == false && f["input_ms"].is_null()));
    // Still refinement before the drag, and the run ends on the converged frame, which the file names.
    assert!(frames[..first]
        .iter()
        .any(|f| f["still"] == true && f["refining"] == true));
    let last = frames.len() - 1;
    assert_eq!(frames[last]["converged"], true, "{}", frames[last]);
    let conv = s["converged_frame"].as_u64().unwrap() as usize;
    assert!(conv > first && frames[conv]["converged"] == true);
    assert!(frames[first..conv].iter().all(|f| f["converged"] == false));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A press on the view that has not moved yet changes nothing and holds the view: no frame is rendered while the
/// button is held (the GPU is free for the motion that will come), and the press does not move the camera (no
/// moving frame, as egui reports a drag from the press on). Refinement goes on after the release, to the rest.
#[test]
fn a_press_that_has_not_moved_holds_the_view() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("press");
    let stats = dir.join("stats.json");
    let (mut v, window) = start_user_run(&dir, "3", &stats);
    // An orbit first (a camera navigation has re-derived), then, into the still refinement, the button held
    // 1.5 s without motion.
    let press = |x: &str, y: &str| {
        xdotool(&[
            "mousemove",
            "--window",
            &window,
            x,
            y,
            "sleep",
            "0.05",
            "mousedown",
            "1",
        ]);
    };
    press("150", "130");
    for x in ["170", "190", "210"] {
        std::thread::sleep(Duration::from_millis(100));
        xdotool(&["mousemove", "--window", &window, x, "135"]);
    }
    xdotool(&["mouseup", "1"]);
    std::thread::sleep(Duration::from_millis(1000));
    let orbited = monotonic_ms();
    press("150", "130");
    let pressed = monotonic_ms();
    std::thread::sleep(Duration::from_millis(1500));
    let released = monotonic_ms();
    xdotool(&["mouseup", "1"]);
    ends_at_rest(&mut v);

    let s = read_stats(&stats);
    let frames = s["frames"].as_array().unwrap();
    let presented: Vec<f64> = frames
        .iter()
        .map(|f| f["presented_ms"].as_f64().unwrap())
        .collect();
    // At most the frame in flight at the press and the one the press reached; then the view holds until the
    // release (a count: a slow frame takes longer, never more frames).
    let during: Vec<f64> = presented
        .iter()
        .filter(|&&t| t > pressed && t < released)
        .map(|t| t - pressed)
        .collect();
    assert!(
        during.len() <= 2,
        "frames rendered while the button was held (ms after the press): {during:?}"
    );
    assert!(
        presented.iter().any(|&t| t < pressed) && presented.iter().any(|&t| t > released),
        "refinement before the press and after the release: {presented:?}"
    );
    let orbit = (1..frames.len()).filter(|&i| frames[i]["moving"] == true && presented[i] < orbited);
    assert!(orbit.count() > 0, "the orbit moved the camera");
    let moving: Vec<usize> = (1..frames.len())
        .filter(|&i| frames[i]["moving"] == true && presented[i] > orbited)
        .collect();
    assert!(moving.is_empty(), "the press moved the camera: frames {moving:?}");
    assert_eq!(frames[frames.len() - 1]["converged"], true);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--ao-out` writes the view's AO of every rendered frame at its internal size, and `--stats` the roughness of
/// each (occluded flat pixels by the frame's own AO).
#[test]
fn ao_out_writes_every_frame_and_its_roughness() {
    if !display_available() {
        return;
    }
    let dir = out_dir("ao");
    let stats = dir.join("stats.json");
    let ao = dir.join("ao");
    let outputs = [
        "--stats",
        stats.to_str().unwrap(),
        "--ao-out",
        ao.to_str().unwrap(),
    ];
    scripted_run(
        &[&["--size", "320x200", "--no-panel", "--orbit", "2"][..], &outputs].concat(),
        &[],
    );
    let s = read_stats(&stats);
    let frames = s["frames"].as_array().unwrap();
    let mut pfms: Vec<PathBuf> = std::fs::read_dir(&ao)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    pfms.sort();
    assert_eq!(pfms.len(), frames.len(), "one PFM per rendered frame");
    let mut rough = Vec::new();
    for (i, (f, p)) in frames.iter().zip(&pfms).enumerate() {
        assert_eq!(
            p.file_name().unwrap().to_str().unwrap(),
            format!("frame_{i:04}.pfm")
        );
        let (w, h, px) = hrtao_core::imageio::read_pfm(p).unwrap();
        assert_eq!(
            [w as u64, h as u64],
            [
                f["internal"][0].as_u64().unwrap(),
                f["internal"][1].as_u64().unwrap()
            ]
        );
        assert!(px.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
        assert!(
            px.iter().filter(|v| **v < 0.95).count() > px.len() / 20,
            "occlusion in frame {i}"
        );
        rough.push(f["roughness"].as_f64());
    }
    eprintln!("roughness per frame: {rough:?}");
    // Every frame of the bundled scene has occluded flat pixels: a finite, positive roughness. Only the frames of
    // a round of slices abandoned before it ended (a slow orbit step can count as a rest) go unmeasured.
    for (i, r) in rough.iter().enumerate() {
        let abandoned = frames[i]["still"] == true
            && frames[i..]
                .iter()
                .take_while(|f| f["still"] == true)
                .all(|f| f["slice"].as_u64() != Some(f["slices"].as_u64().unwrap() - 1));
        assert!(r.is_some() || abandoned, "frame {i}: no roughness: {rough:?}");
    }
    let rough: Vec<f64> = rough.iter().map(|r| r.unwrap_or(f64::NAN)).collect();
    let measured: Vec<f64> = rough.iter().copied().filter(|r| !r.is_nan()).collect();
    assert!(
        measured.iter().all(|r| r.is_finite() && *r > 0.0 && *r < 0.2),
        "{rough:?}"
    );
    // The run ends on the converged image, smoother than the blocky first frame at the moving scale, and the path
    // to it is monotone: no still frame is much rougher than the converged one (the goal is 1.25x; measured
    // 1.04x here, and 1.26x / 1.03x on the bundled scene / san_francisco at 1280x800 with the panel; before the
    // held rounds' B-spline and the full-resolution filter of slices, 2.0x / 1.4-1.7x). The bound leaves room
    // for the lattice the frame-time controller picks under load.
    let last = frames.len() - 1;
    assert_eq!(frames[last]["converged"], true);
    let still: Vec<usize> = (0..frames.len())
        .filter(|&i| frames[i]["still"] == true)
        .collect();
    assert!(still.len() >= 4, "{} still frames", still.len());
    let peak = still
        .iter()
        .map(|&i| rough[i])
        .filter(|r| !r.is_nan())
        .fold(0.0, f64::max);
    assert!(
        rough[last] < rough[0] && peak <= 1.5 * rough[last],
        "converged {} against the first frame {} and the still frames' peak {peak}",
        rough[last],
        rough[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
