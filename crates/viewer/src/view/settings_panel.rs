//! The panel's AO settings: one section per settings group (hrtao_core::settings), each drawn from its group's
//! declaration (`fields_mut`: a checkbox per switch, a slider over the declared range per number, the modes'
//! list), in declaration order. A setting added to a group shows here without a line of panel code; the few
//! declared `custom` have a row below (`custom_row`), whose range still comes from the declaration.
use std::ops::RangeInclusive;

use hrtao_core::settings::{Range, Row, SettingInfo, SettingRef};
use hrtao_core::Mode;

use super::command::{Command, ViewState};

/// The rays-per-frame slider's range: the frame-time target's own bounds.
pub const RAYS_PER_FRAME: RangeInclusive<u32> =
    super::pacer::MIN_RAYS_PER_FRAME..=super::pacer::MAX_RAYS_PER_FRAME;

/// The max render scale slider's range: the smallest scale `RENDER_SCALE` accepts up to the view's own
/// resolution (larger scales, supersampling, only from `--render-scale`).
pub const MAX_RENDER_SCALE: RangeInclusive<f32> = *super::RENDER_SCALE.start()..=1.0;

/// The "Ambient occlusion" section: the settings groups, the ray budget and frame-time target, the render
/// scale, Clear cache, Defaults and Paper.
pub struct SettingsPanel;

impl SettingsPanel {
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let mut out = Vec::new();
        let mut s = state.prefs.settings.clone();
        let mut prefs = state.prefs.clone();
        rows(ui, s.display.fields_mut(), 0.0);
        rows(ui, s.light.fields_mut(), 0.0);
        // With the frame-time target on, the slider shows the target's budget; off, it sets the user's.
        let mut live = state.rays_per_frame;
        let rays = if prefs.auto_budget {
            &mut live
        } else {
            &mut prefs.rays_per_frame
        };
        ui.add_enabled(
            !prefs.auto_budget,
            egui::Slider::new(rays, RAYS_PER_FRAME)
                .logarithmic(true)
                .text("rays / frame"),
        )
        .on_hover_text(
            "Ray budget (§3, §6): rays traced per frame whatever the resolution, shared between the hash \
             cells visible in the image (collaborative ray tracing); the renderer gets it as rays per pixel \
             (at least 1). Higher: faster convergence, slower frames.",
        );
        rows(ui, s.map.fields_mut(), state.default_radius);
        rows(ui, s.filter.fields_mut(), 0.0);
        rows(ui, s.still.fields_mut(), 0.0);
        ui.label("first frames (ours, docs/algorithm.md):");
        rows(ui, s.young.fields_mut(), 0.0);
        rows(ui, s.edits.fields_mut(), 0.0);
        ui.separator();
        let mut scale = state.render_scale;
        ui.add_enabled(
            state.can_scale,
            egui::Slider::new(&mut scale, MAX_RENDER_SCALE).text("max render scale"),
        )
        .on_hover_text(
            "Internal resolution of a still image as a fraction of the 3D view (blitted to the window). While \
             the camera moves the resolution drops to meet the frame-time target (not below 0.35 of the view \
             unless this cap is lower). s_p counts view pixels, so the hash cells do not change with it.",
        );
        if scale != state.render_scale {
            out.push(Command::RenderScale(scale));
        }
        ui.horizontal(|ui| {
            ui.checkbox(&mut prefs.auto_budget, "frame-time target")
                .on_hover_text(
                "§6: \"the ray budget can be adjusted to match a target rendering speed\": while the camera \
                 moves, the ray budget and the render scale adapt to reach the target frame time.",
            );
            // The device's target (a frame per refresh on a GPU, 100 ms on a CPU) until the user sets one.
            let mut target = prefs.frame_target_ms.unwrap_or(state.target_ms as f32);
            let edited = ui
                .add_enabled(
                    prefs.auto_budget,
                    egui::DragValue::new(&mut target)
                        .range(2.0..=2000.0)
                        .suffix(" ms target"),
                )
                .changed();
            if edited {
                prefs.frame_target_ms = Some(target);
            }
            if prefs.frame_target_ms.is_some()
                && ui
                    .small_button("device")
                    .on_hover_text(
                        "The device's target: a frame per display refresh on a GPU, 100 ms on a CPU",
                    )
                    .clicked()
            {
                prefs.frame_target_ms = None;
            }
        });
        ui.horizontal(|ui| {
            if ui
                .button("Clear cache")
                .on_hover_text("Forget all cached AO (the hash map restarts empty)")
                .clicked()
            {
                out.push(Command::ClearCache);
            }
            if ui
                .button("Defaults")
                .on_hover_text("AoSettings::default() with the scene's radius and up axis")
                .clicked()
            {
                s = hrtao_core::AoSettings::default().with_radius(state.default_radius);
                // The sky's zenith is the scene's up axis, not a setting to reset.
                s.light.sky_up = state.nav.world_up;
            }
            if ui
                .button("Paper")
                .on_hover_text(format!(
                    "The paper's technique as published: every addition of ours off ({}); radius, budget and \
                     cells unchanged. Defaults turns them back on.",
                    hrtao_core::AoSettings::addition_names().join(", ")
                ))
                .clicked()
            {
                s = s.paper();
            }
        });
        prefs.settings = state.prefs.settings.clone();
        if prefs != *state.prefs {
            out.push(Command::Prefs(Box::new(prefs)));
        }
        if s != state.prefs.settings {
            out.push(Command::Settings(Box::new(s)));
        }
        out
    }
}

/// A group's rows, from its declaration, in its order: consecutive switches share a wrapped line; a setting
/// that `needs` a switch is disabled while it is off; `hidden` ones are skipped and `custom` ones drawn by
/// `custom_row` (`r0`: the scene's default AO radius).
pub fn rows(ui: &mut egui::Ui, fields: Vec<(&'static SettingInfo, SettingRef<'_>)>, r0: f32) {
    let on: Vec<(&str, bool)> = fields
        .iter()
        .filter_map(|(info, value)| match value {
            SettingRef::Bool(b) => Some((info.name, **b)),
            _ => None,
        })
        .collect();
    let enabled = |info: &SettingInfo| {
        info.needs
            .is_none_or(|n| on.iter().any(|(name, b)| *name == n && *b))
    };
    let mut switches: Vec<(&'static SettingInfo, &mut bool)> = Vec::new();
    for (info, value) in fields {
        if info.row == Row::Hidden {
            continue;
        }
        match value {
            SettingRef::Bool(b) if info.row == Row::Generic => switches.push((info, b)),
            value => {
                checkboxes(ui, std::mem::take(&mut switches), &enabled);
                ui.add_enabled_ui(enabled(info), |ui| {
                    if info.row == Row::Custom {
                        custom_row(ui, info, value, r0);
                    } else {
                        generic_row(ui, info, value);
                    }
                });
            }
        }
    }
    checkboxes(ui, switches, &enabled);
}

/// Switches, a checkbox each with the setting's doc as its hover text, on one wrapped line.
fn checkboxes(
    ui: &mut egui::Ui,
    list: Vec<(&'static SettingInfo, &mut bool)>,
    enabled: &dyn Fn(&SettingInfo) -> bool,
) {
    if list.is_empty() {
        return;
    }
    let ppp = ui.ctx().pixels_per_point();
    ui.horizontal_wrapped(|ui| {
        for (info, on) in list {
            let r = ui.add_enabled(enabled(info), egui::Checkbox::new(on, info.label));
            super::ui_probe::note(info.words, r.rect, ppp);
            super::ui_probe::note_text(info.words, if *on { "on" } else { "off" });
            r.on_hover_text(info.text());
        }
    });
}

/// A number's slider over its declared range (logarithmic where declared), or the modes' list.
fn generic_row(ui: &mut egui::Ui, info: &'static SettingInfo, value: SettingRef<'_>) {
    let ppp = ui.ctx().pixels_per_point();
    let response = match value {
        SettingRef::F32(v) => {
            let r = ui.add(
                egui::Slider::new(v, slider_range(info))
                    .logarithmic(info.log)
                    .text(info.label),
            );
            super::ui_probe::note_text(info.words, &v.to_string());
            r
        }
        SettingRef::U32(v) => {
            let (lo, hi) = slider_range(info).into_inner();
            let r = ui.add(
                egui::Slider::new(v, lo as u32..=hi as u32)
                    .logarithmic(info.log)
                    .text(info.label),
            );
            super::ui_probe::note_text(info.words, &v.to_string());
            r
        }
        SettingRef::Mode(m) => {
            egui::ComboBox::from_label(info.label)
                .selected_text(m.label())
                .show_ui(ui, |ui| {
                    for mode in Mode::ALL {
                        ui.selectable_value(m, mode, mode.label());
                    }
                })
                .response
        }
        // `check_fields` and the panel's test: a text or an axis is `custom` or `hidden`.
        SettingRef::Bool(_) | SettingRef::Text(_) | SettingRef::Axis(_) => {
            ui.label(format!("{}: no generic row", info.label))
        }
    };
    super::ui_probe::note(info.words, response.rect, ppp);
    response.on_hover_text(info.text());
}

/// A generic slider's range: the declared one (`check_fields` makes it closed and finite).
pub fn slider_range(info: &SettingInfo) -> RangeInclusive<f32> {
    let r = info.range.expect("a number has a range");
    r.min as f32..=r.max as f32
}

/// The AO radius slider: 1% to 20 times the scene's default radius `r0`, within the declared range.
pub fn radius_range(r0: f32, r: &Range) -> RangeInclusive<f32> {
    let lowest = if r.above_min {
        (r.min as f32).next_up()
    } else {
        r.min as f32
    };
    let lo = (r0 * 0.01).clamp(lowest, r.max as f32);
    lo..=(r0 * 20.0).clamp(lo, r.max as f32)
}

/// The hash capacity slider, in log2 of cells: the powers of two within the declared range.
pub fn log2_range(r: &Range) -> RangeInclusive<u32> {
    r.min.log2().ceil() as u32..=r.max.log2().floor() as u32
}

/// The rows the declaration marks `custom`: the AO radius (relative to the scene, with a reset), the hash
/// capacity (log2), the environment (a list and a file field). Each spans the declared range.
fn custom_row(ui: &mut egui::Ui, info: &'static SettingInfo, value: SettingRef<'_>, r0: f32) {
    let range = info.range;
    match (info.name, value, range) {
        ("ao_radius", SettingRef::F32(radius), Some(r)) => {
            ui.horizontal(|ui| {
                ui.add(
                    egui::Slider::new(radius, radius_range(r0, &r))
                        .logarithmic(info.log)
                        .text(info.label),
                )
                .on_hover_text(info.text());
                if ui.small_button("↺").on_hover_text("scene default").clicked() {
                    *radius = r0;
                }
            });
        }
        ("hash_capacity", SettingRef::U32(capacity), Some(r)) => {
            let range = log2_range(&r);
            let mut log2 = capacity.trailing_zeros().clamp(*range.start(), *range.end());
            ui.add(
                egui::Slider::new(&mut log2, range)
                    .text(format!("{} (log2)", info.label))
                    .custom_formatter(|v, _| format!("2^{v} = {}", 1u64 << v as u32)),
            )
            .on_hover_text(format!(
                "{} Watch the load factor and failed inserts in the statistics.",
                info.text()
            ));
            *capacity = 1 << log2;
        }
        ("environment", SettingRef::Text(environment), _) => environment_row(ui, info, environment),
        (name, _, _) => {
            debug_assert!(false, "no custom row for `{name}`");
            ui.label(format!("{}: no custom row", info.label));
        }
    }
}

/// The environment: `uniform`, `gradient`, or an `.hdr` file typed in a path field (applied once it names a
/// readable file).
fn environment_row(ui: &mut egui::Ui, info: &'static SettingInfo, environment: &mut String) {
    let is_file = environment.to_ascii_lowercase().ends_with(".hdr");
    let id = ui.make_persistent_id("environment file");
    let mut path: String = ui.data_mut(|d| d.get_temp::<String>(id)).unwrap_or_default();
    if path.is_empty() && is_file {
        path = environment.clone();
    }
    egui::ComboBox::from_label(info.label)
        .selected_text(if is_file { "HDR file" } else { environment.as_str() })
        .show_ui(ui, |ui| {
            for name in ["uniform", "gradient"] {
                ui.selectable_value(environment, name.to_string(), name);
            }
            if ui.selectable_label(is_file, "HDR file").clicked() && !path.is_empty() {
                *environment = path.clone();
            }
        })
        .response
        .on_hover_text(info.text());
    let edit = ui.add(egui::TextEdit::singleline(&mut path).hint_text("equirectangular .hdr file"));
    let usable = path.to_ascii_lowercase().ends_with(".hdr") && std::path::Path::new(&path).is_file();
    if edit.lost_focus() && usable {
        *environment = path.clone();
    }
    if !path.is_empty() && !usable {
        ui.colored_label(egui::Color32::from_rgb(200, 80, 60), "not a readable .hdr file");
    }
    ui.data_mut(|d| d.insert_temp(id, path));
}

#[cfg(test)]
mod tests {
    use super::*;
    use hrtao_core::settings::Kind;
    use hrtao_core::AoSettings;

    /// The value `v` of the number setting `info` in otherwise default settings, validated.
    fn valid(info: &SettingInfo, v: f64) -> bool {
        let v = match info.kind {
            Kind::Integer if v >= 0.0 => serde_json::json!(v as u64),
            _ => serde_json::json!(v),
        };
        let json = serde_json::json!({ info.name: v }).to_string();
        AoSettings::default().with_overrides(&json).is_ok()
    }

    /// Every slider the panel draws spans exactly the values validation accepts: its ends are valid, and a
    /// step past either end is refused (a generic slider's range is the declaration's; the custom ones stay
    /// within it for any scene).
    #[test]
    fn every_slider_spans_the_validated_range() {
        let mut sliders = 0;
        for info in AoSettings::fields() {
            let Some(r) = info.range else { continue };
            match (info.row, info.name) {
                (Row::Generic, _) => {
                    let range = slider_range(info);
                    let (lo, hi) = (*range.start() as f64, *range.end() as f64);
                    assert_eq!((lo, hi), (r.min, r.max), "{}", info.name);
                    assert!(valid(info, lo) && valid(info, hi), "{}: {lo}..={hi}", info.name);
                    let step = if info.kind == Kind::Integer {
                        1.0
                    } else {
                        (hi - lo) * 1e-3
                    };
                    assert!(!valid(info, hi + step), "{} accepts above its slider", info.name);
                    if lo - step >= 0.0 || info.kind == Kind::Float {
                        assert!(!valid(info, lo - step), "{} accepts below its slider", info.name);
                    }
                    sliders += 1;
                }
                (Row::Custom, "ao_radius") => {
                    for r0 in [1e-30, 1e-3, 8.0, 1e6, 1e30] {
                        let range = radius_range(r0, &r);
                        assert!(valid(info, *range.start() as f64), "{r0}: {range:?}");
                        assert!(valid(info, *range.end() as f64), "{r0}: {range:?}");
                    }
                    sliders += 1;
                }
                (Row::Custom, "hash_capacity") => {
                    let range = log2_range(&r);
                    let (lo, hi) = (*range.start(), *range.end());
                    assert!(valid(info, (1u64 << lo) as f64) && valid(info, (1u64 << hi) as f64));
                    assert!(
                        !valid(info, (1u64 << (lo - 1)) as f64) && !valid(info, (1u64 << (hi + 1)) as f64)
                    );
                    sliders += 1;
                }
                (Row::Custom, name) => panic!("{name}: a custom number row without a test of its range"),
                (Row::Hidden, _) => {}
            }
        }
        assert!(sliders >= 9, "{sliders} sliders");
    }

    #[test]
    fn the_budget_slider_spans_the_pacers_budgets() {
        assert_eq!(
            RAYS_PER_FRAME,
            super::super::pacer::MIN_RAYS_PER_FRAME..=super::super::pacer::MAX_RAYS_PER_FRAME
        );
        assert_eq!(*MAX_RENDER_SCALE.start(), *super::super::RENDER_SCALE.start());
    }

    /// Every group draws, headless, without a missing row: each custom setting has its row, and a text or an
    /// axis is never left to the generic rows.
    #[test]
    fn every_setting_has_a_row() {
        for info in AoSettings::fields() {
            if info.row == Row::Generic {
                assert!(
                    matches!(info.kind, Kind::Toggle | Kind::Float | Kind::Integer) || info.name == "mode",
                    "{}: no generic row for its kind",
                    info.name
                );
            }
        }
        let ctx = egui::Context::default();
        let mut s = AoSettings::default();
        s.light.sky_light = true;
        // A custom row missing from `custom_row` fails its debug assertion here.
        let mut out = ctx.run_ui(egui::RawInput::default(), |ui| rows(ui, s.fields_mut(), 8.0));
        out.textures_delta.clear();
        let mut drawn = AoSettings::default();
        drawn.light.sky_light = true;
        assert_eq!(s, drawn, "drawing changes no setting");
    }
}
