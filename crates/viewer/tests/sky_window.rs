//! The sky light in the window, driven with real X input under Xvfb (xdotool): the panel's "sky light" checkbox
//! switches it on, and dragging the environment's rotation slider turns the light on the model (the view's pixels
//! change) while the still image goes on accumulating (no restart, no cache clear: the transfer is re-lit).
mod common;

use std::path::Path;
use std::time::{Duration, Instant};

use common::{differing_pixels, display_available, out_dir, x_input_lock, xdotool, Running};

/// The still image's accumulated frames as the viewer logged them (`ui probe: accumulated = N`), in order, from
/// log line `from` on.
fn accumulated_from(v: &Running, from: usize) -> Vec<u32> {
    v.log_text()
        .lines()
        .skip(from)
        .filter_map(|l| l.split("ui probe: accumulated = ").nth(1))
        .map(|n| n.trim().parse().unwrap())
        .collect()
}

fn accumulated(v: &Running) -> Vec<u32> {
    accumulated_from(v, 0)
}

/// Log lines so far.
fn log_lines(v: &Running) -> usize {
    v.log_text().lines().count()
}

/// Waits until the last logged accumulation reaches `n` frames.
fn wait_accumulated(v: &Running, n: u32) {
    let start = Instant::now();
    while accumulated(v).last().copied().unwrap_or(0) < n {
        assert!(
            start.elapsed() < Duration::from_secs(180),
            "no {n} accumulated frames: {:?}",
            accumulated(v)
        );
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// A probed control's rectangle: centre and width (window pixels).
fn probed_rect(v: &mut Running, name: &str) -> (i32, i32, i32) {
    let (x, y) = v.probed(name);
    let needle = format!("ui probe: {name} at ");
    let log = v.log_text();
    let line = log.lines().rev().find(|l| l.contains(&needle)).unwrap();
    let size = line.split_whitespace().last().unwrap();
    let w: i32 = size.split_once('x').unwrap().0.parse().unwrap();
    (x, y, w)
}

#[test]
fn the_sky_light_turns_with_its_slider_and_keeps_accumulating() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("sky-window");
    // The lobe environment (it has an azimuth: turning it changes the light).
    let lobe = std::fs::canonicalize(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/env/sky_lobe_64x32.hdr"),
    )
    .unwrap();
    let config = dir.join("viewer.json");
    std::fs::write(
        &config,
        serde_json::json!({ "settings": { "environment": lobe } }).to_string(),
    )
    .unwrap();
    let mut v = Running::start_with(
        &["--size", "720x450", "--config", config.to_str().unwrap()],
        &dir,
        &[("HRTAO_UI_PROBE", Some("1"))],
    );
    v.wait_for("] opened ", 1, Duration::from_secs(120));
    let window = v.focus_window();
    // The AO look's still image first (its first frame logged before the click).
    wait_accumulated(&v, 3);
    let sky = v.probed("sky light");
    xdotool(&[
        "mousemove",
        "--window",
        &window,
        &sky.0.to_string(),
        &sky.1.to_string(),
        "click",
        "1",
    ]);
    v.wait_for("ui probe: sky light = on", 1, Duration::from_secs(60));
    // Switching the light re-keys the map: the still image restarts, and accumulates the sky light.
    let switched = log_lines(&v);
    let start = Instant::now();
    while !accumulated_from(&v, switched).contains(&1) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no restart after the switch: {}",
            v.log_text()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    wait_accumulated(&v, 4);
    let shot = log_lines(&v);
    let lit = v.screenshot(&window, &dir, 1);
    // The screenshot renders the view at its own size: the view's still image restarts after it.
    let start = Instant::now();
    while accumulated_from(&v, shot).last().is_none_or(|n| *n < 2) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no frames after the screenshot"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let before_drag = log_lines(&v);
    let frames_before_drag = *accumulated(&v).last().unwrap();

    // Drag the rotation slider's handle from the rail's middle (0°) to the right.
    let (x, y, w) = probed_rect(&mut v, "environment rotation");
    let rail = x - w / 2 + 50;
    xdotool(&[
        "mousemove",
        "--window",
        &window,
        &rail.to_string(),
        &y.to_string(),
    ]);
    xdotool(&["mousedown", "1"]);
    for step in 1..=8 {
        std::thread::sleep(Duration::from_millis(150));
        xdotool(&[
            "mousemove",
            "--window",
            &window,
            &(rail + 5 * step).to_string(),
            &y.to_string(),
        ]);
    }
    xdotool(&["mouseup", "1"]);
    let start = Instant::now();
    while !v.log_text().lines().any(|l| {
        l.split("ui probe: environment rotation = ")
            .nth(1)
            .is_some_and(|r| r.trim().parse::<f32>().unwrap() >= 30.0)
    }) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the slider did not move: {}",
            v.log_text()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    // The frames the drag asked for accumulate on (the image may have converged before: each change of the
    // rotation then renders one more frame of it).
    wait_accumulated(&v, frames_before_drag + 1);
    std::thread::sleep(Duration::from_secs(2));
    let turned = v.screenshot(&window, &dir, 2);
    let changed = differing_pixels(&lit, &turned, 12);
    let counts = accumulated_from(&v, before_drag);
    println!("{changed} pixels changed; accumulated frames from {frames_before_drag}: {counts:?}");
    assert!(changed > 1000, "turning the environment changed {changed} pixels");
    assert!(
        !counts.is_empty() && counts.windows(2).all(|w| w[1] > w[0]) && counts[0] > frames_before_drag,
        "the still image restarted during the rotation: {frames_before_drag} then {counts:?}; the log since:\n{}",
        v.log_text().lines().skip(before_drag).collect::<Vec<_>>().join("\n")
    );
    v.validation_clean();
}
