//! The panel (settings with the paper's references, statistics, selection, camera, screenshots), the 3D view's
//! mouse/keyboard navigation and picking, and the toasts.
use std::time::Instant;

use egui::{Key, PointerButton};
use glam::Vec3;
use hrtao_core::camera::Projection;
use hrtao_core::{Camera, Mode};

use super::edits::{Action, Edit};
use super::nav::{self, StdView};
use super::prefs::Bookmark;
use super::Viewer;

const ORBIT_RAD_PER_PX: f32 = 0.008;
const LOOK_RAD_PER_PX: f32 = 0.004;

/// The key/mouse bindings, shown in the help section (and in the README).
pub const BINDINGS: &[(&str, &str)] = &[
    ("Left drag", "orbit around the pivot"),
    ("Middle drag / Shift+left drag", "pan"),
    ("Wheel", "zoom toward the cursor"),
    ("Right drag", "fly: look around"),
    (
        "W A S D / Q E (Shift: faster)",
        "fly: forward, left, back, right / down, up",
    ),
    (
        "Double-click",
        "set the orbit pivot on the surface under the cursor",
    ),
    ("F", "frame the selection (nothing selected: fit all)"),
    ("Home", "fit all"),
    ("1 / 3 / 7", "front / right / top view (as Blender's numpad)"),
    ("Ctrl+1 / Ctrl+3 / Ctrl+7", "back / left / bottom view"),
    ("9", "opposite view: look from the other side of the pivot"),
    ("0", "isometric view"),
    ("5", "perspective / orthographic"),
    ("Enter", "reset to the initial camera"),
    ("Click", "select an instance (click background: deselect)"),
    (
        "Shift+click / Ctrl+click",
        "add an instance (or a model tree node) to the selection, or remove it; move, hide and delete act on \
         all of it as one undo step",
    ),
    (
        "Ctrl+left drag",
        "move the selection along the world axis closest to the drag",
    ),
    (
        "Arrow keys / PgUp PgDn (Shift: x10)",
        "move the selection by 1% of the scene size",
    ),
    (
        "Ctrl+Shift+left drag",
        "move the active section plane along its normal (Section planes panel)",
    ),
    ("H", "hide / show the selection (a tree node: its whole subtree)"),
    ("I / U", "isolate the selection / show all"),
    (
        "M",
        "measure mode: click two surface points (distance and dx dy dz over the view)",
    ),
    ("Delete", "delete the selection"),
    (
        "Esc",
        "deselect (in measure mode: clear the points; during a background screenshot: cancel it)",
    ),
    ("Ctrl+Z / Ctrl+Y (Ctrl+Shift+Z)", "undo / redo"),
    (
        "Ctrl+O",
        "Open… dialog (desktop portal, or zenity); drop a model file on the window to open it too",
    ),
    (
        "F12",
        "screenshot of the 3D view (no UI) as MODEL-YYYYMMDD-HHMMSS.png in the pictures directory (or the \
         panel's folder)",
    ),
    (
        "Tab",
        "show / hide the panel (also while a panel widget has the keyboard focus)",
    ),
    ("F11", "full screen on / off"),
    ("Ctrl+Q", "quit"),
];

impl Viewer {
    pub(crate) fn ui(&mut self, ctx: &egui::Context) {
        self.frame_started = Instant::now();
        self.global_keys(ctx);
        self.poll_loading();
        self.script_orbit();
        if let Some(d) = self.script.deadline {
            if Instant::now() > d {
                self.script.deadline = None;
                self.fatal("scripted run timed out (--timeout)".into());
            }
        }
        // Dropped files open like the Open button.
        let dropped: Vec<_> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .filter_map(|f| f.path.clone())
                .collect()
        });
        self.open_dropped(&dropped);
        self.poll_open_dialog();
        if self.show_panel {
            egui::SidePanel::right("panel")
                .resizable(true)
                .default_width(480.0)
                .show(ctx, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
                });
        }
        egui::CentralPanel::default()
            .frame(egui::Frame::none())
            .show(ctx, |ui| {
                let rect = ui.max_rect();
                let ppp = ctx.pixels_per_point();
                self.view_rect = [
                    (rect.min.x * ppp).round() as i32,
                    (rect.min.y * ppp).round() as i32,
                    (rect.width() * ppp).round().max(1.0) as i32,
                    (rect.height() * ppp).round().max(1.0) as i32,
                ];
                self.laid_out = true;
                let resp = ui.allocate_rect(rect, egui::Sense::click_and_drag());
                self.view_input(ctx, &resp, rect);
                self.measure_overlay(ui.painter(), rect);
                if let Some(l) = &self.loading {
                    let text = format!(
                        "Loading {} … {} ({:.0} s)",
                        l.spec,
                        l.progress,
                        l.started.elapsed().as_secs_f32()
                    );
                    let area = egui::Rect::from_center_size(rect.center(), egui::vec2(400.0, 80.0));
                    let cancel = ui
                        .allocate_ui_at_rect(area, |ui| {
                            ui.vertical_centered(|ui| {
                                ui.label(egui::RichText::new(text).heading());
                                ui.button("Cancel").clicked()
                            })
                            .inner
                        })
                        .inner;
                    if cancel {
                        self.cancel_loading();
                    }
                }
            });
        self.keyboard(ctx);
        self.draw_toasts(ctx);
        self.draw_shot_overlay(ctx);
    }

    /// Keys that act whatever has the keyboard focus, read before any widget runs: Tab toggles the panel and
    /// F12 takes a screenshot. egui moves the focus between widgets on Tab (and arrow keys); that focus made
    /// every later shortcut wait for a click elsewhere, so focus gained by keyboard navigation is dropped again.
    fn global_keys(&mut self, ctx: &egui::Context) {
        let (tabs, shots) = ctx.input(|i| (key_taps(&i.events, Key::Tab), key_taps(&i.events, Key::F12)));
        if tabs % 2 == 1 {
            self.show_panel = !self.show_panel;
        }
        if shots > 0 {
            self.request_screenshot();
        }
        self.drop_nav_focus = tabs > 0;
    }

    /// Is the user typing into a text field (then letters are text, not shortcuts)?
    fn typing(&self, ctx: &egui::Context) -> bool {
        ctx.memory(|m| m.focus())
            .is_some_and(|id| egui::TextEdit::load_state(ctx, id).is_some())
    }

    fn panel(&mut self, ui: &mut egui::Ui) {
        let software = self.gpu.info.is_software;
        ui.heading("hrtao");
        ui.label(format!("Device: {} ({})", self.gpu.info.name, self.gpu.info.kind))
            .on_hover_text(format!("driver {}", self.gpu.info.driver));
        if software {
            ui.colored_label(
                egui::Color32::from_rgb(230, 160, 40),
                "software device: render scale starts low",
            );
        }

        egui::CollapsingHeader::new("Scene")
            .default_open(true)
            .show(ui, |ui| self.scene_section(ui));
        let load_options = egui::CollapsingHeader::new("Load options")
            .default_open(false)
            .show(ui, |ui| self.load_options_section(ui));
        self.ui_probe.note(
            "Load options",
            load_options.header_response.rect,
            ui.ctx().pixels_per_point(),
        );
        egui::CollapsingHeader::new("Ambient occlusion")
            .default_open(true)
            .show(ui, |ui| self.ao_section(ui));
        egui::CollapsingHeader::new("Statistics")
            .default_open(true)
            .show(ui, |ui| self.stats_section(ui));
        // Opened once when a scene comes with planes (--section).
        let open = std::mem::take(&mut self.section_state.reveal).then_some(true);
        egui::CollapsingHeader::new("Section planes")
            .default_open(false)
            .open(open)
            .show(ui, |ui| self.sections_section(ui));
        egui::CollapsingHeader::new("Model tree")
            .default_open(true)
            .show(ui, |ui| self.tree_section(ui));
        egui::CollapsingHeader::new("Selection")
            .default_open(true)
            .show(ui, |ui| self.selection_section(ui));
        egui::CollapsingHeader::new("Measure")
            .default_open(true)
            .show(ui, |ui| self.measure_section(ui));
        egui::CollapsingHeader::new("Camera")
            .default_open(false)
            .show(ui, |ui| self.camera_section(ui));
        egui::CollapsingHeader::new("Screenshot")
            .default_open(false)
            .show(ui, |ui| self.screenshot_section(ui));
        egui::CollapsingHeader::new("Keys and mouse")
            .default_open(false)
            .show(ui, |ui| {
                egui::Grid::new("bindings").striped(true).show(ui, |ui| {
                    for (k, v) in BINDINGS {
                        ui.label(*k);
                        ui.label(*v);
                        ui.end_row();
                    }
                });
            });
    }

    fn scene_section(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let edit = ui.add(
                egui::TextEdit::singleline(&mut self.open_path)
                    .hint_text("file.glb / .gltf / .obj / gen:city")
                    .desired_width(200.0),
            );
            let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
            if (ui.button("Open").clicked() || enter) && self.loading.is_none() {
                let p = self.open_path.trim().to_string();
                self.start_loading(p);
            }
            if ui
                .add_enabled(self.open_dialog.is_none(), egui::Button::new("Open…"))
                .on_hover_text("Choose a file (desktop portal, or zenity when no portal runs)")
                .clicked()
            {
                self.open_file_dialog();
            }
        })
        .response
        .on_hover_text(
            "Open a glTF/GLB/OBJ file or a generator spec (drag & drop a file onto the window too)",
        );
        if ui.button("Open the bundled scene").clicked() && self.loading.is_none() {
            self.start_loading(super::default_spec());
        }
        if let Some(l) = &self.loading {
            let cancel = ui
                .horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("loading: {}", l.progress));
                    ui.button("Cancel")
                        .on_hover_text("Stop loading; the current scene stays")
                        .clicked()
                })
                .inner;
            if cancel {
                self.cancel_loading();
            }
        }
        if let Some(e) = &self.load_error {
            ui.colored_label(egui::Color32::from_rgb(230, 80, 70), e);
        }
        if let Some(scene) = &self.scene {
            ui.label(format!("{}  ({})", scene.name, self.scene_spec));
            self.dimensions_row(ui);
        }
    }

    fn ao_section(&mut self, ui: &mut egui::Ui) {
        let mut s = self.prefs.settings.clone();
        super::settings_panel::display(ui, &mut s.display);
        ui.add_enabled(
            !self.prefs.auto_budget,
            egui::Slider::new(
                &mut self.prefs.rays_per_frame,
                super::budget::MIN_RAYS_PER_FRAME..=16_000_000,
            )
            .logarithmic(true)
            .text("rays / frame"),
        )
        .on_hover_text(
            "Ray budget (§3, §6): rays traced per frame whatever the resolution, shared between the hash \
             cells visible in the image (collaborative ray tracing); the renderer gets it as rays per pixel \
             (at least 1). Higher: faster convergence, slower frames.",
        );
        super::settings_panel::map(ui, &mut s.map, self.default_radius);
        super::settings_panel::filter(ui, &mut s.filter);
        super::settings_panel::still(ui, &mut s.still);
        super::settings_panel::young(ui, &mut s.young);
        super::settings_panel::edits(ui, &mut s.edits);
        ui.separator();
        let blit = self.presenter.blit_ok || self.presenter.images.is_empty();
        ui.add_enabled(
            blit,
            egui::Slider::new(&mut self.render_scale, 0.1..=1.0).text("max render scale"),
        )
        .on_hover_text(
            "Internal resolution of a still image as a fraction of the 3D view (blitted to the window). While \
             the camera moves the resolution drops to meet the frame-time target (not below 0.35 of the view \
             unless this cap is lower). s_p counts view pixels, so the hash cells do not change with it.",
        );
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.prefs.auto_budget, "frame-time target")
                .on_hover_text(
                "§6: \"the ray budget can be adjusted to match a target rendering speed\": while the camera \
                 moves, the ray budget and the render scale adapt to reach the target frame time.",
            );
            ui.add_enabled(
                self.prefs.auto_budget,
                egui::DragValue::new(&mut self.prefs.target_ms)
                    .clamp_range(5.0..=2000.0)
                    .suffix(" ms target"),
            );
        });
        ui.horizontal(|ui| {
            if ui
                .button("Clear cache")
                .on_hover_text("Forget all cached AO (the hash map restarts empty)")
                .clicked()
            {
                if let Some(r) = &mut self.renderer {
                    if let Err(e) = r.clear_cache() {
                        self.toasts.push(super::Toast {
                            text: format!("{e}"),
                            error: true,
                            until: Instant::now() + std::time::Duration::from_secs(6),
                        });
                    }
                }
            }
            if ui
                .button("Defaults")
                .on_hover_text("AoSettings::default() with the scene's radius")
                .clicked()
            {
                s = hrtao_core::AoSettings::default().with_radius(self.default_radius);
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
        if s != self.prefs.settings {
            self.apply_settings(s);
        }
    }

    /// Settings changed in the panel (or by --set-at-frame): checked, then the next frame's.
    pub(crate) fn apply_settings(&mut self, s: hrtao_core::AoSettings) {
        match s.validate() {
            Ok(()) => self.prefs.settings = s,
            Err(e) => self.toast(format!("settings: {e}"), true),
        }
    }

    fn stats_section(&mut self, ui: &mut egui::Ui) {
        let Some(rep) = &self.last_report else {
            ui.label("no frame yet");
            return;
        };
        let (iw, ih) = self.renderer.as_ref().map(|r| r.size()).unwrap_or((0, 0));
        egui::Grid::new("stats").striped(true).show(ui, |ui| {
            let mut row = |k: &str, v: String| {
                ui.label(k);
                ui.label(v);
                ui.end_row();
            };
            row(
                "frame",
                format!(
                    "{:.1} ms render, {:.1} ms interval ({:.1} fps)",
                    self.frame_ms_avg,
                    self.interval_ms_avg,
                    1000.0 / self.interval_ms_avg.max(1e-3)
                ),
            );
            if rep.gpu_ms.is_empty() {
                row("GPU passes", "not timed on this device (see frame)".to_string());
            } else {
                row("GPU total", format!("{:.2} ms", rep.gpu_total_ms));
            }
            for (name, ms) in &rep.gpu_ms {
                row(&format!("  {name}"), format!("{ms:.2} ms"));
            }
            row(
                "resolution",
                format!(
                    "{iw}×{ih} internal ({:.0}% of the view)",
                    100.0 * iw as f32 / self.view_rect[2].max(1) as f32
                ),
            );
            row(
                "image",
                if super::motion::image_converged(rep) {
                    format!("converged ({} frames)", rep.accumulated_frames)
                } else {
                    format!("refining ({} frames)", rep.accumulated_frames)
                },
            );
            row(
                "rays",
                format!(
                    "{} ({:.2}/px)",
                    rep.rays,
                    rep.rays as f64 / (iw * ih).max(1) as f64
                ),
            );
            if self.prefs.settings.display.mode.uses_hash() {
                row(
                    "hash cells",
                    format!(
                        "{} / {} ({:.1}% load)",
                        rep.occupied_cells,
                        self.prefs.settings.map.hash_capacity,
                        rep.load_factor * 100.0
                    ),
                );
                row("failed inserts", rep.failed_inserts.to_string());
                row("longest probe", rep.longest_probe.to_string());
            } else if self.prefs.settings.display.mode == Mode::Rtao {
                row("accumulated", format!("{} frames", rep.accumulated_frames));
            }
            if let Some(scene) = &self.scene {
                row("F (scene frame)", scene.f().to_string());
                for (label, value) in super::stats::scene_rows(scene) {
                    row(label, value);
                }
                row(
                    "triangles",
                    format!("{} unique", fmt_count(scene.unique_triangle_count())),
                );
                row(
                    "",
                    format!("{} instanced", fmt_count(scene.instanced_triangle_count())),
                );
            }
            row(
                "validation",
                format!("{} messages", self.gpu.validation_messages()),
            );
        });
    }

    fn selection_section(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let undo = self.edits.undo_label();
            if ui
                .add_enabled(undo.is_some(), egui::Button::new("Undo"))
                .on_hover_text(undo.unwrap_or_default())
                .clicked()
            {
                self.edit(Action::Undo);
            }
            let redo = self.edits.redo_label();
            if ui
                .add_enabled(redo.is_some(), egui::Button::new("Redo"))
                .on_hover_text(redo.unwrap_or_default())
                .clicked()
            {
                self.edit(Action::Redo);
            }
        });
        let sel = self.selected;
        let Some(inst) = self
            .scene
            .as_ref()
            .and_then(|s| s.instances.get(sel as usize))
            .cloned()
        else {
            if !self.selection_summary(ui) {
                ui.label("click an instance (or a model tree node) to select it");
            }
            return;
        };
        ui.label(format!(
            "#{sel} {}",
            if inst.name.is_empty() {
                "(unnamed)"
            } else {
                &inst.name
            }
        ));
        let mut visible = inst.visible;
        if ui.checkbox(&mut visible, "visible").changed() {
            self.edit(Action::Apply(Edit::Visibility {
                instance: sel,
                visible,
            }));
        }
        let pos = inst.transform.w_axis.truncate();
        let mut p = pos;
        let step = self.move_step();
        ui.horizontal(|ui| {
            ui.label("position");
            for (c, name) in [(&mut p.x, "x"), (&mut p.y, "y"), (&mut p.z, "z")] {
                ui.add(
                    egui::DragValue::new(c)
                        .speed(step * 0.1)
                        .prefix(format!("{name} ")),
                );
            }
        });
        if p != pos {
            self.move_selected(p - pos);
        }
        ui.horizontal(|ui| {
            if ui.button("Delete").clicked() {
                self.edit(Action::Apply(Edit::Delete {
                    instance: sel,
                    removed: None,
                }));
                self.set_selected(u32::MAX);
            }
            if ui.button("Deselect").clicked() {
                self.set_selected(u32::MAX);
            }
        });
    }

    fn camera_section(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if ui.button("Fit (F)").clicked() {
                self.fit_all();
            }
            for (label, v) in [
                ("Front", StdView::Front),
                ("Right", StdView::Right),
                ("Top", StdView::Top),
                ("Iso", StdView::Iso),
            ] {
                if ui.button(label).clicked() {
                    self.std_view(v);
                }
            }
            if ui.button("Reset").clicked() {
                self.reset_view();
            }
        });
        ui.horizontal(|ui| {
            let mut ortho = self.nav.cam.is_orthographic();
            if ui
                .checkbox(&mut ortho, "Orthographic (5)")
                .on_hover_text("parallel projection; front/right/top views switch to it")
                .changed()
            {
                self.toggle_projection();
            }
        });
        if self.nav.cam.is_orthographic() {
            let h = self.nav.cam.ortho_height;
            ui.add(
                egui::DragValue::new(&mut self.nav.cam.ortho_height)
                    .speed(h * 0.01)
                    .clamp_range(h * 1e-3..=h * 1e3)
                    .prefix("view height "),
            );
        } else {
            ui.add(egui::Slider::new(&mut self.nav.cam.fov_y_deg, 5.0..=120.0).text("field of view"));
        }
        ui.horizontal(|ui| {
            ui.add(
                egui::TextEdit::singleline(&mut self.bookmark_name)
                    .hint_text("bookmark name")
                    .desired_width(160.0),
            );
            if ui.button("Save view").clicked() {
                let name = if self.bookmark_name.trim().is_empty() {
                    format!("view {}", self.prefs.bookmarks.len() + 1)
                } else {
                    self.bookmark_name.trim().to_string()
                };
                self.prefs.bookmarks.push(Bookmark {
                    name,
                    scene: self.scene_spec.clone(),
                    camera: self.nav.cam,
                });
                self.bookmark_name.clear();
            }
        });
        let mut go = None;
        let mut remove = None;
        for (i, b) in self.prefs.bookmarks.iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.button(&b.name).on_hover_text(&b.scene).clicked() {
                    go = Some(b.camera);
                }
                if ui.small_button("✖").on_hover_text("remove").clicked() {
                    remove = Some(i);
                }
            });
        }
        if let Some(c) = go {
            self.nav.cam = c;
            self.nav.pivot = nav::target(&c);
        }
        if let Some(i) = remove {
            self.prefs.bookmarks.remove(i);
        }
        if ui.button("Copy camera JSON").clicked() {
            let mut cam: Camera = self.nav.cam;
            cam.width = self.view_rect[2].max(1) as u32;
            cam.height = self.view_rect[3].max(1) as u32;
            let text = serde_json::to_string_pretty(&cam).unwrap_or_default();
            ui.output_mut(|o| o.copied_text = text);
        }
    }

    fn screenshot_section(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.label("folder");
            let mut dir = self
                .prefs
                .screenshot_folder
                .as_ref()
                .map(|d| d.display().to_string())
                .unwrap_or_default();
            let pictures = super::prefs::pictures_dir()
                .map_or("the pictures directory".to_string(), |d| d.display().to_string());
            if ui
                .add(egui::TextEdit::singleline(&mut dir).hint_text(pictures))
                .on_hover_text("Where F12 saves MODEL-YYYYMMDD-HHMMSS.png; empty: the pictures directory")
                .changed()
            {
                self.prefs.screenshot_folder =
                    Some(dir.trim().into()).filter(|d: &std::path::PathBuf| !d.as_os_str().is_empty());
            }
        });
        ui.checkbox(&mut self.prefs.screenshot_custom, "custom resolution")
            .on_hover_text(
                "Rendered in the background at this size, tile by tile, each tile until its still image has \
             converged (anti-aliased), while the view keeps drawing; else the 3D view's window resolution",
            );
        ui.add_enabled_ui(self.prefs.screenshot_custom, |ui| {
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(&mut self.prefs.screenshot_width).clamp_range(16..=16384));
                ui.label("×");
                ui.add(egui::DragValue::new(&mut self.prefs.screenshot_height).clamp_range(16..=16384));
            });
        });
        ui.add_enabled_ui(!self.prefs.screenshot_custom, |ui| {
            ui.add(egui::Slider::new(&mut self.prefs.screenshot_frames, 1..=4).text("frames"))
                .on_hover_text(
                    "Frames rendered for a window-resolution screenshot (the cache is already warm); a custom \
                     size renders until converged.",
                );
        });
        if let Some((fraction, status)) = self.shot_progress() {
            ui.add(egui::ProgressBar::new(fraction).text(status));
            if self.background_shot.is_some() && ui.button("Cancel screenshot").clicked() {
                self.cancel_background_shot("");
            }
        } else if ui.button("Take screenshot (F12)").clicked() {
            self.request_screenshot();
        }
    }

    /// A background screenshot's progress and Cancel over the 3D view while the panel is hidden.
    fn draw_shot_overlay(&mut self, ctx: &egui::Context) {
        let Some((fraction, status)) = self.shot_progress().filter(|_| !self.show_panel) else {
            return;
        };
        let mut cancel = false;
        egui::Area::new("screenshot progress")
            .anchor(egui::Align2::RIGHT_TOP, [-10.0, 10.0])
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    ui.add(egui::ProgressBar::new(fraction).desired_width(260.0).text(status));
                    cancel = self.background_shot.is_some() && ui.button("Cancel screenshot").clicked();
                });
            });
        if cancel {
            self.cancel_background_shot("");
        }
    }

    fn draw_toasts(&mut self, ctx: &egui::Context) {
        let now = Instant::now();
        self.toasts.retain(|t| t.until > now);
        let Some(first_expiry) = self.toasts.iter().map(|t| t.until).min() else {
            return;
        };
        // Repaint when the first toast expires (the loop rests otherwise).
        ctx.request_repaint_after(first_expiry - now);
        egui::Area::new("toasts")
            .anchor(egui::Align2::LEFT_BOTTOM, [10.0, -10.0])
            .interactable(false)
            .show(ctx, |ui| {
                for t in &self.toasts {
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        let color = if t.error {
                            egui::Color32::from_rgb(240, 90, 80)
                        } else {
                            ui.visuals().text_color()
                        };
                        ui.colored_label(color, &t.text);
                    });
                }
            });
    }

    /// Mouse input over the 3D view.
    fn view_input(&mut self, ctx: &egui::Context, resp: &egui::Response, rect: egui::Rect) {
        let ppp = ctx.pixels_per_point();
        let delta = view_drag_delta(ctx, resp) * ppp;
        // A drag in progress keeps the view "moving" (reduced resolution) even in frames without a new delta;
        // a press whose drag has not moved yet holds the view (`Motion::holds`).
        let acted = delta != egui::Vec2::ZERO;
        self.motion.drag(resp.dragged(), acted);
        if self.scene.is_none() {
            return;
        }
        let (shift, ctrl) = ctx.input(|i| (i.modifiers.shift, i.modifiers.command));
        let world_up = self.nav.world_up.vector();
        let view_h = self.view_rect[3].max(1) as f32;
        // A press that has not moved changes nothing (no section plane or part moved, no camera re-derived).
        if acted {
            if resp.dragged_by(PointerButton::Primary) && ctrl && shift {
                self.drag_section(delta);
            } else if resp.dragged_by(PointerButton::Primary) && ctrl && !self.selection.instances.is_empty()
            {
                self.drag_move(delta);
            } else if resp.dragged_by(PointerButton::Middle)
                || (resp.dragged_by(PointerButton::Primary) && shift)
            {
                // Pan moves the pivot with the view.
                let wpp = nav::world_per_pixel(&self.nav.cam, view_h);
                let d = (-delta.x * nav::right(&self.nav.cam) + delta.y * nav::cam_up(&self.nav.cam)) * wpp;
                self.nav.pivot += d;
                self.nav.cam = nav::pan(&self.nav.cam, delta.x, delta.y, view_h);
            } else if resp.dragged_by(PointerButton::Primary) {
                self.nav.cam = nav::orbit(
                    &self.nav.cam,
                    self.nav.pivot,
                    world_up,
                    -delta.x * ORBIT_RAD_PER_PX,
                    -delta.y * ORBIT_RAD_PER_PX,
                );
            } else if resp.dragged_by(PointerButton::Secondary) {
                self.nav.cam = nav::fly_look(
                    &self.nav.cam,
                    world_up,
                    -delta.x * LOOK_RAD_PER_PX,
                    -delta.y * LOOK_RAD_PER_PX,
                );
                self.nav.pivot = nav::target(&self.nav.cam);
            }
        }
        let scroll = ctx.input(|i| i.scroll_delta.y);
        if resp.hovered() && scroll != 0.0 {
            if let Some(pos) = resp.hover_pos() {
                let ray = self.view_ray(pos, rect, ppp);
                let factor = (-scroll * 0.0025).exp();
                self.nav.cam = nav::zoom_to(&self.nav.cam, ray, factor);
            }
        }
        if resp.double_clicked() {
            if let Some(p) = resp.interact_pointer_pos().and_then(|p| self.pick(p, rect, ppp)) {
                let pos = Vec3::from(p.0);
                self.nav.pivot = pos;
                // Same view; the focal distance becomes the pivot's depth (zoom speed follows).
                let c = self.nav.cam;
                let f = nav::forward(&c);
                let depth = (pos - nav::eye(&c)).dot(f).max(1e-4);
                self.nav.cam.target = (nav::eye(&c) + f * depth).to_array();
                self.toast(
                    format!("pivot set to ({:.2}, {:.2}, {:.2})", pos.x, pos.y, pos.z),
                    false,
                );
            }
        } else if resp.clicked() && self.measure.active {
            if let Some(hit) = resp.interact_pointer_pos().and_then(|p| self.pick(p, rect, ppp)) {
                self.measure_pick(hit.0);
            }
        } else if resp.clicked() {
            let hit = resp.interact_pointer_pos().and_then(|p| self.pick(p, rect, ppp));
            let sel = hit.map(|h| h.1).unwrap_or(u32::MAX);
            if super::selection::click_toggles(ctx) {
                self.toggle_selected(sel);
            } else if sel != self.selected {
                self.set_selected(sel);
            }
        }
    }

    /// World-space ray (origin, unit direction) through a point of the view (egui points).
    fn view_ray(&self, pos: egui::Pos2, rect: egui::Rect, ppp: f32) -> (Vec3, Vec3) {
        let cam = Camera {
            width: self.view_rect[2].max(1) as u32,
            height: self.view_rect[3].max(1) as u32,
            ..self.nav.cam
        };
        let x = (pos.x - rect.min.x) * ppp;
        let y = (pos.y - rect.min.y) * ppp;
        cam.ray(x - 0.5, y - 0.5)
    }

    /// Switches perspective / orthographic keeping the framing at the pivot.
    pub(crate) fn toggle_projection(&mut self) {
        let next = match self.nav.cam.projection {
            Projection::Perspective => Projection::Orthographic,
            Projection::Orthographic => Projection::Perspective,
        };
        self.nav.cam = nav::set_projection(&self.nav.cam, self.nav.pivot, next);
        log::info!(
            "projection: {next:?} (view height at the pivot {:.4})",
            nav::world_per_pixel(&self.nav.cam, 1.0)
        );
    }

    /// Picks the surface under a view point from the last frame's G-buffer: (position, instance).
    fn pick(&mut self, pos: egui::Pos2, rect: egui::Rect, ppp: f32) -> Option<([f32; 3], u32)> {
        let r = self.renderer.as_ref()?;
        let (iw, ih) = r.size();
        let fx = (pos.x - rect.min.x) * ppp / self.view_rect[2].max(1) as f32;
        let fy = (pos.y - rect.min.y) * ppp / self.view_rect[3].max(1) as f32;
        if !(0.0..1.0).contains(&fx) || !(0.0..1.0).contains(&fy) {
            return None;
        }
        let (x, y) = ((fx * iw as f32) as u32, (fy * ih as f32) as u32);
        self.gpu.wait_idle();
        match r.pick(x, y) {
            Ok(Some(px)) => Some(([px.position[0], px.position[1], px.position[2]], px.instance)),
            Ok(None) => None,
            Err(e) => {
                self.toast(format!("pick failed: {e}"), true);
                None
            }
        }
    }

    fn move_step(&self) -> f32 {
        self.scene
            .as_ref()
            .map(|s| s.bounds().diagonal().length() * 0.01)
            .unwrap_or(1.0)
            .max(1e-6)
    }

    /// Moves the selection by a world offset (one edit for all selected instances: F increments, TLAS rebuilt;
    /// drags merge in undo).
    fn move_selected(&mut self, d: Vec3) {
        let edit = self
            .scene
            .as_ref()
            .and_then(|s| Edit::move_all(s, &self.selection.instances, d));
        if let Some(e) = edit {
            self.edit(Action::Apply(e));
        }
    }

    /// Ctrl+drag: move along the world axis whose screen projection best matches the drag.
    fn drag_move(&mut self, delta: egui::Vec2) {
        if delta == egui::Vec2::ZERO {
            return;
        }
        let c = self.nav.cam;
        let (r, u) = (nav::right(&c), nav::cam_up(&c));
        let drag = glam::Vec2::new(delta.x, -delta.y);
        let mut best = (0.0f32, Vec3::X, glam::Vec2::X);
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let s = glam::Vec2::new(axis.dot(r), axis.dot(u));
            if s.length() < 0.2 {
                continue;
            }
            let score = s.normalize().dot(drag.normalize()).abs();
            if score > best.0 {
                best = (score, axis, s);
            }
        }
        let (_, axis, s) = best;
        let wpp = nav::world_per_pixel(&c, self.view_rect[3].max(1) as f32);
        let amount = drag.dot(s.normalize()) * wpp / s.length();
        self.move_selected(axis * amount);
    }

    fn fit_all(&mut self) {
        if let Some(s) = &self.scene {
            let b = s.bounds();
            self.fit_box(b);
        }
    }

    /// F with a selection: frames the selected instances' bounds (the view direction stays).
    fn frame_selection(&mut self) {
        let Some(s) = &self.scene else {
            return;
        };
        let b = self
            .selection
            .instances
            .iter()
            .map(|&i| s.instance_bounds(i))
            .fold(hrtao_scene::Aabb::empty(), |a, b| a.union(&b));
        if b.is_empty() {
            return self.fit_all();
        }
        log::info!(
            "framed the selection: {} instances, centre {:?}",
            self.selection.instances.len(),
            b.center().to_array()
        );
        self.fit_box(b);
    }

    fn fit_box(&mut self, b: hrtao_scene::Aabb) {
        {
            let (c, p) = nav::fit(&self.view_cam(), b.min, b.max);
            self.nav.cam = Camera {
                width: self.nav.cam.width,
                height: self.nav.cam.height,
                ..c
            };
            self.nav.pivot = p;
        }
    }

    fn std_view(&mut self, v: StdView) {
        if let Some(s) = &self.scene {
            let b = s.bounds();
            let (c, p) = nav::std_view(&self.view_cam(), v, self.nav.world_up, b.min, b.max);
            self.nav.cam = Camera {
                width: self.nav.cam.width,
                height: self.nav.cam.height,
                ..c
            };
            self.nav.pivot = p;
        }
    }

    fn reset_view(&mut self) {
        self.nav.cam = self.home;
        self.nav.pivot = nav::target(&self.home);
    }

    /// The camera with the 3D view's aspect (for fitting).
    fn view_cam(&self) -> Camera {
        Camera {
            width: self.view_rect[2].max(1) as u32,
            height: self.view_rect[3].max(1) as u32,
            ..self.nav.cam
        }
    }

    fn keyboard(&mut self, ctx: &egui::Context) {
        if self.drop_nav_focus {
            // Tab is ours: nothing keeps the focus egui gave to a widget for it.
            ctx.memory_mut(|m| m.stop_text_input());
            self.drop_nav_focus = false;
        }
        if self.typing(ctx) {
            return;
        }
        let (pressed, down, mods, dt) = ctx.input(|i| {
            let keys = [
                Key::F,
                Key::Home,
                Key::Num1,
                Key::Num3,
                Key::Num7,
                Key::Num9,
                Key::Num0,
                Key::Num5,
                Key::F11,
                Key::Q,
                Key::Enter,
                Key::Delete,
                Key::H,
                Key::I,
                Key::U,
                Key::M,
                Key::Escape,
                Key::Z,
                Key::Y,
                Key::O,
                Key::ArrowLeft,
                Key::ArrowRight,
                Key::ArrowUp,
                Key::ArrowDown,
                Key::PageUp,
                Key::PageDown,
            ];
            // Each key with the modifiers held when it was pressed (a quick Ctrl+Z can press and release Ctrl
            // within one frame's events).
            let held = |k: Key| {
                i.events
                    .iter()
                    .rev()
                    .find_map(|e| match e {
                        egui::Event::Key {
                            key,
                            pressed: true,
                            modifiers,
                            ..
                        } if *key == k => Some(*modifiers),
                        _ => None,
                    })
                    .unwrap_or(i.modifiers)
            };
            let pressed: Vec<(Key, egui::Modifiers)> = keys
                .into_iter()
                .filter(|k| i.key_pressed(*k))
                .map(|k| (k, held(k)))
                .collect();
            // Fly keys, not while Ctrl is held (Ctrl+Q quits, Ctrl+S…).
            let down: Vec<Key> = [Key::W, Key::A, Key::S, Key::D, Key::Q, Key::E]
                .into_iter()
                .filter(|k| i.key_down(*k) && !i.modifiers.command)
                .collect();
            (pressed, down, i.modifiers, i.stable_dt.min(0.25))
        });
        for (k, mods) in pressed {
            match k {
                Key::F if !self.selection.instances.is_empty() => self.frame_selection(),
                Key::F | Key::Home => self.fit_all(),
                Key::Num1 if mods.command => self.std_view(StdView::Back),
                Key::Num3 if mods.command => self.std_view(StdView::Left),
                Key::Num7 if mods.command => self.std_view(StdView::Bottom),
                Key::Num1 => self.std_view(StdView::Front),
                Key::Num3 => self.std_view(StdView::Right),
                Key::Num7 => self.std_view(StdView::Top),
                Key::Num9 => {
                    self.nav.cam = nav::opposite(&self.nav.cam, self.nav.pivot);
                }
                Key::Num0 => self.std_view(StdView::Iso),
                Key::Num5 => self.toggle_projection(),
                Key::F11 => {
                    self.fullscreen = !self.fullscreen;
                    log::info!("full screen {}", if self.fullscreen { "on" } else { "off" });
                    ctx.send_viewport_cmd(egui::ViewportCommand::Fullscreen(self.fullscreen));
                }
                Key::Q if mods.command => {
                    log::info!("quit (Ctrl+Q)");
                    self.exit_signal.send(std::process::ExitCode::SUCCESS);
                }
                Key::Enter => self.reset_view(),
                Key::Escape if self.background_shot.is_some() => self.cancel_background_shot(" (Esc)"),
                Key::Escape if self.measure.active => self.measure.points.clear(),
                Key::Escape => self.set_selected(u32::MAX),
                Key::M => {
                    self.measure.active = !self.measure.active;
                    let state = if self.measure.active { "on" } else { "off" };
                    log::info!("measure mode {state}");
                }
                Key::H | Key::I | Key::U => {
                    let edit = self.scene.as_ref().and_then(|scene| match k {
                        Key::H => self.hide_selection_edit(scene),
                        Key::I => self.isolate_edit(scene),
                        _ => super::tree::show_all(scene),
                    });
                    if let Some(e) = edit {
                        self.edit(Action::Apply(e));
                    }
                }
                Key::Z if mods.command && mods.shift => self.edit(Action::Redo),
                Key::Z if mods.command => self.edit(Action::Undo),
                Key::Y if mods.command => self.edit(Action::Redo),
                Key::O if mods.command => self.open_file_dialog(),
                Key::Delete => self.delete_selection(),
                Key::ArrowLeft
                | Key::ArrowRight
                | Key::ArrowUp
                | Key::ArrowDown
                | Key::PageUp
                | Key::PageDown
                    if !self.selection.instances.is_empty() =>
                {
                    let step = self.move_step() * if mods.shift { 10.0 } else { 1.0 };
                    let c = self.nav.cam;
                    let dir = match k {
                        Key::ArrowLeft => -nav::right(&c),
                        Key::ArrowRight => nav::right(&c),
                        Key::ArrowUp => nav::cam_up(&c),
                        Key::ArrowDown => -nav::cam_up(&c),
                        Key::PageUp => nav::forward(&c),
                        _ => -nav::forward(&c),
                    };
                    self.move_selected(dominant_axis(dir) * step);
                }
                _ => {}
            }
        }
        if !down.is_empty() && self.scene.is_some() {
            self.motion.drag(true, true);
            let speed = self.move_step() * 25.0 * if mods.shift { 4.0 } else { 1.0 } * dt;
            let mut local = Vec3::ZERO;
            for k in down {
                match k {
                    Key::W => local.z += 1.0,
                    Key::S => local.z -= 1.0,
                    Key::A => local.x -= 1.0,
                    Key::D => local.x += 1.0,
                    Key::Q => local.y -= 1.0,
                    _ => local.y += 1.0,
                }
            }
            self.nav.cam = nav::fly_move(&self.nav.cam, local * speed);
            self.nav.pivot = nav::target(&self.nav.cam);
        }
    }
}

/// The signed world axis closest to `v`.
fn dominant_axis(v: Vec3) -> Vec3 {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        Vec3::X * v.x.signum()
    } else if a.y >= a.z {
        Vec3::Y * v.y.signum()
    } else {
        Vec3::Z * v.z.signum()
    }
}

fn fmt_count(n: u64) -> String {
    let s = n.to_string();
    let head = s.len() % 3;
    let mut parts: Vec<&str> = Vec::new();
    if head > 0 {
        parts.push(&s[..head]);
    }
    parts.extend(
        s.as_bytes()[head..]
            .chunks(3)
            .map(|c| std::str::from_utf8(c).unwrap_or("")),
    );
    parts.join(",")
}

/// How many times `key` went down this frame, repeats left out: a key held (or pressed as the window gains the
/// focus, when X delivers it twice, the second as a repeat) acts once. egui's `num_presses` counts repeats, and
/// a Tab tapped while the window took the focus toggled the panel twice.
fn key_taps(events: &[egui::Event], key: Key) -> usize {
    events
        .iter()
        .filter(|e| matches!(e, egui::Event::Key { key: k, pressed: true, repeat: false, .. } if *k == key))
        .count()
}

/// The pointer's motion that a drag of the view answers this frame, in points. egui's `drag_delta` is the
/// pointer's whole motion since the previous frame, so on the frame a drag starts it also holds the motion before
/// the press (a hover and a press that a busy frame delivers together): the view would jump by a motion made with
/// no button down. A drag moves the view by the motion since its press, and from then on by each frame's.
fn view_drag_delta(ctx: &egui::Context, resp: &egui::Response) -> egui::Vec2 {
    if !resp.dragged() {
        return egui::Vec2::ZERO;
    }
    if resp.drag_started() {
        return ctx
            .input(|i| Some(i.pointer.latest_pos()? - i.pointer.press_origin()?))
            .unwrap_or_default();
    }
    resp.drag_delta()
}

#[cfg(test)]
mod tests {
    /// A Tab tapped as the window gains the focus comes as a press and a repeat: one tap. Two taps are two.
    #[test]
    fn a_key_repeat_is_not_a_tap() {
        use egui::{Event, Key};
        let key = |key, pressed, repeat| Event::Key {
            key,
            physical_key: Some(key),
            pressed,
            repeat,
            modifiers: Default::default(),
        };
        let focus = [
            Event::WindowFocused(true),
            key(Key::Tab, true, false),
            key(Key::Tab, true, true),
            key(Key::Tab, false, false),
            key(Key::F12, true, false),
        ];
        assert_eq!(super::key_taps(&focus, Key::Tab), 1);
        assert_eq!(super::key_taps(&focus, Key::F12), 1);
        let twice = [
            key(Key::Tab, true, false),
            key(Key::Tab, false, false),
            key(Key::Tab, true, false),
        ];
        assert_eq!(super::key_taps(&twice, Key::Tab), 2);
    }

    /// One frame of a bare egui context with a drag-sensing area over the whole screen, fed `events`: the drag
    /// delta the view answers.
    fn drag_frame(ctx: &egui::Context, events: Vec<egui::Event>) -> egui::Vec2 {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(400.0, 300.0),
            )),
            events,
            ..Default::default()
        };
        let mut delta = egui::Vec2::ZERO;
        let _ = ctx.run(input, |ctx| {
            egui::CentralPanel::default().show(ctx, |ui| {
                let rect = ui.max_rect();
                let resp = ui.allocate_rect(rect, egui::Sense::click_and_drag());
                delta = super::view_drag_delta(ctx, &resp);
            });
        });
        delta
    }

    /// A hover and a press that arrive in one frame do not move the view by the hover's motion (egui's own
    /// `drag_delta` gives the hover's 40 points there); the motion after the press does, from the press on,
    /// including the part of it that came in the press's frame.
    #[test]
    fn a_drag_moves_the_view_by_the_motion_after_its_press() {
        use egui::{Event, PointerButton, Pos2};
        let press = |p: Pos2, pressed| Event::PointerButton {
            pos: p,
            button: PointerButton::Primary,
            pressed,
            modifiers: Default::default(),
        };
        let ctx = egui::Context::default();
        let (a, b) = (Pos2::new(100.0, 100.0), Pos2::new(140.0, 100.0));
        assert_eq!(drag_frame(&ctx, vec![Event::PointerMoved(a)]), egui::Vec2::ZERO);
        let d = drag_frame(&ctx, vec![Event::PointerMoved(b), press(b, true)]);
        assert_eq!(d, egui::Vec2::ZERO, "the hover's motion moved the view");
        let d = drag_frame(&ctx, vec![Event::PointerMoved(Pos2::new(150.0, 104.0))]);
        assert_eq!(d, egui::vec2(10.0, 4.0));
        // A press and motion after it in one frame: the motion since the press.
        let _ = drag_frame(&ctx, vec![press(Pos2::new(150.0, 104.0), false)]);
        let c = Pos2::new(200.0, 200.0);
        let d = drag_frame(
            &ctx,
            vec![
                Event::PointerMoved(c),
                press(c, true),
                Event::PointerMoved(Pos2::new(207.0, 195.0)),
            ],
        );
        assert_eq!(d, egui::vec2(7.0, -5.0));
    }

    #[test]
    fn counts_and_axes() {
        assert_eq!(super::fmt_count(0), "0");
        assert_eq!(super::fmt_count(1234567), "1,234,567");
        assert_eq!(super::fmt_count(123456), "123,456");
        assert_eq!(
            super::dominant_axis(glam::Vec3::new(0.2, -0.9, 0.1)),
            -glam::Vec3::Y
        );
    }
}
