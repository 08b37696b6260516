//! A hook for window tests: with `HRTAO_UI_PROBE` set in the environment, the window rectangles of named panel
//! controls are logged whenever they change (`ui probe: NAME at X,Y WxH`, window pixels, X,Y the centre), so a
//! test can click them with real X input (xdotool) instead of guessing where egui laid them out. Any panel notes
//! its controls through `note`, and a text it shows through `note_text`; the process has one probe.
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// The last rectangle logged per control; None when the probe is off.
type Rects = Option<HashMap<&'static str, [i32; 4]>>;

fn probe() -> &'static Mutex<Rects> {
    static PROBE: OnceLock<Mutex<Rects>> = OnceLock::new();
    PROBE.get_or_init(|| Mutex::new(std::env::var_os("HRTAO_UI_PROBE").map(|_| HashMap::new())))
}

/// The control `name` is at `rect` (egui points; window pixels are points × `pixels_per_point`).
pub fn note(name: &'static str, rect: egui::Rect, pixels_per_point: f32) {
    let mut guard = probe().lock().unwrap_or_else(|p| p.into_inner());
    let Some(last) = guard.as_mut() else {
        return;
    };
    let px = |v: f32| (v * pixels_per_point).round() as i32;
    let r = [
        px(rect.center().x),
        px(rect.center().y),
        px(rect.width()),
        px(rect.height()),
    ];
    if last.insert(name, r) != Some(r) {
        log::info!("ui probe: {name} at {},{} {}x{}", r[0], r[1], r[2], r[3]);
    }
}

/// The text a panel shows for `name` is `text` (logged as `ui probe: NAME = TEXT` whenever it changes).
pub fn note_text(name: &'static str, text: &str) {
    static TEXTS: OnceLock<Mutex<HashMap<&'static str, String>>> = OnceLock::new();
    if probe().lock().unwrap_or_else(|p| p.into_inner()).is_none() {
        return;
    }
    let mut last = TEXTS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|p| p.into_inner());
    if last.get(name).map(String::as_str) != Some(text) {
        log::info!("ui probe: {name} = {text}");
        last.insert(name, text.to_string());
    }
}
