//! `hrtao view`: the interactive viewer. A winit window (`app`: the event loop and egui-winit) with an egui
//! panel; each frame records the 3D view into the swapchain image and egui on top (`ui_layer`,
//! egui-ash-renderer).
//!
//! - `nav`: CAD camera maths (pure, unit tested).
//! - `edits`: scene edits with undo/redo (F increments, TLAS rebuild).
//! - `prefs`: persisted settings and camera bookmarks.
//! - `present`: swapchain, the scaled blit of the renderer's output, readback of the presented image.
//! - `frame_loop`: the per-frame GPU loop (acquire, plan, record, submit, present, complete the frames in
//!   flight, measure); it returns events the viewer applies as it applies commands.
//! - `script`: scripted runs (`--frames`, `--orbit`, `--set-at-frame`, …), turned into commands.
//! - `shot`: custom-size screenshots rendered in the background, tile by tile, while the window keeps drawing;
//!   `shots`: the screenshots in flight and where they go.
//! - `ui`: the panel, navigation and picking input, toasts.
//!
//! `Viewer` is implemented here only (`impl Viewer`): the other modules take what they read as arguments and
//! return commands or events (tests/structure.rs guards this and the number of its fields).
mod app;
mod command;
pub mod edits;
mod files;
mod frame_loop;
mod frames;
mod input;
pub mod latency;
pub(crate) mod load_options;
mod loader;
pub mod measure;
pub mod nav;
pub(crate) mod pacer;
pub mod prefs;
pub mod present;
mod properties;
mod recent;
mod reload;
mod script;
mod sections;
mod selection;
mod settings_panel;
pub mod shot;
mod shots;
pub mod stats;
mod storeys;
pub mod tree;
mod tree_panel;
mod ui;
mod ui_colors;
mod ui_layer;
mod ui_probe;
mod up_axis;
mod view_cube;
mod walk;
mod watch;

use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use glam::Vec3;
use hrtao_core::camera::UpAxis;
use hrtao_core::{Camera, Gpu, SceneGpu};
use hrtao_scene::{NodeTree, Scene};

use crate::cli::ViewArgs;
use crate::setup;
use command::{Command, PickFor};
use edits::EditStack;
use frame_loop::{Event, FrameLoop, UiFrame};
use nav::Nav;
use prefs::Prefs;
use present::Presenter;
use script::Script;

/// The window's application id, the name of the desktop entry (`hrtao.desktop`).
pub const APP_ID: &str = "hrtao";

/// The render scale's range (`--render-scale`, the preferences, the panel).
pub const RENDER_SCALE: std::ops::RangeInclusive<f32> = 0.05..=2.0;

/// `scale` within [`RENDER_SCALE`].
fn clamp_render_scale(scale: f32) -> f32 {
    scale.clamp(*RENDER_SCALE.start(), *RENDER_SCALE.end())
}

/// The key and mouse bindings (the panel's Help table; `hrtao --help` prints them too).
pub use ui::BINDINGS;

/// The bundled scene's path, normalised for display.
pub(crate) fn default_spec() -> String {
    let p = crate::common::default_scene_path();
    std::fs::canonicalize(&p).unwrap_or(p).display().to_string()
}

/// `hrtao view`: the window until the viewer or the user ends it (`app::run`).
pub fn run(args: &ViewArgs) -> Result<()> {
    app::run(args)
}

/// What the frame loop reads of the viewer (a macro: it borrows the fields it names, not the whole viewer).
macro_rules! frame_view {
    ($v:expr) => {
        frame_loop::FrameView {
            scene: $v.scene.as_ref().zip($v.scene_gpu.as_ref()),
            cam: $v.nav.cam,
            prefs: &$v.prefs,
            render_scale: $v.render_scale,
            scripted: $v.script.running(),
        }
    };
}

/// What the walk reads of the viewer (None without a scene).
macro_rules! walk_view {
    ($v:expr) => {
        $v.scene.as_ref().map(|scene| walk::WalkView {
            scene,
            spec: &$v.scene_spec,
            nav: &$v.nav,
            settings: &$v.prefs.walk,
        })
    };
}

pub(crate) struct Viewer {
    gpu: Arc<Gpu>,
    egui_ctx: egui::Context,
    exit: app::Exit,
    // Scene and rendering.
    scene: Option<Scene>,
    scene_spec: String,
    scene_gpu: Option<SceneGpu>,
    /// The per-frame GPU loop: swapchain, renderer, pacer, frames in flight, screenshots, statistics.
    frame_loop: FrameLoop,
    nav: Nav,
    home: Camera,
    default_radius: f32,
    /// What is highlighted; its primary instance is what move and delete act on.
    selection: tree::Selection,
    /// The panels and tools, each with its own state; they send commands (`apply`).
    panels: ui::Panels,
    edits: EditStack,
    loader: loader::Loader,
    /// The view a running reload keeps, and the watch on the open file (`reload.rs`, `watch.rs`).
    reload: reload::Reload,
    /// What the command line asked of the first scene (crate::setup), then of the scenes opened after it.
    startup: setup::SetupInputs,
    /// The user's render scale: the internal resolution of a still image, and the cap while moving.
    render_scale: f32,
    // Persistence.
    prefs: Prefs,
    prefs_file: prefs::PrefsFile,
    // Messages.
    toasts: Vec<ui::Toast>,
    script: Script,
}

impl Viewer {
    fn new(
        gpu: Arc<Gpu>,
        presenter: Presenter,
        args: &ViewArgs,
        links: app::Links,
        egui_ctx: egui::Context,
        // The preferences file, what it holds and what went wrong reading it (opened with the device: app.rs).
        (prefs_file, mut prefs, prefs_msg): (prefs::PrefsFile, prefs::Prefs, Option<String>),
    ) -> Viewer {
        let app::Links { hooks, exit } = links;
        setup::view_prefs(args, &mut prefs);
        // The user's render scale caps the internal resolution; a still image is rendered at it.
        let render_scale = clamp_render_scale(args.render_scale.or(prefs.max_render_scale).unwrap_or(1.0));
        egui_ctx.set_theme(if prefs.dark_theme {
            egui::Theme::Dark
        } else {
            egui::Theme::Light
        });
        let spec = args.file.clone().unwrap_or_else(default_spec);
        let frame_loop = FrameLoop::new(&gpu, &egui_ctx, presenter, args, &prefs, render_scale);
        let mut v = Viewer {
            gpu,
            egui_ctx,
            exit,
            scene: None,
            scene_spec: String::new(),
            scene_gpu: None,
            frame_loop,
            nav: Nav {
                cam: Camera::default(),
                pivot: Vec3::ZERO,
                world_up: UpAxis::Y,
            },
            home: Camera::default(),
            default_radius: 1.0,
            selection: tree::Selection::default(),
            panels: ui::Panels::new(&spec, !args.no_panel),
            edits: EditStack::default(),
            loader: loader::Loader::default(),
            reload: reload::Reload::default(),
            startup: setup::SetupInputs::from_view(args),
            render_scale,
            prefs,
            prefs_file,
            toasts: Vec::new(),
            script: Script::new(args, hooks),
        };
        if let Some(m) = prefs_msg {
            v.toast(m, true);
        }
        if let Some(p) = &args.walk_path {
            match walk::path::WalkPathFile::read(p) {
                Ok(f) => v.panels.walk.script = Some(f),
                Err(e) => v.fatal(format!("{e:#}")),
            }
        }
        v.start_loading(spec);
        v
    }

    fn toast(&mut self, text: impl Into<String>, error: bool) {
        let text = text.into();
        if error {
            log::warn!("{text}");
        } else {
            log::info!("{text}");
        }
        self.toasts.push(ui::Toast {
            text,
            error,
            until: Instant::now() + Duration::from_secs(if error { 8 } else { 4 }),
        });
    }

    /// An unrecoverable error: remembered for the exit status, shown, and in scripted mode the app exits.
    fn fatal(&mut self, msg: String) {
        log::error!("{msg}");
        self.exit.error(&msg);
        self.toast(msg, true);
        if self.script.exit {
            self.exit.signal.send(ExitCode::FAILURE);
        }
    }

    /// Starts loading `spec` on a background thread (the window keeps running; the old scene stays).
    /// A load still running is cancelled.
    fn start_loading(&mut self, spec: String) {
        self.loader.start(spec, load_options::load_options(&self.prefs));
    }

    /// Polls the loader; installs a loaded scene (GPU build, camera, radius).
    fn poll_loading(&mut self) {
        if !self.frame_loop.laid_out {
            // The first UI pass has not laid out the 3D view yet (its aspect frames the camera).
            return;
        }
        let Some(loaded) = self.loader.poll() else {
            return;
        };
        let spec = loaded.spec;
        let keep = self.reload.take(&spec);
        match loaded.result.and_then(|scene| {
            self.install_scene(scene, &spec)
                .map_err(|e| format!("cannot open `{spec}`: {e:#}"))
        }) {
            Ok(()) => {
                // A file joins the recent list (saved now) and is watched for changes.
                if reload::remember_opened(&spec, &mut self.prefs.recent) {
                    self.maybe_save_prefs(true);
                }
                self.reload.watch(&spec, &self.egui_ctx);
                match keep {
                    Some(k) => self.reloaded(k),
                    None => self.toast(
                        format!("opened {spec} in {:.1} s", loaded.took.as_secs_f64()),
                        false,
                    ),
                }
            }
            Err(e) => {
                self.loader.error = Some(e.clone());
                if keep.is_some() {
                    self.toast(format!("reload failed, the previous model stays: {e}"), true);
                } else if self.scene.is_none() && self.script.exit {
                    // The exit status's line names the file and the reason (the OS's, for a missing file).
                    self.fatal(e);
                } else {
                    self.toast(e, true);
                }
            }
        }
    }

    fn install_scene(&mut self, scene: Scene, spec: &str) -> Result<()> {
        // The rules `render` and `bench` follow too (crate::setup); the up axis the user chose for this file.
        let remembered = up_axis::remembered(&self.prefs.up_axes, spec);
        let p = setup::prepare(&self.startup.for_next_scene(spec, remembered), &scene)?;
        // What the loader assumed (an IFC file with no length unit): a warning, never silent.
        for w in &scene.warnings {
            self.toast(w.clone(), true);
        }
        // The old scene's frames in flight complete before the renderer renders the new one's probes.
        self.complete(Some(0))?;
        self.gpu.wait_idle();
        let section_state = sections::SectionState::for_scene(scene.bounds(), &p.sections);
        self.cancel_background_shot(": another scene was opened");
        let scene_gpu = setup::build_scene_gpu(&self.gpu, &scene, &section_state.sections())?;
        self.default_radius = p.default_radius;
        log::info!("up axis {}", p.up);
        // The sky light's zenith is the scene's up axis.
        self.prefs.settings.light.sky_up = p.up;
        let [_, _, w, h] = self.frame_loop.view_rect;
        let cam = p.view_camera((w > 1).then(|| w.max(1) as f32 / h.max(1) as f32));
        self.nav = Nav {
            cam,
            pivot: nav::target(&cam),
            world_up: p.up,
        };
        self.home = cam;
        self.selection = tree::Selection::default();
        self.panels.scene_opened(spec, section_state, p.unit(&scene));
        self.edits.clear();
        let settings = self.prefs.settings.clone().with_radius(p.radius);
        let (scene_pair, prefs) = ((&scene, &scene_gpu), &self.prefs);
        self.frame_loop
            .scene_installed(scene_pair, cam, &settings, p.primary, self.render_scale, prefs)?;
        self.prefs.settings.map.ao_radius = p.radius;
        self.scene_gpu = Some(scene_gpu);
        self.scene = Some(scene);
        self.scene_spec = spec.to_string();
        let name = Path::new(spec).file_name().map(|f| f.to_string_lossy());
        let title = format!("hrtao — {}", name.unwrap_or(spec.into()));
        self.egui_ctx
            .send_viewport_cmd(egui::ViewportCommand::Title(title));
        Ok(())
    }

    /// Reloads the open file in the background, keeping the view (nothing when no file is open or a load runs).
    fn reload(&mut self) {
        let Some(scene) = self.scene.as_ref().filter(|_| !self.loader.is_loading()) else {
            return;
        };
        let view = (self.nav, self.home);
        match reload::Keep::of(
            &self.scene_spec,
            scene,
            view,
            &self.panels.sections,
            &self.selection,
        ) {
            Ok(keep) => {
                self.reload.start(keep);
                self.start_loading(self.scene_spec.clone());
            }
            Err(e) => self.toast(e, true),
        }
    }

    /// After a reload installed the new scene: the old camera, sections and selection, and the toast.
    fn reloaded(&mut self, keep: reload::Keep) {
        let Some(scene) = &self.scene else {
            return;
        };
        let r = keep.restore(scene);
        (self.nav, self.home) = (r.nav, r.home);
        let planes = r.sections.sections();
        self.panels.sections = r.sections;
        self.apply_sections(planes);
        self.panels.tree.reveal(r.selection.node);
        self.apply_selection(r.selection);
        self.toast(r.message, false);
    }

    /// The window's monitor refreshes at `refresh_mhz` millihertz (None: unknown): a GPU's frame-time target.
    pub(crate) fn display_refresh(&mut self, refresh_mhz: Option<u32>) {
        self.frame_loop.pacer.display_refresh(refresh_mhz);
    }

    /// Selects what `choose` makes of the scene's tree and the selection, and reveals its node in the tree.
    fn reveal_selection(&mut self, choose: impl FnOnce(&NodeTree, &tree::Selection) -> tree::Selection) {
        let Some(scene) = &self.scene else {
            return;
        };
        let selection = choose(&scene.tree, &self.selection);
        self.panels.tree.reveal(selection.node);
        self.apply_selection(selection);
    }

    /// Makes `selection` current and updates the highlight: the instance table's flags, written by the next
    /// frame's commands (no TLAS build, no wait for the device, the still image keeps refining).
    fn apply_selection(&mut self, selection: tree::Selection) {
        self.selection = selection;
        if let Some(sg) = &mut self.scene_gpu {
            sg.set_highlight(self.selection.instances.as_slice());
        }
    }

    /// Applies an edit / undo / redo through the edit stack (F increments, TLAS rebuilt).
    fn edit(&mut self, action: edits::Action) {
        let (Some(scene), Some(sg)) = (&mut self.scene, &mut self.scene_gpu) else {
            return;
        };
        self.gpu.wait_idle();
        match edits::run_logged(&mut self.edits, scene, sg, &self.selection, action) {
            Ok(again) => self.apply_all(again.map(Command::Select)),
            Err(e) => self.toast(e, true),
        }
    }

    /// Walk mode on (standing below the camera's eye, or at `at`) or off (`walk.rs`).
    fn set_walking(&mut self, on: bool, at: Option<Vec3>) {
        let commands = match walk_view!(self) {
            Some(v) => self.panels.walk.set(on, at, &v),
            None => return,
        };
        self.apply_all(commands);
    }

    /// The UI pass of a frame (egui's input stamped): the loader and the scripted run move on, the panels draw
    /// and send commands, the viewer applies them in order, the walk takes its step.
    fn ui_pass(&mut self, ui: &mut egui::Ui) {
        let f = &mut self.frame_loop;
        f.latency.ui_pass(latency::egui_has_input(ui.ctx()));
        f.clock.ui_started = Instant::now();
        self.poll_loading();
        // A settled change of the open file reloads it (with auto-reload on, once no load runs).
        if self.prefs.auto_reload && !self.loader.is_loading() && self.reload.changed() {
            self.reload();
        }
        let shows_image = !self.loader.is_loading() && self.frame_loop.last_report.is_some();
        let orbit = self.script.orbit(&self.nav, self.scene.is_some() && shows_image);
        self.apply_all(orbit);
        if self.script.timed_out() {
            self.fatal("scripted run timed out (--timeout)".into());
        }
        let f = &self.frame_loop;
        let state = command::ViewState {
            device: &self.gpu.info,
            validation_messages: self.gpu.validation_messages(),
            scene: self.scene.as_ref(),
            spec: &self.scene_spec,
            section_sides: self.scene_gpu.as_ref().map(|sg| sg.section_sides),
            selection: &self.selection,
            nav: &self.nav,
            walking: self.panels.walk.walking(),
            in_plan: self.panels.storeys.in_plan(),
            home: self.home,
            prefs: &self.prefs,
            default_radius: self.default_radius,
            render_scale: self.render_scale,
            can_scale: f.can_scale(),
            view_rect: f.view_rect,
            report: f.last_report.as_ref(),
            internal: f.renderer.as_ref().map_or((0, 0), |r| r.size()),
            frame_ms: f.pacer.averages(),
            rays_per_frame: f.pacer.rays_per_frame(),
            target_ms: f
                .pacer
                .target_ms(frame_loop::pacing(&self.prefs, self.render_scale)),
            loading: self.loader.view(),
            load_error: self.loader.error.as_deref(),
            undo: self.edits.undo_label(),
            redo: self.edits.redo_label(),
            shot: f.shots.progress(),
        };
        let commands = self.panels.ui(ui, &state);
        ui::draw_toasts(ui.ctx(), &mut self.toasts);
        self.apply_all(commands);
        let ready = self.frame_loop.last_report.is_some() && !self.loader.is_loading();
        let commands = match walk_view!(self) {
            Some(v) => self.panels.walk.tick(&v, ready),
            None => Vec::new(),
        };
        self.apply_all(commands);
        self.frame_loop.clock.ui_done = Instant::now();
    }

    fn apply_all(&mut self, commands: impl IntoIterator<Item = Command>) {
        for c in commands {
            self.apply(c);
        }
    }

    /// Carries out a command of a panel, the view's input, a shortcut or a scripted run.
    fn apply(&mut self, command: Command) {
        match command {
            Command::Open(spec) => self.start_loading(spec),
            Command::Reload => self.reload(),
            Command::OpenDialog => {
                if let Some(c) = self.panels.files.open_dialog(&self.scene_spec, &self.egui_ctx) {
                    self.apply(c);
                }
            }
            Command::CancelLoading => {
                if let Some(spec) = self.loader.cancel() {
                    let text = format!("cancelled opening {spec}; the current scene stays");
                    self.toast(text, false);
                }
            }
            Command::Select(selection) => self.apply_selection(selection),
            Command::SelectInstance(i) => self.reveal_selection(|tree, _| tree::Selection::picked(tree, i)),
            Command::Pick { at, purpose } => self.pick(at, purpose),
            Command::Edit(action) => self.edit(action),
            Command::DeleteSelection => {
                // One edit (one undo step) for the whole selection, which is cleared.
                if let Some(e) = edits::Edit::delete_all(&self.selection.instances) {
                    self.apply_selection(tree::Selection::default());
                    self.edit(edits::Action::Apply(e));
                }
            }
            Command::Settings(s) => match s.validate() {
                Ok(()) => self.prefs.settings = *s,
                Err(e) => self.toast(format!("settings: {e}"), true),
            },
            Command::SetJson { json, what } => match self.prefs.settings.with_overrides(&json) {
                Ok(s) => self.apply(Command::Settings(Box::new(s))),
                Err(e) => self.fatal(format!("{what}: {e}")),
            },
            Command::Prefs(p) => {
                // The AO settings change through Command::Settings only (validated).
                let settings = std::mem::take(&mut self.prefs.settings);
                self.prefs = *p;
                self.prefs.settings = settings;
            }
            Command::RenderScale(scale) => self.render_scale = clamp_render_scale(scale),
            Command::UpAxis(up) => {
                let Some(scene) = &self.scene else { return };
                let view = (&mut self.nav, &mut self.home);
                if up_axis::choose(up, scene, &self.scene_spec, view, &mut self.prefs) {
                    self.maybe_save_prefs(true);
                }
            }
            Command::Walk(on) => self.set_walking(on, None),
            Command::Plan(storey) => {
                let sg = self.scene_gpu.as_ref();
                let sections = sg.map(|sg| sg.sections().clone()).unwrap_or_default();
                let commands = match &self.scene {
                    Some(scene) => self.panels.storeys.plan(storey, scene, &self.nav, sections),
                    None => Vec::new(),
                };
                self.apply_all(commands);
            }
            Command::ClearCache => {
                if let Some(Err(e)) = self.frame_loop.renderer.as_mut().map(|r| r.clear_cache()) {
                    self.toast(format!("{e}"), true);
                }
            }
            Command::Camera { cam, pivot } => {
                self.nav.cam = cam;
                self.nav.pivot = pivot;
            }
            Command::Drag { dragging, moved } => self.frame_loop.pacer.drag(dragging, moved),
            Command::Sections(sections) => self.apply_sections(sections),
            Command::Screenshot => self.request_screenshot(),
            Command::CancelScreenshot(why) => self.cancel_background_shot(why),
            Command::BackgroundShot { size, path } => self.start_background_shot(size, path),
            Command::CaptureWindow(path) => self.frame_loop.capture_ui = Some(path),
            Command::FinishScript { after_shot } => self.finish_script(after_shot),
            Command::Fullscreen(on) => {
                log::info!("full screen {}", if on { "on" } else { "off" });
                self.egui_ctx
                    .send_viewport_cmd(egui::ViewportCommand::Fullscreen(on));
            }
            Command::WindowSize(w, h) => {
                let ppp = self.egui_ctx.pixels_per_point();
                let size = egui::vec2(w as f32 / ppp, h as f32 / ppp);
                self.egui_ctx
                    .send_viewport_cmd(egui::ViewportCommand::InnerSize(size));
            }
            Command::Quit => {
                log::info!("quit (Ctrl+Q)");
                self.exit.signal.send(ExitCode::SUCCESS);
            }
            Command::ViewRect(rect) => self.frame_loop.set_view_rect(rect),
            Command::Toast { text, error } => self.toast(text, error),
        }
    }

    /// Carries out what a frame reported.
    fn happened(&mut self, event: Event) {
        match event {
            Event::Toast { text, error } => self.toast(text, error),
            Event::Fatal(msg) => self.fatal(msg),
            Event::ShotFailed(msg) => self.shot_failed(msg),
            Event::Rendered => {
                let v = script::ScriptView {
                    converged: self.frame_loop.converged_full(self.render_scale),
                    loading: self.loader.is_loading(),
                    walking: self.panels.walk.script_running(),
                };
                let commands = self.script.step(&v);
                self.apply_all(commands);
            }
            Event::Exit(code) => self.exit.signal.send(code),
        }
    }

    /// A click or double-click in the view at `at` (fractions of the view): picks the surface under it from the
    /// last frame's G-buffer and selects, toggles, sets the pivot or measures.
    fn pick(&mut self, at: [f32; 2], purpose: PickFor) {
        let (hit, floor_hit) = match self.frame_loop.pick(at) {
            Some(Ok(px)) => (
                px.map(|px| (Vec3::from_slice(&px.position[..3]), px.instance)),
                // The surface faces up: a floor to stand on.
                px.is_some_and(|px| Vec3::from(px.normal).dot(self.nav.world_up.vector()) > walk::FLOOR_COS),
            ),
            Some(Err(e)) => return self.toast(format!("pick failed: {e}"), true),
            None => (None, false),
        };
        let walk_here = |v: &Viewer| walk_view!(v).is_some_and(|w| v.panels.walk.here(&w));
        match (purpose, hit) {
            (PickFor::Select, _) => {
                let sel = hit.map_or(u32::MAX, |h| h.1);
                if sel != self.selection.primary() {
                    self.apply(Command::SelectInstance(sel));
                }
            }
            (PickFor::Toggle, _) => {
                let i = hit.map_or(u32::MAX, |h| h.1);
                self.reveal_selection(|tree, s| s.toggled_logged(tree, i));
            }
            (PickFor::Pivot, Some((pos, _))) if floor_hit && walk_here(self) => {
                self.set_walking(true, Some(pos));
            }
            (PickFor::Pivot, Some((pos, _))) => {
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
            (PickFor::Measure, Some((pos, _))) => {
                if let Some(scene) = &self.scene {
                    self.panels.measure.pick(scene, pos.to_array());
                }
            }
            _ => {}
        }
    }

    /// Sends section planes to the scene (TLAS rebuild; F of the frame moves on).
    fn apply_sections(&mut self, sections: hrtao_core::Sections) {
        let (Some(sg), Some(scene)) = (&mut self.scene_gpu, &self.scene) else {
            return;
        };
        if *sg.sections() == sections {
            return;
        }
        self.gpu.wait_idle();
        match sg.set_sections(scene, &sections, self.selection.instances.as_slice()) {
            Ok(()) => log::info!(
                "section planes: {:?}; instances untouched, crossed, cut away: {:?}",
                sections
                    .planes
                    .iter()
                    .map(|p| (p.normal, p.offset))
                    .collect::<Vec<_>>(),
                sg.section_sides
            ),
            Err(e) => self.toast(format!("section planes: {e}"), true),
        }
    }

    /// F12/the button: a custom size renders in the background; the window's size right away.
    fn request_screenshot(&mut self) {
        let model = self.scene.as_ref().map_or("hrtao", |s| s.name.as_str());
        let path = shots::path(self.prefs.screenshot_folder.clone(), model);
        if self.prefs.screenshot_custom {
            let size = (self.prefs.screenshot_width, self.prefs.screenshot_height);
            self.start_background_shot(size, path);
            return;
        }
        self.frame_loop.shots.pending = Some(shots::ShotRequest {
            size: None,
            frames: self.prefs.screenshot_frames.min(4),
            path,
        });
    }

    /// Starts a background screenshot of the current view at `size` (one at a time).
    fn start_background_shot(&mut self, size: (u32, u32), path: std::path::PathBuf) {
        match self.frame_loop.start_shot(size, path, &frame_view!(self)) {
            Ok(msg) => self.toast(msg, false),
            Err(e) => self.shot_failed(e),
        }
    }

    /// Cancel button (or a new scene): the background screenshot is dropped.
    fn cancel_background_shot(&mut self, why: &str) {
        if self.frame_loop.shots.cancel() {
            // Its last frame was waited for with the viewer's frame: nothing of it is in flight.
            self.toast(format!("screenshot cancelled{why}"), false);
        }
    }

    /// A failed screenshot: a toast (fatal in a scripted run with a background screenshot); the viewer keeps
    /// running.
    fn shot_failed(&mut self, msg: String) {
        if self.script.shot_is_fatal() {
            self.fatal(msg);
        } else {
            self.toast(msg, true);
        }
    }

    /// A frame after its UI pass (an error is fatal: shown, and the exit status of scripted runs).
    fn paint(&mut self, size: winit::dpi::PhysicalSize<u32>, mut ui: UiFrame) {
        // egui's texture changes apply whether or not this frame presents: later frames' shapes use them. The
        // textures it changes or frees may be in use by frames in flight: those complete first.
        if !(ui.textures.set.is_empty() && ui.textures.free.is_empty()) {
            if let Err(e) = self.complete(Some(0)) {
                self.fatal(format!("{e:#}"));
            }
        }
        let presenter = &mut self.frame_loop.presenter;
        let pool = presenter.pool;
        if let Err(e) = presenter
            .ui
            .prepare(pool, &mut ui.textures, &mut ui.primitives)
            .and_then(|()| self.draw(size, &ui))
        {
            self.fatal(format!("{e:#}"));
        }
        // The frame that drew with them has completed (or none was submitted).
        self.frame_loop.presenter.ui.frame_done();
    }

    /// The per-frame work (`frame_loop`): the frames finished meanwhile, a screenshot asked for, the frame's
    /// plan, recording and presentation, then the repaint it asks for.
    fn draw(&mut self, size: winit::dpi::PhysicalSize<u32>, ui: &UiFrame) -> Result<()> {
        let Some(start) = self.frame_loop.begin(size) else {
            return Ok(());
        };
        if let Some(e) = self.frame_loop.poll_saving() {
            self.happened(e);
        }
        // The frames the device finished meanwhile: their reports before this frame's plan. All frames in flight
        // before a screenshot is taken or a frame whose results are read from buffers the next one overwrites.
        self.complete(None)?;
        if self.frame_loop.exclusive() {
            self.complete(Some(0))?;
        }
        if let Some(req) = self.frame_loop.shots.pending.take() {
            match self.frame_loop.take_screenshot(req, &frame_view!(self)) {
                Ok(p) => self.toast(format!("screenshot saved: {}", p.display()), false),
                Err(e) => self.toast(format!("screenshot failed: {e:#}"), true),
            }
        }
        let view = frame_view!(self);
        let Some(keep) = self
            .frame_loop
            .record(size, start, ui, &view, &mut self.panels.walk)?
        else {
            return Ok(());
        };
        self.complete(Some(keep))?;
        self.maybe_save_prefs(false);
        // Another frame while something is still changing (a scripted run, the walk, a screenshot or a capture
        // waits for frames too); otherwise the event loop waits for events.
        let busy = self.script.running() || self.panels.walk.wants_frames();
        let (viewing, loading) = (self.scene.is_some(), self.loader.is_loading());
        if let Some(e) = self.frame_loop.repaint(busy, viewing, loading, self.render_scale) {
            self.happened(e);
        }
        Ok(())
    }

    /// Completes frames in flight, oldest first: until `keep` are left (waiting for each), or with None those
    /// the device has finished. What each frame reports is carried out before the next completes.
    fn complete(&mut self, keep: Option<usize>) -> Result<()> {
        loop {
            let view = frame_view!(self);
            let walk = &mut self.panels.walk;
            let Some((events, result)) = self.frame_loop.complete_next(keep, &view, walk) else {
                return Ok(());
            };
            self.apply_events(events);
            result?;
        }
    }

    fn apply_events(&mut self, events: Vec<Event>) {
        for e in events {
            self.happened(e);
        }
    }

    /// The scripted run's frames are done: the frames in flight complete, the screenshot, the statistics, the
    /// exit (after a background screenshot: once it is written).
    fn finish_script(&mut self, after_shot: bool) {
        if after_shot && self.frame_loop.shots.in_background() {
            return;
        }
        self.script.done = true;
        // The frames recorded after this one complete first: the screenshot renders with the view's renderer,
        // and the statistics end with them.
        if let Err(e) = self.complete(Some(0)) {
            self.fatal(format!("{e:#}"));
        }
        if let Some(req) = self.script.screenshot() {
            match self.frame_loop.take_screenshot(req, &frame_view!(self)) {
                Ok(p) => log::info!("screenshot saved: {}", p.display()),
                Err(e) => self.fatal(format!("screenshot failed: {e:#}")),
            }
        }
        self.frame_loop.log_script_end(self.script.rendered);
        self.write_stats();
        if self.script.exit {
            let bad = self.gpu.validation_messages() > 0 || self.exit.failed();
            self.exit
                .signal
                .send(if bad { ExitCode::FAILURE } else { ExitCode::SUCCESS });
        }
    }

    /// Writes `--stats` (once; an error is fatal in scripted mode).
    fn write_stats(&mut self) {
        let target = self
            .frame_loop
            .pacer
            .target_ms(frame_loop::pacing(&self.prefs, self.render_scale));
        if let Some(Err(e)) = self.frame_loop.write_stats(&self.scene_spec, target) {
            self.fatal(e);
        }
    }

    fn maybe_save_prefs(&mut self, force: bool) {
        self.prefs.max_render_scale = Some(self.render_scale);
        if let Err(e) = self.prefs_file.maybe_save(&self.prefs, force) {
            self.toast(e, true);
        }
    }

    /// The event loop is exiting: save, release every Vulkan object while the window still exists.
    fn shutdown(&mut self) {
        if !self.frame_loop.shut_down() {
            return;
        }
        self.maybe_save_prefs(true);
        if let Err(e) = self.complete(Some(0)) {
            log::warn!("the last frames: {e:#}");
        }
        self.frame_loop.frames.clear();
        self.write_stats();
        self.gpu.wait_idle();
        self.frame_loop.release();
        self.scene_gpu = None;
        self.frame_loop.presenter.destroy();
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.shutdown();
    }
}
