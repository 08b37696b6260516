//! A hook for window tests: with `HRTAO_UI_PROBE` set in the environment, the window rectangles of named panel
//! controls are logged whenever they change (`ui probe: NAME at X,Y WxH`, window pixels, X,Y the centre), so a
//! test can click them with real X input (xdotool) instead of guessing where egui laid them out.
use std::collections::HashMap;

pub struct UiProbe {
    enabled: bool,
    last: HashMap<&'static str, [i32; 4]>,
}

impl UiProbe {
    pub fn from_env() -> UiProbe {
        UiProbe {
            enabled: std::env::var_os("HRTAO_UI_PROBE").is_some(),
            last: HashMap::new(),
        }
    }

    /// The control `name` is at `rect` (egui points; window pixels are points × `pixels_per_point`).
    pub fn note(&mut self, name: &'static str, rect: egui::Rect, pixels_per_point: f32) {
        if !self.enabled {
            return;
        }
        let px = |v: f32| (v * pixels_per_point).round() as i32;
        let r = [
            px(rect.center().x),
            px(rect.center().y),
            px(rect.width()),
            px(rect.height()),
        ];
        if self.last.insert(name, r) != Some(r) {
            log::info!("ui probe: {name} at {},{} {}x{}", r[0], r[1], r[2], r[3]);
        }
    }
}
