//! The panel's AO settings: one section per settings group (hrtao_core::settings), each drawing its group's
//! fields and nothing else. Adding a setting to a group means adding its widget here, in its group's function.
use hrtao_core::settings::{
    DisplaySettings, EditSettings, FilterSettings, LightSettings, MapSettings, StillSettings,
    YoungMapSettings,
};
use hrtao_core::Mode;

use super::command::{Command, ViewState};

/// The "Ambient occlusion" section: the settings groups, the ray budget and frame-time target, the render
/// scale, Clear cache, Defaults and Paper.
pub struct SettingsPanel;

impl SettingsPanel {
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let mut out = Vec::new();
        let mut s = state.prefs.settings.clone();
        let mut prefs = state.prefs.clone();
        display(ui, &mut s.display);
        light(ui, &mut s.light);
        // With the frame-time target on, the slider shows the target's budget; off, it sets the user's.
        let mut live = state.rays_per_frame;
        let rays = if prefs.auto_budget {
            &mut live
        } else {
            &mut prefs.rays_per_frame
        };
        ui.add_enabled(
            !prefs.auto_budget,
            egui::Slider::new(rays, super::pacer::MIN_RAYS_PER_FRAME..=16_000_000)
                .logarithmic(true)
                .text("rays / frame"),
        )
        .on_hover_text(
            "Ray budget (§3, §6): rays traced per frame whatever the resolution, shared between the hash \
             cells visible in the image (collaborative ray tracing); the renderer gets it as rays per pixel \
             (at least 1). Higher: faster convergence, slower frames.",
        );
        map(ui, &mut s.map, state.default_radius);
        filter(ui, &mut s.filter);
        still(ui, &mut s.still);
        young(ui, &mut s.young);
        edits(ui, &mut s.edits);
        ui.separator();
        let mut scale = state.render_scale;
        ui.add_enabled(
            state.can_scale,
            egui::Slider::new(&mut scale, 0.1..=1.0).text("max render scale"),
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

/// What is shown: the mode, shading and feature edges.
pub fn display(ui: &mut egui::Ui, s: &mut DisplaySettings) {
    egui::ComboBox::from_label("mode")
        .selected_text(s.mode.label())
        .show_ui(ui, |ui| {
            for m in Mode::ALL {
                ui.selectable_value(&mut s.mode, m, m.label());
            }
        })
        .response
        .on_hover_text(
            "HRTAO: the paper's hashed ray-traced AO (§1-§5). Per-pixel RTAO: the brute-force baseline \
             (accumulates while nothing moves). Debug views: hash cells (Fig. 3), LOD used (§4), samples \
             per cell.",
        );
    ui.horizontal(|ui| {
        ui.checkbox(&mut s.edges, "edges").on_hover_text(
            "Feature edges over the shading: silhouettes (depth and part changes) and creases. In \
             screenshots, never in the AO image.",
        );
        ui.add_enabled(
            s.edges,
            egui::Slider::new(&mut s.crease_deg, hrtao_core::settings::CREASE_DEG_RANGE).text("crease °"),
        )
        .on_hover_text("Faces meeting at more than this angle draw a crease line.");
    });
    ui.checkbox(&mut s.shaded, "base colours")
        .on_hover_text("Use the materials' base colours (off: uniform grey clay)");
}

/// How the model is lit: the AO look, or the sky light with its environment, rotation and intensity (which
/// re-light the cells' transfer without new rays).
pub fn light(ui: &mut egui::Ui, s: &mut LightSettings) {
    let ppp = ui.ctx().pixels_per_point();
    let toggle = ui.checkbox(&mut s.sky_light, "sky light");
    super::ui_probe::note("sky light", toggle.rect, ppp);
    super::ui_probe::note_text("sky light", if s.sky_light { "on" } else { "off" });
    toggle.on_hover_text(
        "Light the model with an environment and its soft shadows (rays past the AO radius, to the sky) \
         instead of the AO look. The cells keep where their rays escaped: turning the environment or changing \
         it traces no new rays.",
    );
    ui.add_enabled_ui(s.sky_light, |ui| {
        let is_file = s.environment.to_ascii_lowercase().ends_with(".hdr");
        let id = ui.make_persistent_id("environment file");
        let mut path: String = ui.data_mut(|d| d.get_temp::<String>(id)).unwrap_or_default();
        if path.is_empty() && is_file {
            path = s.environment.clone();
        }
        egui::ComboBox::from_label("environment")
            .selected_text(if is_file { "HDR file" } else { s.environment.as_str() })
            .show_ui(ui, |ui| {
                for name in ["uniform", "gradient"] {
                    ui.selectable_value(&mut s.environment, name.to_string(), name);
                }
                if ui.selectable_label(is_file, "HDR file").clicked() && !path.is_empty() {
                    s.environment = path.clone();
                }
            })
            .response
            .on_hover_text(
                "uniform: white light from every direction (an open surface gets 1). gradient: a blue sky over \
                 a brown ground. HDR file: an equirectangular Radiance .hdr image, its centre facing +x.",
            );
        let edit = ui.add(egui::TextEdit::singleline(&mut path).hint_text("equirectangular .hdr file"));
        let usable = path.to_ascii_lowercase().ends_with(".hdr") && std::path::Path::new(&path).is_file();
        if edit.lost_focus() && usable {
            s.environment = path.clone();
        }
        if !path.is_empty() && !usable {
            ui.colored_label(egui::Color32::from_rgb(200, 80, 60), "not a readable .hdr file");
        }
        ui.data_mut(|d| d.insert_temp(id, path));
        let rotation = ui.add(egui::Slider::new(&mut s.environment_rotation, -180.0..=180.0).text("rotation °"));
        super::ui_probe::note("environment rotation", rotation.rect, ppp);
        super::ui_probe::note_text("environment rotation", &format!("{:.0}", s.environment_rotation));
        rotation.on_hover_text("Turns the environment counter-clockwise seen from above (no new rays).");
        ui.add(
            egui::Slider::new(&mut s.environment_intensity, hrtao_core::settings::INTENSITY_RANGE)
                .text("intensity"),
        )
        .on_hover_text("Scales the environment's light.");
    });
}

/// The paper's hash map and sampling; `default_radius` is the scene's default AO radius.
pub fn map(ui: &mut egui::Ui, s: &mut MapSettings, default_radius: f32) {
    ui.add(
        egui::Slider::new(&mut s.s_p, 0.5..=32.0)
            .logarithmic(true)
            .text("s_p"),
    )
    .on_hover_text(
        "s_p (eq. 2): target size in pixels of a hash cell's footprint; the cell size s_w grows with \
         distance. Larger: coarser cells, fewer rays per cell needed, blurrier AO.",
    );
    ui.add(egui::Slider::new(&mut s.s_nd, 0.5..=16.0).text("s_nd"))
        .on_hover_text(
            "s_nd (eq. 5): normal discretisation; cells are keyed by position and quantised normal so \
             surfaces with different orientations don't share AO.",
        );
    let r0 = default_radius;
    ui.horizontal(|ui| {
        ui.add(
            egui::Slider::new(&mut s.ao_radius, r0 * 0.01..=r0 * 20.0)
                .logarithmic(true)
                .text("AO radius"),
        )
        .on_hover_text(
            "AO radius R (§1): occlusion rays longer than this count as unoccluded. Default: 8 mm for the \
             bundled gearbox, 5% of the bounding-box diagonal otherwise.",
        );
        if ui.small_button("↺").on_hover_text("scene default").clicked() {
            s.ao_radius = r0;
        }
    });
    ui.add(
        egui::Slider::new(&mut s.max_samples, 16..=10000)
            .logarithmic(true)
            .text("max samples"),
    )
    .on_hover_text(
        "Maximum samples per cell (§6, 1000 in the paper): a converged cell stops receiving rays, \
         freeing the budget for the others.",
    );
    ui.add(egui::Slider::new(&mut s.min_samples, 0..=256).text("min samples"))
        .on_hover_text(
            "Minimum samples (§4): a cell with fewer samples is replaced by its coarser LOD (eq. 3) \
             until it has gathered enough.",
        );
    additions(ui, s.additions_mut());
    let mut log2 = s.hash_capacity.trailing_zeros();
    ui.add(
        egui::Slider::new(&mut log2, 10..=26)
            .text("hash capacity (log2)")
            .custom_formatter(|v, _| format!("2^{v} = {}", 1u64 << v as u32)),
    )
    .on_hover_text(
        "Hash map capacity in cells (§1, §6): the world-space cache of AO values. Changing it empties the \
         cache. Watch the load factor and failed inserts in the statistics.",
    );
    s.hash_capacity = 1 << log2;
}

/// The adaptive à-trous filter.
pub fn filter(ui: &mut egui::Ui, s: &mut FilterSettings) {
    ui.horizontal(|ui| {
        ui.add(
            egui::Slider::new(
                &mut s.filter_iterations,
                0..=hrtao_core::settings::MAX_FILTER_ITERATIONS,
            )
            .text("filter iterations"),
        )
        .on_hover_text(
            "Adaptive à-trous filter (§5): each iteration doubles its reach; the footprint follows the cell \
                 size. 0: no filter.",
        );
        additions(ui, s.additions_mut());
    });
}

/// The first frames of a young map.
pub fn young(ui: &mut egui::Ui, s: &mut YoungMapSettings) {
    ui.label("first frames (ours, docs/algorithm.md):");
    additions(ui, s.additions_mut());
}

/// Still-camera refinement.
pub fn still(ui: &mut egui::Ui, s: &mut StillSettings) {
    ui.horizontal(|ui| {
        ui.checkbox(&mut s.refine, "refine when still").on_hover_text(
            "Ours (docs/algorithm.md): while the view rests, each pixel traces its own rays and its AO converges \
             from the cell estimate to the ray-traced value, with anti-aliasing. Off: the paper's behaviour.",
        );
        ui.add_enabled(
            s.refine,
            egui::Slider::new(&mut s.still_samples, 8..=4096)
                .logarithmic(true)
                .text("rays per pixel"),
        )
        .on_hover_text("A still image is final once every pixel has this many rays of its own.");
    });
    let others = s
        .additions_mut()
        .into_iter()
        .filter(|a| a.name != "refine")
        .collect();
    additions(ui, others);
}

/// Scene edits.
pub fn edits(ui: &mut egui::Ui, s: &mut EditSettings) {
    additions(ui, s.additions_mut());
}

/// Our additions of a group, a checkbox each with the setting's doc as its hover text (`additions_mut`): a new
/// addition shows here without a line of panel code.
fn additions(ui: &mut egui::Ui, list: Vec<hrtao_core::settings::Addition<'_>>) {
    ui.horizontal_wrapped(|ui| {
        for a in list {
            let (label, text) = (a.label(), a.text());
            ui.checkbox(a.on, label).on_hover_text(text);
        }
    });
}
