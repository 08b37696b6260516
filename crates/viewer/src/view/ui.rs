//! The viewer's panels as one `Panels` value: the side panel (scene, load options, AO settings, statistics,
//! section planes, model tree, selection, properties, measure, camera, screenshot, bindings), the 3D view's area
//! and overlays (the view cube), and the toasts. Each panel owns its state and returns commands (view/command.rs).
use std::time::Instant;

use egui::Key;
use hrtao_core::Mode;

use super::command::{Command, ViewState};
use super::edits::{Action, Edit};
use super::files::FilesPanel;
use super::input::{self, CameraButton, Tools};
use super::load_options::LoadOptionsPanel;
use super::measure::{Measure, Unit};
use super::nav::{self, StdView};
use super::prefs::Bookmark;
use super::properties::PropertiesPanel;
use super::sections::SectionState;
use super::settings_panel::SettingsPanel;
use super::tree_panel::TreeView;
use super::ui_probe;
use super::view_cube::ViewCube;

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
        "G (Esc leaves)",
        "walk mode: W A S D walk at eye height (Shift runs), left drag looks",
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
    (
        "Click on the view cube (top right of the view)",
        "a face: that standard view; a corner: the isometric view from that corner",
    ),
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
    (
        "F5 / Ctrl+R",
        "reload the open file, keeping the camera, section planes and selection (also automatic when the file \
         changes on disk: the Scene section's Auto-reload)",
    ),
    ("F11", "full screen on / off"),
    ("Ctrl+Q", "quit"),
];

/// A message shown over the view's bottom left corner until `until`.
pub(crate) struct Toast {
    pub text: String,
    pub error: bool,
    pub until: Instant,
}

/// The viewer's panels and tools, each owning its state; `ui` draws them all and returns what they ask for.
pub struct Panels {
    pub files: FilesPanel,
    pub load_options: LoadOptionsPanel,
    pub settings: SettingsPanel,
    pub sections: SectionState,
    pub tree: TreeView,
    pub properties: PropertiesPanel,
    pub measure: Measure,
    pub camera: CameraPanel,
    pub screenshot: ScreenshotPanel,
    pub view_cube: ViewCube,
    /// Walk mode (`walk.rs`).
    pub walk: super::walk::Walk,
    /// The storeys and their plan views (`storeys.rs`).
    pub storeys: super::storeys::Storeys,
    /// The side panel is shown (Tab).
    pub show: bool,
    fullscreen: bool,
}

impl Panels {
    pub fn new(spec: &str, show: bool) -> Panels {
        Panels {
            files: FilesPanel::new(spec),
            load_options: LoadOptionsPanel,
            settings: SettingsPanel,
            sections: SectionState::default(),
            tree: TreeView::default(),
            properties: PropertiesPanel::default(),
            measure: Measure::for_spec(spec),
            camera: CameraPanel::default(),
            screenshot: ScreenshotPanel,
            view_cube: ViewCube,
            walk: Default::default(),
            storeys: Default::default(),
            show,
            fullscreen: false,
        }
    }

    /// A scene was opened: the panels that describe it start over.
    pub fn scene_opened(&mut self, spec: &str, sections: SectionState, unit: Option<Unit>) {
        self.files.opened(spec);
        self.sections = sections;
        self.tree = TreeView::default();
        self.properties = PropertiesPanel { unit };
        self.measure = Measure::for_spec(spec);
        // Another scene: not walking (a scripted walk still to start stays), no plan to leave.
        self.walk.leave();
        self.storeys.scene_opened();
        if let Some(u) = unit {
            self.measure.file_unit = u;
            self.measure.show_unit = u;
        }
    }

    /// The whole UI of a frame: global keys, the side panel, the 3D view's input and overlays, the keyboard.
    pub fn ui(&mut self, root: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let ctx = &root.ctx().clone();
        let mut out = self.global_keys(ctx);
        // Dropped files open like the Open button.
        let dropped: Vec<_> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        out.extend(FilesPanel::dropped(&dropped));
        out.extend(self.files.poll_dialog(state.loading.is_some()));
        if self.show {
            egui::Panel::right("panel")
                .resizable(true)
                .default_size(480.0)
                .show(root, |ui| {
                    // Text wraps at the panel's edge, in rows and grids too: what a frame reports (statistics,
                    // names) never widens the panel, so the 3D view keeps the size the user gave it.
                    ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Wrap);
                    egui::ScrollArea::vertical().show(ui, |ui| out.extend(self.panel(ui, state)));
                });
        }
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(root, |ui| out.extend(self.view(ctx, ui, state)));
        let mut tools = Tools {
            measure: &mut self.measure,
            sections: &mut self.sections,
            fullscreen: &mut self.fullscreen,
            walk: &mut self.walk.input,
        };
        out.extend(input::keyboard(ctx, state, &mut tools));
        out.extend(self.shot_overlay(ctx, state));
        out
    }

    /// Keys that act whatever has the keyboard focus, read before any widget runs: Tab toggles the panel and
    /// F12 takes a screenshot. egui moves the focus between widgets on Tab (and arrow keys); that focus made
    /// every later shortcut wait for a click elsewhere, so focus gained by keyboard navigation is dropped.
    fn global_keys(&mut self, ctx: &egui::Context) -> Vec<Command> {
        let (tabs, shots) = ctx.input(|i| (key_taps(&i.events, Key::Tab), key_taps(&i.events, Key::F12)));
        let mut out = Vec::new();
        if tabs % 2 == 1 {
            self.show = !self.show;
        }
        if tabs > 0 {
            // Tab is ours: nothing keeps the focus egui gives a widget for it.
            ctx.memory_mut(|m| m.stop_text_input());
        }
        if shots > 0 {
            out.push(Command::Screenshot);
        }
        out
    }

    /// The 3D view: its rectangle, mouse input, the measure overlay and the loading overlay.
    fn view(&mut self, ctx: &egui::Context, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let rect = ui.max_rect();
        let ppp = ctx.pixels_per_point();
        let mut out = vec![Command::ViewRect([
            (rect.min.x * ppp).round() as i32,
            (rect.min.y * ppp).round() as i32,
            (rect.width() * ppp).round().max(1.0) as i32,
            (rect.height() * ppp).round().max(1.0) as i32,
        ])];
        let resp = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        let mut tools = Tools {
            measure: &mut self.measure,
            sections: &mut self.sections,
            fullscreen: &mut self.fullscreen,
            walk: &mut self.walk.input,
        };
        out.extend(input::view_input(ctx, &resp, rect, state, &mut tools));
        self.measure.overlay(ui.painter(), rect, &state.view_cam());
        out.extend(self.view_cube.ui(ui, state));
        if let Some(l) = &state.loading {
            let text = format!("Loading {} … {} ({:.0} s)", l.spec, l.progress, l.seconds);
            let area = egui::Rect::from_center_size(rect.center(), egui::vec2(400.0, 80.0));
            let cancel = ui
                .scope_builder(egui::UiBuilder::new().max_rect(area), |ui| {
                    ui.vertical_centered(|ui| {
                        ui.label(egui::RichText::new(text).heading());
                        ui.button("Cancel").clicked()
                    })
                    .inner
                })
                .inner;
            if cancel {
                out.push(Command::CancelLoading);
            }
        }
        out
    }

    fn panel(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let mut out = Vec::new();
        let device = state.device;
        ui.heading("hrtao");
        ui.label(format!("Device: {} ({})", device.name, device.kind))
            .on_hover_text(format!("driver {}", device.driver));
        if device.is_software {
            ui.colored_label(
                egui::Color32::from_rgb(230, 160, 40),
                "software device: render scale starts low",
            );
        }
        out.extend(ray_backend_row(ui, state));
        egui::CollapsingHeader::new("Scene")
            .default_open(true)
            .show(ui, |ui| {
                out.extend(self.files.ui(ui, state));
                if let Some(scene) = state.scene {
                    ui.label(format!("{}  ({})", scene.name, state.spec));
                    self.measure.dimensions_row(ui, scene);
                    out.extend(super::up_axis::row(ui, state));
                    out.extend(super::storeys::panel(ui, state, state.in_plan));
                }
            });
        egui::CollapsingHeader::new("Walk")
            .default_open(false)
            .show(ui, |ui| out.extend(super::walk::panel(ui, state, state.walking)));
        let load_options = egui::CollapsingHeader::new("Load options")
            .default_open(false)
            .show(ui, |ui| out.extend(self.load_options.ui(ui, state)));
        ui_probe::note(
            "Load options",
            load_options.header_response.rect,
            ui.ctx().pixels_per_point(),
        );
        egui::CollapsingHeader::new("Ambient occlusion")
            .default_open(true)
            .show(ui, |ui| out.extend(self.settings.ui(ui, state)));
        egui::CollapsingHeader::new("Statistics")
            .default_open(true)
            .show(ui, |ui| stats_section(ui, state));
        // Opened once when a scene comes with planes (--section).
        let open = std::mem::take(&mut self.sections.reveal).then_some(true);
        egui::CollapsingHeader::new("Section planes")
            .default_open(false)
            .open(open)
            .show(ui, |ui| out.extend(self.sections.ui(ui, state)));
        egui::CollapsingHeader::new("Model tree")
            .default_open(true)
            .show(ui, |ui| {
                out.extend(self.tree.ui(ui, state.scene, state.selection))
            });
        egui::CollapsingHeader::new("Selection")
            .default_open(true)
            .show(ui, |ui| out.extend(selection_section(ui, state)));
        egui::CollapsingHeader::new("Properties")
            .default_open(true)
            .show(ui, |ui| out.extend(self.properties.ui(ui, state)));
        egui::CollapsingHeader::new("Measure")
            .default_open(true)
            .show(ui, |ui| self.measure.ui(ui));
        egui::CollapsingHeader::new("Camera")
            .default_open(false)
            .show(ui, |ui| out.extend(self.camera.ui(ui, state)));
        egui::CollapsingHeader::new("Screenshot")
            .default_open(false)
            .show(ui, |ui| out.extend(self.screenshot.ui(ui, state)));
        egui::CollapsingHeader::new("Keys and mouse")
            .default_open(false)
            .show(ui, |ui| {
                kv_grid("bindings").show(ui, |ui| {
                    for (k, v) in BINDINGS {
                        kv_row(ui, k, *v);
                    }
                });
            });
        out
    }

    /// A background screenshot's progress and Cancel over the 3D view while the panel is hidden.
    fn shot_overlay(&mut self, ctx: &egui::Context, state: &ViewState) -> Option<Command> {
        let (fraction, status, cancellable) = state.shot.clone().filter(|_| !self.show)?;
        let mut cancel = false;
        egui::Area::new(egui::Id::new("screenshot progress"))
            .anchor(egui::Align2::RIGHT_TOP, [-10.0, 10.0])
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    ui.add(egui::ProgressBar::new(fraction).desired_width(260.0).text(status));
                    cancel = cancellable && ui.button("Cancel screenshot").clicked();
                });
            });
        cancel.then_some(Command::CancelScreenshot(""))
    }
}

/// Draws the toasts that have not expired, and asks for a repaint when the first one expires.
/// How rays are traced now, and the saved choice (automatic, ray queries, ray-tracing pipelines), which the
/// device is opened with at the next start (app.rs; `--ray-backend` overrides it).
fn ray_backend_row(ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
    use hrtao_core::RayBackend;
    let name = |b: Option<RayBackend>| match b {
        None => "automatic",
        Some(RayBackend::Query) => "ray queries",
        Some(RayBackend::Pipeline) => "ray-tracing pipelines",
    };
    let mut out = Vec::new();
    let saved = state.prefs.ray_backend;
    let active = state.device.ray_backend;
    ui.horizontal(|ui| {
        ui.label(format!("Rays: {}", name(Some(active))));
        let mut choice = saved;
        egui::ComboBox::from_id_salt("ray backend")
            .selected_text(name(choice))
            .show_ui(ui, |ui| {
                for b in [None, Some(RayBackend::Query), Some(RayBackend::Pipeline)] {
                    ui.selectable_value(&mut choice, b, name(b));
                }
            })
            .response
            .on_hover_text(
                "How rays are traced: ray queries in compute shaders, or ray-tracing pipelines (the same \
                 image). Automatic: ray queries where the device has them. Applies at the next start.",
            );
        if choice != saved {
            let mut prefs = state.prefs.clone();
            prefs.ray_backend = choice;
            out.push(Command::Prefs(Box::new(prefs)));
        }
    });
    if saved.is_some_and(|b| b != active) {
        ui.small("the saved choice applies at the next start");
    }
    out
}

pub(crate) fn draw_toasts(ctx: &egui::Context, toasts: &mut Vec<Toast>) {
    let now = Instant::now();
    toasts.retain(|t| t.until > now);
    let Some(first_expiry) = toasts.iter().map(|t| t.until).min() else {
        return;
    };
    // Repaint when the first toast expires (the loop rests otherwise).
    ctx.request_repaint_after(first_expiry - now);
    egui::Area::new(egui::Id::new("toasts"))
        .anchor(egui::Align2::LEFT_BOTTOM, [10.0, -10.0])
        .interactable(false)
        .show(ctx, |ui| {
            if let Some(last) = toasts.last() {
                ui_probe::note_text("toast", &last.text);
            }
            for t in toasts.iter() {
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

/// A grid of named values in the panel: names on one line, values wrapped at the panel's edge (the last column
/// takes the rest of the width), so a long value never widens the panel nor squeezes the names.
pub(crate) fn kv_grid(id: &str) -> egui::Grid {
    egui::Grid::new(id).num_columns(2).striped(true)
}

/// One row of a `kv_grid`.
pub(crate) fn kv_row(ui: &mut egui::Ui, key: &str, value: impl Into<egui::WidgetText>) {
    ui.add(egui::Label::new(key).extend());
    ui.label(value);
    ui.end_row();
}

fn stats_section(ui: &mut egui::Ui, state: &ViewState) {
    let Some(rep) = state.report else {
        ui.label("no frame yet");
        return;
    };
    let (iw, ih) = state.internal;
    let settings = &state.prefs.settings;
    kv_grid("stats").show(ui, |ui| {
        let mut row = |k: &str, v: String| kv_row(ui, k, v);
        let (frame_ms, interval_ms) = state.frame_ms;
        row(
            "frame",
            format!(
                "{frame_ms:.1} ms render, {interval_ms:.1} ms interval ({:.1} fps)",
                1000.0 / interval_ms.max(1e-3)
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
                100.0 * iw as f32 / state.view_rect[2].max(1) as f32
            ),
        );
        row(
            "image",
            if super::pacer::image_converged(rep) {
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
        if settings.display.mode.uses_hash() {
            row(
                "hash cells",
                format!(
                    "{} / {} ({:.1}% load)",
                    rep.occupied_cells,
                    settings.map.hash_capacity,
                    rep.load_factor * 100.0
                ),
            );
            row("failed inserts", rep.failed_inserts.to_string());
            row("longest probe", rep.longest_probe.to_string());
        } else if settings.display.mode == Mode::Rtao {
            row("accumulated", format!("{} frames", rep.accumulated_frames));
        }
        if let Some(scene) = state.scene {
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
        row("validation", format!("{} messages", state.validation_messages));
    });
}

fn selection_section(ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
    let mut out = Vec::new();
    ui.horizontal(|ui| {
        if ui
            .add_enabled(state.undo.is_some(), egui::Button::new("Undo"))
            .on_hover_text(state.undo.clone().unwrap_or_default())
            .clicked()
        {
            out.push(Command::Edit(Action::Undo));
        }
        if ui
            .add_enabled(state.redo.is_some(), egui::Button::new("Redo"))
            .on_hover_text(state.redo.clone().unwrap_or_default())
            .clicked()
        {
            out.push(Command::Edit(Action::Redo));
        }
    });
    let sel = state.selection.primary();
    let Some(inst) = state.scene.and_then(|s| s.instances.get(sel as usize)) else {
        match super::tree::selection_summary(ui, state) {
            Some(c) => out.extend(c),
            None => {
                ui.label("click an instance (or a model tree node) to select it");
            }
        }
        return out;
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
        out.push(Command::Edit(Action::Apply(Edit::Visibility {
            instance: sel,
            visible,
        })));
    }
    let pos = inst.transform.w_axis.truncate();
    let mut p = pos;
    let step = state.move_step();
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
        out.extend(input::move_selection(state, p - pos));
    }
    ui.horizontal(|ui| {
        if ui.button("Delete").clicked() {
            out.push(Command::DeleteSelection);
        }
        if ui.button("Deselect").clicked() {
            out.push(Command::SelectInstance(u32::MAX));
        }
    });
    out
}

/// The "Camera" section: standard views, projection, lens, bookmarks, the camera as JSON.
#[derive(Default)]
pub struct CameraPanel {
    bookmark_name: String,
}

impl CameraPanel {
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let mut out = Vec::new();
        ui.horizontal(|ui| {
            for (label, button) in [
                ("Fit (F)", CameraButton::Fit),
                ("Front", CameraButton::View(StdView::Front)),
                ("Right", CameraButton::View(StdView::Right)),
                ("Top", CameraButton::View(StdView::Top)),
                ("Iso", CameraButton::View(StdView::Iso)),
                ("Reset", CameraButton::Reset),
            ] {
                if ui.button(label).clicked() {
                    out.extend(input::camera_button(state, button));
                }
            }
        });
        let nav = state.nav;
        let mut cam = nav.cam;
        ui.horizontal(|ui| {
            let mut ortho = cam.is_orthographic();
            if ui
                .checkbox(&mut ortho, "Orthographic (5)")
                .on_hover_text("parallel projection; front/right/top views switch to it")
                .changed()
            {
                cam = input::toggled_projection(nav);
            }
        });
        if nav.cam.is_orthographic() {
            let h = nav.cam.ortho_height;
            ui.add(
                egui::DragValue::new(&mut cam.ortho_height)
                    .speed(h * 0.01)
                    .range(h * 1e-3..=h * 1e3)
                    .prefix("view height "),
            );
        } else {
            ui.add(egui::Slider::new(&mut cam.fov_y_deg, 5.0..=120.0).text("field of view"));
        }
        if cam != nav.cam {
            out.push(Command::Camera {
                cam,
                pivot: nav.pivot,
            });
        }
        let mut prefs = state.prefs.clone();
        ui.horizontal(|ui| {
            ui.add(
                egui::TextEdit::singleline(&mut self.bookmark_name)
                    .hint_text("bookmark name")
                    .desired_width(160.0),
            );
            if ui.button("Save view").clicked() {
                let name = if self.bookmark_name.trim().is_empty() {
                    format!("view {}", prefs.bookmarks.len() + 1)
                } else {
                    self.bookmark_name.trim().to_string()
                };
                prefs.bookmarks.push(Bookmark {
                    name,
                    scene: state.spec.to_string(),
                    camera: nav.cam,
                });
                self.bookmark_name.clear();
            }
        });
        let mut remove = None;
        for (i, b) in prefs.bookmarks.iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.button(&b.name).on_hover_text(&b.scene).clicked() {
                    out.push(Command::Camera {
                        cam: b.camera,
                        pivot: nav::target(&b.camera),
                    });
                }
                if ui.small_button("✖").on_hover_text("remove").clicked() {
                    remove = Some(i);
                }
            });
        }
        if let Some(i) = remove {
            prefs.bookmarks.remove(i);
        }
        if prefs != *state.prefs {
            out.push(Command::Prefs(Box::new(prefs)));
        }
        if ui.button("Copy camera JSON").clicked() {
            let cam = state.view_cam();
            let text = serde_json::to_string_pretty(&cam).unwrap_or_default();
            ui.ctx().copy_text(text);
        }
        out
    }
}

/// The "Screenshot" section: folder, size, frames, and the button (F12).
pub struct ScreenshotPanel;

impl ScreenshotPanel {
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let mut out = Vec::new();
        let mut prefs = state.prefs.clone();
        ui.horizontal(|ui| {
            ui.label("folder");
            let mut dir = prefs
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
                prefs.screenshot_folder =
                    Some(dir.trim().into()).filter(|d: &std::path::PathBuf| !d.as_os_str().is_empty());
            }
        });
        ui.checkbox(&mut prefs.screenshot_custom, "custom resolution")
            .on_hover_text(
                "Rendered in the background at this size, tile by tile, each tile until its still image has \
             converged (anti-aliased), while the view keeps drawing; else the 3D view's window resolution",
            );
        ui.add_enabled_ui(prefs.screenshot_custom, |ui| {
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(&mut prefs.screenshot_width).range(16..=16384));
                ui.label("×");
                ui.add(egui::DragValue::new(&mut prefs.screenshot_height).range(16..=16384));
            });
        });
        ui.add_enabled_ui(!prefs.screenshot_custom, |ui| {
            ui.add(egui::Slider::new(&mut prefs.screenshot_frames, 1..=4).text("frames"))
                .on_hover_text(
                    "Frames rendered for a window-resolution screenshot (the cache is already warm); a custom \
                     size renders until converged.",
                );
        });
        if prefs != *state.prefs {
            out.push(Command::Prefs(Box::new(prefs)));
        }
        if let Some((fraction, status, cancellable)) = state.shot.clone() {
            ui.add(egui::ProgressBar::new(fraction).text(status));
            if cancellable && ui.button("Cancel screenshot").clicked() {
                out.push(Command::CancelScreenshot(""));
            }
        } else if ui.button("Take screenshot (F12)").clicked() {
            out.push(Command::Screenshot);
        }
        out
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

#[cfg(test)]
mod tests {
    /// In a narrow panel that wraps text (as the side panel does), a named-value grid keeps its names on one
    /// line and wraps a long value at the panel's edge, over the frames after the first (egui measures the
    /// columns in the first).
    #[test]
    fn a_value_grid_keeps_names_whole_and_wraps_values_at_the_edge() {
        let ctx = egui::Context::default();
        let value = "141.4 ms render, 193.8 ms interval (5.2 fps) and more words to wrap past the edge";
        let mut texts = Vec::new();
        for _ in 0..3 {
            let input = egui::RawInput {
                screen_rect: Some(egui::Rect::from_min_size(
                    egui::Pos2::ZERO,
                    egui::vec2(300.0, 400.0),
                )),
                ..Default::default()
            };
            let out = ctx.run_ui(input, |root| {
                egui::CentralPanel::default().show(root, |ui| {
                    ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Wrap);
                    super::kv_grid("test").show(ui, |ui| {
                        super::kv_row(ui, "resolution", value);
                        super::kv_row(ui, "GPU passes", "3 ms");
                    });
                });
            });
            texts = out
                .shapes
                .iter()
                .filter_map(|c| match &c.shape {
                    egui::Shape::Text(t) => Some((
                        t.galley.text().to_owned(),
                        t.galley.rows.len(),
                        t.visual_bounding_rect(),
                    )),
                    _ => None,
                })
                .collect::<Vec<_>>();
            out.drop_without_applying_deltas();
        }
        let find = |k: &str| {
            texts
                .iter()
                .find(|(t, _, _)| t == k)
                .unwrap_or_else(|| panic!("{k}: {texts:?}"))
        };
        assert_eq!(find("resolution").1, 1);
        assert_eq!(find("GPU passes").1, 1);
        let (_, rows, rect) = find(value);
        assert!(
            *rows >= 2 && rect.right() <= 300.0,
            "{rows} rows, right edge {}",
            rect.right()
        );
        // The value column starts right after the names, not after a squeezed first column.
        assert!(rect.left() < 120.0, "{rect:?}");
    }

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

    #[test]
    fn counts() {
        assert_eq!(super::fmt_count(0), "0");
        assert_eq!(super::fmt_count(1234567), "1,234,567");
        assert_eq!(super::fmt_count(123456), "123,456");
    }
}
