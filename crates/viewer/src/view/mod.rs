//! `hrtao view`: the interactive viewer. A winit window (`app`: the event loop and egui-winit) with an egui
//! panel; each frame records the 3D view into the swapchain image and egui on top (`ui_layer`,
//! egui-ash-renderer).
//!
//! - `nav`: CAD camera maths (pure, unit tested).
//! - `edits`: scene edits with undo/redo (F increments, TLAS rebuild).
//! - `prefs`: persisted settings and camera bookmarks.
//! - `present`: swapchain, the scaled blit of the renderer's output, readback of the presented image.
//! - `shot`: custom-size screenshots rendered in the background, tile by tile, while the window keeps drawing.
//! - `ui`: the panel, navigation and picking input, toasts.
mod app;
mod command;
pub mod edits;
mod files;
mod frames;
mod input;
pub mod latency;
mod load_options;
mod loader;
pub mod measure;
pub mod nav;
mod pacer;
pub mod prefs;
pub mod present;
mod properties;
mod recent;
mod reload;
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

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use hrtao_core::buffer::Buffer;
use hrtao_core::camera::UpAxis;
use hrtao_core::{Camera, FrameDesc, FrameReport, Gpu, Output, Renderer, SceneGpu};
use hrtao_scene::Scene;

use crate::cli::ViewArgs;
use crate::setup;
use command::{Command, PickFor};
use edits::EditStack;
use nav::Nav;
use prefs::Prefs;
use present::Presenter;

/// Seconds a scripted run may take: --timeout, or 600 plus 600 per million pixels of a background screenshot.
fn scripted_timeout(args: &ViewArgs) -> u64 {
    let shot_pixels = args.screenshot_size.map_or(0, |(w, h)| w as u64 * h as u64);
    args.timeout
        .unwrap_or(600 + 600 * shot_pixels.div_ceil(1_000_000))
}

/// The window's application id, the name of the desktop entry (`hrtao.desktop`).
pub const APP_ID: &str = "hrtao";

/// The key and mouse bindings (the panel's Help table; `hrtao --help` prints them too).
pub use ui::BINDINGS;

/// The bundled scene's path, normalised for display.
pub(crate) fn default_spec() -> String {
    let p = crate::common::default_scene_path();
    std::fs::canonicalize(&p).unwrap_or(p).display().to_string()
}

/// What the process reports when the window closes.
#[derive(Default)]
struct Outcome {
    error: Option<String>,
    gpu: Option<Arc<Gpu>>,
}

pub fn run(args: &ViewArgs) -> Result<()> {
    let resize = match crate::cli::frame_pairs("--resize-at-frame", &args.resize_at_frame)?.as_slice() {
        [] => None,
        [(k, wh)] => Some((
            *k,
            crate::cli::parse_size(wh).map_err(|e| anyhow!("--resize-at-frame: {e}"))?,
        )),
        _ => bail!("--resize-at-frame is given once"),
    };
    let set_at_frame = crate::cli::set_at_frame(&args.set_at_frame)?;
    if args.sections.section.len() > hrtao_core::gpu::MAX_SECTIONS as usize {
        bail!(
            "at most {} section planes are supported",
            hrtao_core::gpu::MAX_SECTIONS
        );
    }
    if let Some(s) = args.render_scale {
        if !(0.05..=2.0).contains(&s) {
            bail!("--render-scale must be within 0.05..=2");
        }
    }
    let unset = |v: &str| std::env::var_os(v).is_none_or(|x| x.is_empty());
    if unset("DISPLAY") && unset("WAYLAND_DISPLAY") {
        bail!(
            "no display: set DISPLAY (e.g. run under `xvfb-run -a`) or use `hrtao render` for headless use"
        );
    }
    let outcome = Arc::new(Mutex::new(Outcome::default()));
    let hooks = ScriptHooks { resize, set_at_frame };
    let code = app::run(args, hooks, outcome.clone());
    let mut out = outcome.lock().unwrap_or_else(|p| p.into_inner());
    // The last Arc<Gpu> goes here, after the window and the viewer released everything they held.
    let gpu = out.gpu.take();
    let validation = gpu.as_ref().map(|g| g.validation_messages()).unwrap_or(0);
    drop(gpu);
    if let Some(e) = out.error.take() {
        bail!("{e}");
    }
    if validation > 0 {
        bail!("the validation layer reported {validation} messages");
    }
    if code? != ExitCode::SUCCESS {
        bail!("the viewer exited with an error");
    }
    Ok(())
}

/// The scripted run's hooks, parsed from the arguments before the window opens.
#[derive(Clone)]
struct ScriptHooks {
    /// --resize-at-frame K WxH.
    resize: Option<(u32, (u32, u32))>,
    /// --set-at-frame K JSON (repeatable).
    set_at_frame: Vec<(u32, String)>,
}

/// What egui's UI pass produced for the frame: its triangles, their scale, and the textures it changed.
pub(crate) struct UiFrame {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub pixels_per_point: f32,
    pub textures: egui::TexturesDelta,
}

/// Scripted-mode state.
struct Script {
    frames: Option<u32>,
    /// --orbit N: frames still to orbit, and whether the run waits for convergence after them.
    orbit_left: u32,
    wait_converged: bool,
    stats: Option<stats::StatsLog>,
    screenshot: Option<PathBuf>,
    screenshot_ui: Option<PathBuf>,
    screenshot_frames: u32,
    /// --screenshot-size: --screenshot is rendered in the background at this size (started once).
    screenshot_size: Option<(u32, u32)>,
    shot_started: bool,
    resize: Option<(u32, (u32, u32))>,
    open: Option<(u32, String)>,
    /// --set-at-frame: settings (JSON) applied after K rendered frames, as the panel applies them.
    set_at_frame: Vec<(u32, String)>,
    exit: bool,
    deadline: Option<Instant>,
    rendered: u32,
    done: bool,
    ui_capture_pending: bool,
    /// The --screenshot-ui capture was asked for (once).
    ui_captured: bool,
}

/// The renderer's output to present: its buffer, width and height.
type ViewOutput = (vk::Buffer, u32, u32);

/// The presented image copied for `--screenshot-ui`, read after the frame.
struct UiCapture {
    path: PathBuf,
    buf: Buffer,
    size: (u32, u32),
    bgra: bool,
}

pub(crate) struct Viewer {
    gpu: Arc<Gpu>,
    presenter: Presenter,
    egui_ctx: egui::Context,
    exit_signal: app::ExitSignal,
    outcome: Arc<Mutex<Outcome>>,
    // Scene and rendering.
    scene: Option<Scene>,
    scene_spec: String,
    scene_gpu: Option<SceneGpu>,
    renderer: Option<Renderer>,
    /// Frame pacing: what each frame renders (size, ray budget, slices) or holds, and when the loop wakes.
    pacer: pacer::Pacer,
    nav: Nav,
    home: Camera,
    default_radius: f32,
    /// What is highlighted; its primary instance is what move and delete act on.
    selection: tree::Selection,
    /// The panels and tools, each with its own state; they send commands (`apply`).
    panels: ui::Panels,
    edits: EditStack,
    loader: loader::Loader,
    /// The view a running reload keeps (`reload.rs`), and the watch on the open file (`watch.rs`).
    reloading: Option<reload::Keep>,
    watch: Option<watch::FileWatch>,
    /// What the command line asked of the first scene (crate::setup), then of the scenes opened after it.
    startup: crate::setup::SetupInputs,
    // View.
    /// The user's render scale: the internal resolution of a still image, and the cap while moving.
    render_scale: f32,
    view_rect: [i32; 4],
    laid_out: bool,
    last_report: Option<FrameReport>,
    /// The stamps of the view's frames (statistics, and the pacer's clock).
    clock: stats::FrameClock,
    // Persistence.
    prefs: Prefs,
    prefs_file: prefs::PrefsFile,
    // Messages.
    toasts: Vec<ui::Toast>,
    /// Screenshots asked for, rendering in the background or being written.
    shots: shots::Shots,
    script: Script,
    /// Presentation and input stamps, `--ao-out`, `--exit-after`.
    latency: latency::Latency,
    /// Frames submitted and not completed.
    frames: frames::Frames,
    shut_down: bool,
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
        let app::Links {
            hooks,
            exit: exit_signal,
            outcome,
        } = links;
        if let Some(m) = args.mode {
            prefs.settings.display.mode = m;
        }
        if let Some(r) = args.rays_per_frame {
            prefs.rays_per_frame = r.clamp(pacer::MIN_RAYS_PER_FRAME, pacer::MAX_RAYS_PER_FRAME);
            prefs.auto_budget = false;
        }
        if args.no_auto_budget {
            prefs.auto_budget = false;
        }
        // The command line's tessellation and smoothing flags become the panel's load options.
        if let Some(t) = hrtao_scene::command_line_cad_tessellation() {
            prefs.cad_load = load_options::CadLoadOptions::from_tessellation(t);
        }
        if let Some(c) = hrtao_scene::normals::command_line_crease_deg() {
            prefs.mesh_load = load_options::MeshLoadOptions::from_crease(c);
        }
        // The user's render scale caps the internal resolution; a still image is rendered at it.
        let render_scale = args
            .render_scale
            .or(prefs.max_render_scale)
            .unwrap_or(1.0)
            .clamp(0.05, 2.0);
        // The device's class and display (`display_refresh`: the window's monitor): the frame-time target,
        // the first budget, the moving frames' filter and scale (0.35 on a software device, full on a GPU).
        let device = pacer::DeviceModel::new(gpu.info.is_software, None);
        let moving_scale = device.first_moving_scale();
        egui_ctx.set_theme(if prefs.dark_theme {
            egui::Theme::Dark
        } else {
            egui::Theme::Light
        });
        let spec = args.file.clone().unwrap_or_else(default_spec);
        let frames_in_flight = prefs::frames_in_flight(
            std::env::var("HRTAO_FRAMES_IN_FLIGHT").ok().as_deref(),
            prefs.frames_in_flight,
            gpu.info.is_software,
        );
        log::info!("{frames_in_flight} frame(s) in flight");
        let mut v = Viewer {
            gpu,
            presenter,
            egui_ctx,
            exit_signal,
            outcome,
            scene: None,
            scene_spec: String::new(),
            scene_gpu: None,
            renderer: None,
            pacer: pacer::Pacer::new(
                prefs.rays_per_frame,
                moving_scale.min(render_scale),
                device,
                std::time::Duration::ZERO,
            ),
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
            reloading: None,
            watch: None,
            startup: crate::setup::SetupInputs::from_view(args),
            render_scale,
            view_rect: [0, 0, 1, 1],
            laid_out: false,
            last_report: None,
            clock: stats::FrameClock::new(),
            prefs,
            prefs_file,
            toasts: Vec::new(),
            shots: shots::Shots::default(),
            script: Script {
                frames: args
                    .frames
                    .or(args.orbit.map(|_| 0))
                    .or(args.walk_path.as_ref().map(|_| 0)),
                orbit_left: args.orbit.unwrap_or(0),
                wait_converged: args.orbit.is_some(),
                stats: args.stats.clone().map(stats::StatsLog::new),
                screenshot: args.screenshot.clone(),
                screenshot_ui: args.screenshot_ui.clone(),
                screenshot_frames: args.screenshot_frames,
                screenshot_size: args.screenshot_size,
                shot_started: false,
                resize: hooks.resize,
                set_at_frame: hooks.set_at_frame,
                open: match args.open_at_frame.as_slice() {
                    [k, file] => k.parse::<u32>().ok().map(|k| (k, file.clone())),
                    _ => None,
                },
                exit: args.exit,
                deadline: Some(scripted_timeout(args))
                    .filter(|&t| (args.exit || args.exit_after.is_some()) && t > 0)
                    .map(|t| Instant::now() + Duration::from_secs(t)),
                rendered: 0,
                done: false,
                ui_capture_pending: false,
                ui_captured: false,
            },
            latency: latency::Latency::new(args.ao_out.clone(), args.exit_after),
            frames: frames::Frames::new(frames_in_flight),
            shut_down: false,
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
        let mut o = self.outcome.lock().unwrap_or_else(|p| p.into_inner());
        if o.error.is_none() {
            o.error = Some(msg.clone());
        }
        drop(o);
        self.toast(msg, true);
        if self.script.exit {
            self.exit_signal.send(ExitCode::FAILURE);
        }
    }

    /// Starts loading `spec` on a background thread (the window keeps running; the old scene stays).
    /// A load still running is cancelled.
    fn start_loading(&mut self, spec: String) {
        self.loader.start(spec, load_options::load_options(&self.prefs));
    }

    /// Cancel button: stops the running load; the current scene stays.
    fn cancel_loading(&mut self) {
        if let Some(spec) = self.loader.cancel() {
            self.toast(
                format!("cancelled opening {spec}; the current scene stays"),
                false,
            );
        }
    }

    /// Polls the loader; installs a loaded scene (GPU build, camera, radius).
    fn poll_loading(&mut self) {
        if !self.laid_out {
            // The first UI pass has not laid out the 3D view yet (its aspect frames the camera).
            return;
        }
        let Some(loaded) = self.loader.poll() else {
            return;
        };
        let spec = loaded.spec;
        let keep = self.take_reload(&spec);
        match loaded.result.and_then(|scene| {
            self.install_scene(scene, &spec)
                .map_err(|e| format!("cannot open `{spec}`: {e:#}"))
        }) {
            Ok(()) => {
                self.opened_file(&spec);
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
                    self.reload_failed(&e);
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
        // The command line's camera, radius and sections are the first scene's; its up axis and primary
        // visibility hold for every scene (crate::setup: the rules `render` and `bench` follow too).
        let later = setup::SetupInputs {
            up: self.startup.up,
            primary: self.startup.primary,
            ..Default::default()
        };
        let mut inputs = setup::SetupInputs {
            spec: Some(spec.to_string()),
            ..std::mem::replace(&mut self.startup, later)
        };
        // The up axis the user chose for this file in the panel, unless `--up` says otherwise.
        inputs.up = inputs.up.or(up_axis::remembered(&self.prefs.up_axes, spec));
        let p = setup::prepare(&inputs, &scene)?;
        // What the loader assumed (an IFC file with no length unit): a warning, never silent.
        for w in &scene.warnings {
            self.toast(w.clone(), true);
        }
        // The old scene's frames in flight complete before the renderer renders the new one's probes.
        self.complete_frames(0)?;
        self.gpu.wait_idle();
        let section_state = sections::SectionState::for_scene(scene.bounds(), &p.sections);
        self.cancel_background_shot(": another scene was opened");
        let scene_gpu = setup::build_scene_gpu(&self.gpu, &scene, &section_state.sections())?;
        self.default_radius = p.default_radius;
        let radius = p.radius;
        let world_up = p.up;
        log::info!("up axis {world_up}");
        // The sky light's zenith is the scene's up axis.
        self.prefs.settings.light.sky_up = world_up;
        // Orient the camera with a true up vector (nav keeps it orthogonal).
        let mut cam = nav::orbit(&p.camera, nav::target(&p.camera), world_up.vector(), 0.0, 0.0);
        // A camera file framed for a wider image: back off so the 3D view shows the same horizontal extent.
        let file_aspect = cam.width as f32 / cam.height.max(1) as f32;
        let view_aspect = self.view_rect[2].max(1) as f32 / self.view_rect[3].max(1) as f32;
        if p.camera_file.is_some() && self.view_rect[2] > 1 && view_aspect < file_aspect {
            let widen = file_aspect / view_aspect;
            if cam.is_orthographic() {
                cam.ortho_height *= widen;
            } else {
                let t = nav::target(&cam);
                cam.eye = (t + (nav::eye(&cam) - t) * widen).to_array();
            }
        }
        self.nav = Nav {
            cam,
            pivot: nav::target(&cam),
            world_up,
        };
        self.home = cam;
        self.selection = tree::Selection::default();
        // STEP and IGES declare their length unit; the bundled gearbox is a CAD export in millimetres (its glTF
        // says metres).
        let unit = if p.bundled {
            Some(measure::Unit::Mm)
        } else {
            scene.unit_m.and_then(measure::Unit::from_metres)
        };
        self.panels.scene_opened(spec, section_state, unit);
        self.edits.clear();
        if self.renderer.is_none() {
            self.renderer = Some(Renderer::new(&self.gpu)?);
        }
        let (w, h) = self.internal_size();
        let mut probe_rq_ms = f64::NAN;
        if let Some(r) = &mut self.renderer {
            // A different scene: the cached AO belongs to the old geometry.
            r.clear_cache()?;
            // Rasterised or ray-traced primary visibility, whichever is faster for this scene here.
            let probe = Camera {
                width: w,
                height: h,
                ..self.nav.cam
            };
            let settings = self.prefs.settings.clone().with_radius(radius);
            let frame = FrameDesc::new(&scene_gpu, scene.f(), probe, &settings);
            probe_rq_ms = setup::choose_primary(&self.gpu, r, p.primary, false, &frame)?.1;
            // The first frames after opening answer input as soon as any other (no pipeline compiles in them).
            let t = Instant::now();
            r.warm_up(&FrameDesc {
                jitter: true,
                ..FrameDesc::new(&scene_gpu, scene.f(), probe, &settings)
            })?;
            log::info!("passes warmed up in {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
        }
        let pacing = pacing(&self.prefs, self.render_scale);
        self.pacer
            .scene_installed(probe_rq_ms, w as u64 * h as u64, pacing);
        self.prefs.settings.map.ao_radius = radius;
        self.scene_gpu = Some(scene_gpu);
        self.scene = Some(scene);
        self.scene_spec = spec.to_string();
        let title = format!(
            "hrtao — {}",
            Path::new(spec)
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_else(|| spec.to_string())
        );
        self.egui_ctx
            .send_viewport_cmd(egui::ViewportCommand::Title(title));
        Ok(())
    }

    /// The window's monitor refreshes at `refresh_mhz` millihertz (None: unknown): a GPU's frame-time target.
    pub(crate) fn display_refresh(&mut self, refresh_mhz: Option<u32>) {
        self.pacer.display_refresh(refresh_mhz);
    }

    /// Internal resolution of a still image: the 3D view rectangle times the render scale.
    fn internal_size(&self) -> (u32, u32) {
        self.internal_size_at(self.render_scale)
    }

    /// Internal resolution at `scale` (1 when the swapchain cannot blit: the output is copied 1:1).
    fn internal_size_at(&self, scale: f32) -> (u32, u32) {
        let can_scale = self.presenter.blit_ok || self.presenter.images.is_empty();
        internal_size(self.view_rect, can_scale, scale)
    }

    /// Selects one instance (u32::MAX: nothing), as a pick in the view does, and reveals its tree node.
    fn set_selected(&mut self, sel: u32) {
        let Some(scene) = &self.scene else {
            return;
        };
        let selection = tree::Selection::of_instance(&scene.tree, sel);
        if let Some(node) = selection.node {
            let path: Vec<&str> = scene
                .tree
                .path(node)
                .iter()
                .map(|&n| scene.tree.nodes[n as usize].name.as_str())
                .collect();
            log::info!("selected instance {sel} (tree: {})", path.join(" / "));
        }
        self.panels.tree.reveal(selection.node);
        self.apply_selection(selection);
    }

    /// Shift/Ctrl+click: adds the instance to the selection or removes it (u32::MAX: nothing changes).
    fn toggle_selected(&mut self, instance: u32) {
        let Some(scene) = &self.scene else {
            return;
        };
        let selection = self.selection.toggled(&scene.tree, instance);
        log::info!(
            "selection: {} instances {:?}",
            selection.instances.len(),
            selection.instances
        );
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
        let count = scene.instances.len();
        let highlight = self.selection.instances.as_slice();
        let result = edits::run_action(&mut self.edits, scene, sg, highlight, action);
        match result {
            Ok(Some(label)) => {
                log::info!(
                    "edit: {label}: F = {}, {} instances",
                    scene.f(),
                    scene.instances.len()
                );
                // Deletes (and their undo) shift later ids: select the node again, or nothing.
                if scene.instances.len() != count {
                    let again = match self.selection.node {
                        Some(n) if self.selection.instances.len() > 1 => {
                            tree::Selection::of_node(&scene.tree, n)
                        }
                        _ => tree::Selection::default(),
                    };
                    self.apply_selection(again);
                }
            }
            Ok(None) => {}
            Err(e) => self.toast(format!("edit failed: {e:#}"), true),
        }
    }

    /// The UI pass: the loader and the scripted run move on, the panels draw and send commands, the viewer
    /// applies them in order.
    fn ui(&mut self, ui: &mut egui::Ui) {
        self.clock.ui_started = Instant::now();
        self.poll_loading();
        self.poll_watch();
        self.script_orbit();
        if let Some(d) = self.script.deadline {
            if Instant::now() > d {
                self.script.deadline = None;
                self.fatal("scripted run timed out (--timeout)".into());
            }
        }
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
            can_scale: self.presenter.blit_ok || self.presenter.images.is_empty(),
            view_rect: self.view_rect,
            report: self.last_report.as_ref(),
            internal: self.renderer.as_ref().map_or((0, 0), |r| r.size()),
            frame_ms: self.pacer.averages(),
            rays_per_frame: self.pacer.rays_per_frame(),
            target_ms: self.pacer.target_ms(pacing(&self.prefs, self.render_scale)),
            loading: self.loader.view(),
            load_error: self.loader.error.as_deref(),
            undo: self.edits.undo_label(),
            redo: self.edits.redo_label(),
            shot: self.shots.progress(),
        };
        let commands = self.panels.ui(ui, &state);
        ui::draw_toasts(ui.ctx(), &mut self.toasts);
        for c in commands {
            self.apply(c);
        }
        self.walk_tick();
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
            Command::CancelLoading => self.cancel_loading(),
            Command::Select(selection) => self.apply_selection(selection),
            Command::SelectInstance(instance) => self.set_selected(instance),
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
            Command::Prefs(p) => {
                // The AO settings change through Command::Settings only (validated).
                let settings = std::mem::take(&mut self.prefs.settings);
                self.prefs = *p;
                self.prefs.settings = settings;
            }
            Command::RenderScale(scale) => self.render_scale = scale.clamp(0.05, 2.0),
            Command::UpAxis(up) => self.set_up_axis(up),
            Command::Walk(on) => self.set_walking(on, None),
            Command::Plan(storey) => self.plan_view(storey),
            Command::ClearCache => {
                if let Some(Err(e)) = self.renderer.as_mut().map(|r| r.clear_cache()) {
                    self.toast(format!("{e}"), true);
                }
            }
            Command::Camera { cam, pivot } => {
                self.nav.cam = cam;
                self.nav.pivot = pivot;
            }
            Command::Drag { dragging, moved } => self.pacer.drag(dragging, moved),
            Command::Sections(sections) => self.apply_sections(sections),
            Command::Screenshot => self.request_screenshot(),
            Command::CancelScreenshot(why) => self.cancel_background_shot(why),
            Command::Fullscreen(on) => {
                log::info!("full screen {}", if on { "on" } else { "off" });
                self.egui_ctx
                    .send_viewport_cmd(egui::ViewportCommand::Fullscreen(on));
            }
            Command::Quit => {
                log::info!("quit (Ctrl+Q)");
                self.exit_signal.send(ExitCode::SUCCESS);
            }
            Command::ViewRect(rect) => {
                // Laid out once two UI passes agree: the side panel grows to fit its content over the first
                // passes, and the first scene is framed and rendered at the size the view keeps.
                if !self.laid_out {
                    self.laid_out = rect == self.view_rect;
                    self.egui_ctx.request_repaint();
                }
                self.view_rect = rect;
            }
            Command::Toast { text, error } => self.toast(text, error),
        }
    }

    /// A click or double-click in the view at `at` (fractions of the view): picks the surface under it from the
    /// last frame's G-buffer and selects, toggles, sets the pivot or measures.
    fn pick(&mut self, at: [f32; 2], purpose: PickFor) {
        // The surface faces up: a floor to stand on.
        let mut floor_hit = false;
        let hit = match &self.renderer {
            Some(r) if (0.0..1.0).contains(&at[0]) && (0.0..1.0).contains(&at[1]) => {
                let (iw, ih) = r.size();
                let (x, y) = ((at[0] * iw as f32) as u32, (at[1] * ih as f32) as u32);
                self.gpu.wait_idle();
                match r.pick(x, y) {
                    Ok(px) => {
                        floor_hit = px.is_some_and(|px| {
                            Vec3::from(px.normal).dot(self.nav.world_up.vector()) > walk::FLOOR_COS
                        });
                        px.map(|px| (Vec3::from_slice(&px.position[..3]), px.instance))
                    }
                    Err(e) => {
                        self.toast(format!("pick failed: {e}"), true);
                        return;
                    }
                }
            }
            _ => None,
        };
        match (purpose, hit) {
            (PickFor::Select, _) => {
                let sel = hit.map_or(u32::MAX, |h| h.1);
                if sel != self.selection.primary() {
                    self.set_selected(sel);
                }
            }
            (PickFor::Toggle, _) => self.toggle_selected(hit.map_or(u32::MAX, |h| h.1)),
            (PickFor::Pivot, Some((pos, _))) if floor_hit && self.walk_here() => {
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

    /// Renders `frames` frames of the current view at `size` with the main renderer (its world-space cache is
    /// warm and survives the resize), reads the image back and restores the view resolution.
    fn render_offscreen(&mut self, size: (u32, u32), frames: u32) -> Result<Vec<u8>> {
        let (Some(r), Some(sg), Some(scene)) = (&mut self.renderer, &self.scene_gpu, &self.scene) else {
            bail!("no scene is open");
        };
        let cam = Camera {
            width: size.0,
            height: size.1,
            ..self.nav.cam
        };
        // The view's frame at another size (RGBA output): the next view frame restarts its still image.
        let frame = FrameDesc {
            jitter: true,
            budget: Some(self.pacer.budget()),
            ..FrameDesc::new(sg, scene.f(), cam, &self.prefs.settings)
        };
        for _ in 0..frames.max(1) {
            r.render(&frame)?;
        }
        Ok(r.read_rgba()?)
    }

    /// Takes a screenshot of the 3D view without UI and writes the PNG on a background thread.
    fn take_screenshot(&mut self, req: shots::ShotRequest) -> Result<PathBuf> {
        let size = req
            .size
            .unwrap_or((self.view_rect[2].max(1) as u32, self.view_rect[3].max(1) as u32));
        let rgba = self.render_offscreen(size, req.frames)?;
        if let Some(dir) = req.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        hrtao_core::imageio::write_png(&req.path, size.0, size.1, &rgba)
            .with_context(|| format!("cannot write {}", req.path.display()))?;
        Ok(req.path)
    }

    /// `MODEL-YYYYMMDD-HHMMSS.png` in the panel's folder, else the pictures directory, else the working directory.
    fn screenshot_path(&self) -> PathBuf {
        let folder = self
            .prefs
            .screenshot_folder
            .clone()
            .or_else(prefs::pictures_dir)
            .unwrap_or_default();
        let model = self.scene.as_ref().map_or("hrtao", |s| s.name.as_str());
        unique_path(&folder, &screenshot_name(model, jiff::Zoned::now()))
    }

    /// F12/the button: a custom size renders in the background; the window's size right away.
    fn request_screenshot(&mut self) {
        let path = self.screenshot_path();
        if self.prefs.screenshot_custom {
            let size = (self.prefs.screenshot_width, self.prefs.screenshot_height);
            self.start_background_shot(size, path);
            return;
        }
        self.shots.pending = Some(shots::ShotRequest {
            size: None,
            frames: self.prefs.screenshot_frames.min(4),
            path,
        });
    }

    /// Starts a background screenshot of the current view at `size` (one at a time).
    fn start_background_shot(&mut self, size: (u32, u32), path: PathBuf) {
        // A slice costs about what a moving frame of the view costs (the frame-time target).
        let (w, h) = self.internal_size_at(self.pacer.moving_scale().min(self.render_scale));
        let (gpu, settings, cam) = (&self.gpu, &self.prefs.settings, &self.nav.cam);
        let primary = self
            .scene_gpu
            .as_ref()
            .and(self.renderer.as_ref())
            .map(|r| r.primary());
        let started = self.shots.start(size, || {
            // The folder first: a bad destination fails now, not after minutes of rendering.
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
            }
            let primary = primary.ok_or_else(|| anyhow!("no scene is open"))?;
            let pixels = w as u64 * h as u64;
            shot::BackgroundShot::new(gpu, settings, cam, size, path, pixels, primary)
        });
        match started {
            Ok(msg) => self.toast(msg, false),
            Err(e) => self.shot_failed(e),
        }
    }

    /// Cancel button (or a new scene): the background screenshot is dropped.
    fn cancel_background_shot(&mut self, why: &str) {
        if self.shots.cancel() {
            // Its last frame was waited for with the viewer's frame: nothing of it is in flight.
            self.toast(format!("screenshot cancelled{why}"), false);
        }
    }

    /// A failed screenshot: a toast (fatal in a scripted run with a background screenshot); the viewer keeps
    /// running.
    fn shot_failed(&mut self, msg: String) {
        if self.script.screenshot_size.is_some() && self.script.frames.is_some() {
            self.fatal(msg);
        } else {
            self.toast(msg, true);
        }
    }

    /// After the viewer's frame completed: the background screenshot's frame. Returns its GPU milliseconds.
    fn finish_shot_frame(&mut self, viewer_rendered: bool) -> f64 {
        self.shots.finish_frame(viewer_rendered).unwrap_or_else(|e| {
            self.shot_failed(e);
            0.0
        })
    }

    /// Polls the PNG writer of a background screenshot.
    fn poll_saving(&mut self) {
        match self.shots.poll_saving() {
            Some(Ok(sm)) => {
                self.toast(
                    format!(
                        "screenshot saved: {} ({}×{}, {} tiles, {} frames, {:.1} s)",
                        sm.path.display(),
                        sm.size[0],
                        sm.size[1],
                        sm.tiles,
                        sm.frames,
                        sm.seconds
                    ),
                    false,
                );
                if let Some(log) = &mut self.script.stats {
                    log.screenshot = Some(sm);
                }
            }
            Some(Err(e)) => self.shot_failed(e),
            None => {}
        }
    }

    /// Scripted UI capture (`--screenshot-ui`): records the copy of the presented image (3D view and UI).
    fn record_ui_capture(&mut self, cmd: vk::CommandBuffer, index: u32) -> Result<Option<UiCapture>> {
        if !(self.script.ui_capture_pending && self.presenter.readback_ok) {
            return Ok(None);
        }
        self.script.ui_capture_pending = false;
        let Some(path) = self.script.screenshot_ui.clone() else {
            return Ok(None);
        };
        let (w, h) = (self.presenter.extent.width, self.presenter.extent.height);
        let buf = Buffer::new(
            &self.gpu,
            "window readback",
            w as u64 * h as u64 * 4,
            MemoryLocation::GpuToCpu,
            vk::BufferUsageFlags::empty(),
        )?;
        self.presenter.record_readback(cmd, index, buf.raw);
        let bgra = self.presenter.is_bgra();
        Ok(Some(UiCapture {
            path,
            buf,
            size: (w, h),
            bgra,
        }))
    }

    /// After the frame: writes the UI capture's PNG (a surface that cannot be read back fails the run).
    fn finish_ui_capture(&mut self, capture: Option<UiCapture>) -> Result<()> {
        let Some(UiCapture {
            path,
            buf,
            size: (w, h),
            bgra,
        }) = capture
        else {
            if self.script.ui_capture_pending {
                self.fatal("this surface cannot be read back (no TRANSFER_SRC)".into());
            }
            return Ok(());
        };
        let mut px: Vec<u8> = buf.read((w * h * 4) as usize)?;
        for p in px.chunks_exact_mut(4) {
            if bgra {
                p.swap(0, 2);
            }
            p[3] = 255;
        }
        match hrtao_core::imageio::write_png(&path, w, h, &px) {
            Ok(()) => self.toast(format!("window captured: {}", path.display()), false),
            Err(e) => self.fatal(format!("cannot write {}: {e}", path.display())),
        }
        Ok(())
    }

    /// The swapchain image to draw into: the swapchain recreated first when the window's size changed (egui's
    /// renderer told), None when there is none to draw into now (a repaint is asked for when it is out of date).
    fn next_image(&mut self, size: winit::dpi::PhysicalSize<u32>) -> Result<Option<u32>> {
        let p = &mut self.presenter;
        if (p.dirty || p.extent.width != size.width || p.extent.height != size.height)
            && !p.recreate(size.width, size.height)?
        {
            std::thread::sleep(Duration::from_millis(30));
            return Ok(None);
        }
        let index = self.presenter.acquire()?;
        if index.is_none() {
            // Out of date: the next frame recreates the swapchain.
            self.egui_ctx.request_repaint();
        }
        Ok(index)
    }

    /// The UI pass of a frame: egui's input, the panels, the clock.
    fn ui_pass(&mut self, ui: &mut egui::Ui) {
        self.latency.ui_pass(latency::egui_has_input(ui.ctx()));
        self.ui(ui);
        self.clock.ui_done = Instant::now();
    }

    /// A frame after its UI pass (an error is fatal: shown, and the exit status of scripted runs).
    fn paint(&mut self, size: winit::dpi::PhysicalSize<u32>, mut ui: UiFrame) {
        // egui's texture changes apply whether or not this frame presents: later frames' shapes use them. The
        // textures it changes or frees may be in use by frames in flight: those complete first.
        if !(ui.textures.set.is_empty() && ui.textures.free.is_empty()) {
            if let Err(e) = self.complete_frames(0) {
                self.fatal(format!("{e:#}"));
            }
        }
        let pool = self.presenter.pool;
        if let Err(e) = self
            .presenter
            .ui
            .prepare(pool, &mut ui.textures, &mut ui.primitives)
            .and_then(|()| self.draw(size, &ui))
        {
            self.fatal(format!("{e:#}"));
        }
        // The frame that drew with them has completed (or none was submitted).
        self.presenter.ui.frame_done();
    }

    /// The per-frame work: swapchain upkeep, the pacer's plan, the renderer's passes, the blit, egui, present,
    /// what the frame measured.
    fn draw(&mut self, size: winit::dpi::PhysicalSize<u32>, ui: &UiFrame) -> Result<()> {
        if self.shut_down {
            return Ok(());
        }
        let mut split = stats::CpuSplit {
            ui: ms_between(self.clock.ui_started, self.clock.ui_done),
            ..Default::default()
        };
        let mut laps = stats::Laps::start_at(self.clock.ui_done);
        split.tessellate = laps.lap();
        if size.width == 0 || size.height == 0 {
            // Minimised: nothing to present; don't spin.
            std::thread::sleep(Duration::from_millis(30));
            return Ok(());
        }
        self.poll_saving();
        // The frames the device finished meanwhile: their reports before this frame's plan. All frames in flight
        // before a screenshot is taken or a frame whose results are read from buffers the next one overwrites.
        self.complete_finished_frames()?;
        if self.shots.pending.is_some() || self.frames_to_keep() == 0 {
            self.complete_frames(0)?;
        }
        if let Some(req) = self.shots.pending.take() {
            match self.take_screenshot(req) {
                Ok(p) => self.toast(format!("screenshot saved: {}", p.display()), false),
                Err(e) => self.toast(format!("screenshot failed: {e:#}"), true),
            }
        }
        let Some(index) = self.next_image(size)? else {
            return Ok(());
        };
        // The 3D view rectangle, clamped to the swapchain.
        self.view_rect = self.presenter.clamp(self.view_rect);
        let script_running = self.script.frames.is_some() && !self.script.done;
        let (rect, can_scale) = (
            self.view_rect,
            self.presenter.blit_ok || self.presenter.images.is_empty(),
        );
        let size_at = move |scale| internal_size(rect, can_scale, scale);
        let plan = self.pacer.plan(pacer::PlanInputs {
            now: self.clock.now(),
            camera: &self.nav.cam,
            pacing: pacing(&self.prefs, self.render_scale),
            output: self.renderer.as_ref().map(|r| r.size()),
            has_image: self.last_report.is_some(),
            scripted: script_running,
            shooting: self.shots.rendering(),
            size_at: &size_at,
        });
        split.acquire = laps.lap();
        let t0 = Instant::now();
        let cmd = self.presenter.begin_frame()?;
        // One frame of the background screenshot's current tile, before the view's own passes.
        let shot = self.shots.rendering();
        let shot_error = match (&self.scene_gpu, &self.scene) {
            (Some(sg), Some(scene)) => self.shots.record(cmd, sg, scene.f()).err(),
            _ => None,
        };
        let (src, rendered) = self.record_view_frame(cmd, &plan, script_running)?;
        // The input this frame answers: what came before it was recorded (not before it completed).
        let input = rendered.then(|| self.latency.take_input(plan.changed)).flatten();
        if let (true, Some((_, w, h))) = (self.presenter.blit_ok, src) {
            self.presenter.ensure_internal(w, h)?;
        }
        let bg = background(self.egui_ctx.global_style().visuals.dark_mode);
        self.presenter.record_view(cmd, index, src, self.view_rect, bg);
        split.record = laps.lap();
        self.presenter
            .ui
            .record(cmd, index, ui.pixels_per_point, &ui.primitives)?;
        split.egui_record = laps.lap();
        let capture = self.record_ui_capture(cmd, index)?;
        unsafe {
            self.gpu.device.end_command_buffer(cmd)?;
        }
        split.record += laps.lap();
        let slot = self.presenter.submit(index)?;
        let submitted = Instant::now();
        // One frame in flight: the frame completes before it is presented.
        let keep = self.frames_to_keep();
        if keep == 0 {
            self.presenter.wait(slot)?;
        }
        split.gpu_wait = laps.lap();
        self.presenter.present(index)?;
        let presented_ms = latency::monotonic_ms();
        split.present = laps.lap();
        self.frames.push(frames::Submitted {
            slot,
            waited: keep == 0,
            plan,
            rendered,
            shot,
            shot_error,
            capture,
            t0,
            presented_ms,
            split,
            laps,
            ui_started: self.clock.ui_started,
            submitted,
            device_ms: split.gpu_wait,
            input,
            camera: Camera {
                width: plan.size.0,
                height: plan.size.1,
                ..self.nav.cam
            },
        });
        self.complete_frames(keep)?;
        self.maybe_save_prefs(false);
        self.schedule_repaint();
        Ok(())
    }

    /// Frames in flight to keep after submitting one: the limit less one, none while a frame's results are
    /// read from buffers the next frame overwrites (a background screenshot's tiles, `--ao-out`) or the window
    /// is captured.
    fn frames_to_keep(&self) -> usize {
        let exclusive = self.shots.rendering() || self.latency.dumps_ao() || self.script.ui_capture_pending;
        if exclusive {
            0
        } else {
            self.frames.limit - 1
        }
    }

    /// Completes frames in flight, oldest first, until `keep` are left: waits for each and reads its results.
    fn complete_frames(&mut self, keep: usize) -> Result<()> {
        while let Some(f) = self.frames.pop_over(keep) {
            if !f.waited {
                self.presenter.wait(f.slot)?;
            }
            self.complete(f)?;
        }
        Ok(())
    }

    /// Completes the frames in flight the device has finished, without waiting.
    fn complete_finished_frames(&mut self) -> Result<()> {
        while let Some(slot) = self.frames.oldest_slot() {
            if !self.presenter.done(slot) {
                break;
            }
            let f = self.frames.pop_over(0).expect("a frame in flight");
            self.presenter.wait(f.slot)?;
            self.complete(f)?;
        }
        Ok(())
    }

    /// After a frame completed: the background screenshot's tile, the window capture, the view's report.
    fn complete(&mut self, mut f: frames::Submitted) -> Result<()> {
        let gpu_wall = f.t0.elapsed().as_secs_f64() * 1e3;
        if !f.waited {
            // Submitted, presented, completed later: its device time runs from the submission to now (at most:
            // the host may have found it complete late), the wait from its present to now (the spans stay
            // disjoint: the finish is timed from here).
            f.device_ms = f.submitted.elapsed().as_secs_f64() * 1e3;
            f.split.gpu_wait = f.laps.lap();
        }
        self.frames.overlapped += (f.ui_started < self.clock.ui_started) as u64;
        let shot_ms = if f.shot {
            self.finish_shot_frame(f.rendered)
        } else {
            0.0
        };
        if let Some(e) = f.shot_error.take() {
            // Dropped only now: its commands were in the frame just completed.
            self.shots.cancel();
            self.shot_failed(format!("screenshot failed: {e:#}"));
        }
        self.finish_ui_capture(f.capture.take())?;
        if f.rendered {
            self.frame_rendered(f, gpu_wall, shot_ms)?;
            self.script_step();
        }
        Ok(())
    }

    /// Records the view's own frame as `plan` says: renders (a frame, or a round's visibility ahead of its
    /// slices), or presents the output again (held, settling, or already converged on this view). Returns the
    /// output to present (buffer, width, height) and whether a frame was rendered.
    fn record_view_frame(
        &mut self,
        cmd: vk::CommandBuffer,
        plan: &pacer::FramePlan,
        script_running: bool,
    ) -> Result<(Option<ViewOutput>, bool)> {
        let (Some(r), Some(sg), Some(scene)) = (&mut self.renderer, &self.scene_gpu, &self.scene) else {
            return Ok((None, false));
        };
        let (iw, ih) = plan.size;
        let settings = plan.settings(&self.prefs.settings);
        let frame = FrameDesc {
            // s_p counts view pixels: cells keep their size when the render scale changes.
            view_height: self.view_rect[3].max(1) as u32,
            budget: Some(plan.budget),
            // Still frames are jittered and accumulated: anti-aliased stills (docs/algorithm.md).
            jitter: true,
            lattice: plan.lattice,
            output: Output {
                bgra: !self.presenter.blit_ok && self.presenter.is_bgra(),
                ..Output::default()
            },
            // The walk's gravity and collision rays (answered with this frame's report).
            probes: self.panels.walk.rays(),
            ..FrameDesc::new(
                sg,
                scene.f(),
                Camera {
                    width: iw,
                    height: ih,
                    ..self.nav.cam
                },
                &settings,
            )
        };
        // A converged image of this very view is already in the output: present it again (expose events, UI
        // repaints) instead of rendering. Scripted runs count rendered frames: they always render, except during
        // a background screenshot, where the view rests once converged as it would for a user.
        let scripted = script_running && !self.shots.in_background();
        let settling = self.pacer.settles(r.shows(&frame));
        let walk = self.panels.walk.wants_frames();
        let render = !plan.hold && !settling && (scripted || walk || !r.shows_final(&frame));
        // Each round of a still image in slices starts with the view's visibility drawn in a frame of its own
        // (`Renderer::record_visibility`): input that comes meanwhile waits for the draw alone, and the view
        // shows the last image until the round's first slice.
        if render && !plan.moving && r.record_visibility(cmd, &frame)? {
            let (w, h) = r.size();
            return Ok((Some((r.output_buffer().raw, w, h)), false));
        }
        if render {
            r.record_frame(cmd, &frame)?;
            self.panels.walk.submitted();
        }
        Ok((Some((r.output_buffer().raw, iw, ih)), render))
    }

    /// After a rendered frame: its report, what the pacer learns from it, the statistics and the AO dumps.
    fn frame_rendered(&mut self, f: frames::Submitted, gpu_wall: f64, shot_ms: f64) -> Result<()> {
        let frames::Submitted {
            plan,
            presented_ms,
            mut split,
            mut laps,
            ui_started,
            camera,
            input,
            device_ms,
            ..
        } = f;
        let full = self.internal_size();
        let Some(r) = self.renderer.as_mut() else {
            return Ok(());
        };
        let report = r.finish_frame(gpu_wall)?;
        self.panels.walk.hits(&report.probe_hits);
        let walk_stat = self.scene.as_ref().and_then(|s| self.panels.walk.stat(s.origin));
        let converged = pacer::image_converged(&report) && r.size() == full;
        let input_ms = input;
        let stats_index = self.script.stats.as_ref().map_or(0, |log| log.frames.len());
        let round_end = report.slice + 1 >= report.slices;
        let roughness = self.latency.dump_ao(r, stats_index, !plan.moving, round_end)?;
        split.finish = laps.lap();
        let wall_ms = ui_started.elapsed().as_secs_f64() * 1e3;
        let interval_ms = self.clock.rendered(ui_started);
        let (iw, ih) = plan.size;
        // The background screenshot's share of the frame is not the view's.
        let measured = pacer::FrameMeasurement {
            now: self.clock.now(),
            camera: Camera {
                width: iw,
                height: ih,
                ..camera
            },
            view_ms: (wall_ms - shot_ms).max(0.0),
            // The wait for the swapchain's image (a display's vsync) is not the frame's cost.
            wait_ms: split.acquire,
            rays: report.rays,
            ray_ms: report
                .gpu_ms
                .iter()
                .find(|(name, _)| name == hrtao_core::bench_json::HRTAO_PASSES[1])
                .map(|&(_, ms)| ms),
            device_ms,
            render_ms: gpu_wall,
            slices: report.slices,
            shooting: self.shots.rendering(),
        };
        // The statistics record the budget this frame traced with, before the frame-time target moves it.
        let rays_per_frame = self.pacer.rays_per_frame();
        self.pacer
            .observe(measured, pacing(&self.prefs, self.render_scale));
        if let Some(log) = &mut self.script.stats {
            log.frames.push(stats::FrameStat {
                wall_ms,
                gpu_ms: report.gpu_total_ms,
                gpu_sections_ms: report.gpu_ms.iter().cloned().collect(),
                internal: [iw, ih],
                view: [self.view_rect[2] as u32, self.view_rect[3] as u32],
                moving: plan.changed,
                still: !plan.moving,
                refining: !plan.moving && !converged,
                converged,
                slice: report.slice,
                slices: report.slices,
                presented_ms,
                input: input_ms.is_some(),
                input_ms: input_ms.map(|i| i.0),
                input_last_ms: input_ms.map(|i| i.1),
                roughness: None,
                rays: report.rays,
                rays_per_frame,
                non_finite: report.non_finite,
                cpu_ms: split,
                interval_ms,
                eye: walk_stat.map(|w| w.1),
                walk: walk_stat.map(|w| w.0),
            });
            for (i, value) in roughness {
                if let Some(f) = log.frames.get_mut(i) {
                    f.roughness = value;
                }
            }
        }
        // Window tests follow the still image's accumulation (`HRTAO_UI_PROBE`).
        ui_probe::note_text("accumulated", &report.accumulated_frames.to_string());
        self.last_report = Some(report);
        Ok(())
    }

    /// Asks for another frame while something is still changing (the pacer decides; a scripted run, a
    /// screenshot or a capture waits for frames too); otherwise the event loop waits for events.
    fn schedule_repaint(&mut self) {
        let now = Instant::now();
        let repaint = self.pacer.repaint(pacer::RepaintInputs {
            now: self.clock.now(),
            busy: (self.script.frames.is_some() && !self.script.done)
                || self.panels.walk.wants_frames()
                || self.shots.busy()
                || self.script.ui_capture_pending,
            viewing: self.renderer.is_some() && self.scene.is_some(),
            converged: self.converged_full(),
            loading: self.loader.is_loading(),
        });
        match repaint.wake {
            pacer::Wake::Now => self.egui_ctx.request_repaint(),
            pacer::Wake::After(d) => self.egui_ctx.request_repaint_after(d),
            pacer::Wake::Rest => {}
        }
        if repaint.came_to_rest {
            let frames = self.last_report.as_ref().map_or(0, |r| r.accumulated_frames);
            log::info!("at rest: the image has converged ({frames} frames); waiting for input");
        }
        match self.latency.exit_after(repaint.resting, now) {
            latency::ExitAfter::Now => self.exit_signal.send(ExitCode::SUCCESS),
            latency::ExitAfter::WakeIn(d) => self.egui_ctx.request_repaint_after(d),
            latency::ExitAfter::No => {}
        }
    }

    /// Scripted mode: count frames, resize, take the screenshots, exit.
    fn script_step(&mut self) {
        let Some(frames) = self.script.frames else {
            return;
        };
        if self.script.done {
            return;
        }
        self.script.rendered += 1;
        let n = self.script.rendered;
        if let Some((k, (w, h))) = self.script.resize {
            if n == k {
                log::info!("scripted resize to {w}x{h}");
                self.egui_ctx
                    .send_viewport_cmd(egui::ViewportCommand::InnerSize(egui::vec2(
                        w as f32 / self.egui_ctx.pixels_per_point(),
                        h as f32 / self.egui_ctx.pixels_per_point(),
                    )));
            }
        }
        if let Some((k, file)) = self.script.open.clone() {
            if n == k {
                log::info!("scripted open of {file}");
                self.apply(Command::Open(file));
            }
        }
        for (_, json) in self
            .script
            .set_at_frame
            .iter()
            .filter(|(k, _)| *k == n)
            .cloned()
            .collect::<Vec<_>>()
        {
            log::info!("scripted settings after frame {n}: {json}");
            match self.prefs.settings.with_overrides(&json) {
                Ok(s) => self.apply(Command::Settings(Box::new(s))),
                Err(e) => self.fatal(format!("--set-at-frame {n}: {e}")),
            }
        }
        if self.script.orbit_left > 0
            || self.panels.walk.script_running()
            || (self.script.wait_converged && !self.converged_full())
        {
            return;
        }
        if n >= frames && self.loader.is_loading() {
            // Let a scripted open finish (success or error) before the screenshots.
            return;
        }
        if n >= frames && !self.script.ui_captured && self.script.screenshot_ui.is_some() {
            // Captured with the next presented frame (after --frames N, or once --orbit has converged).
            self.script.ui_capture_pending = true;
            self.script.ui_captured = true;
            return;
        }
        if n >= frames {
            if let (Some(size), Some(path)) = (self.script.screenshot_size, self.script.screenshot.clone()) {
                // Rendered in the background while the window keeps drawing: the run ends once it is written.
                if !self.script.shot_started {
                    self.script.shot_started = true;
                    self.start_background_shot(size, path);
                }
                if self.shots.in_background() {
                    return;
                }
            }
            self.script.done = true;
            // The frames recorded after this one complete first: the screenshot renders with the view's
            // renderer, and the statistics end with them.
            if let Err(e) = self.complete_frames(0) {
                self.fatal(format!("{e:#}"));
            }
            if let Some(path) = self
                .script
                .screenshot
                .clone()
                .filter(|_| self.script.screenshot_size.is_none())
            {
                let req = shots::ShotRequest {
                    size: None,
                    frames: self.script.screenshot_frames,
                    path,
                };
                match self.take_screenshot(req) {
                    Ok(p) => log::info!("screenshot saved: {}", p.display()),
                    Err(e) => self.fatal(format!("screenshot failed: {e:#}")),
                }
            }
            if let Some(rep) = &self.last_report {
                log::info!(
                    "scripted run: {n} frames, last {:.1} ms ({}), {} rays, view {}x{}, internal {:?}, {} \
                     completed after the next frame began",
                    rep.wall_ms,
                    if rep.gpu_ms.is_empty() {
                        "passes not timed".to_string()
                    } else {
                        format!("{:.1} ms GPU", rep.gpu_total_ms)
                    },
                    rep.rays,
                    self.view_rect[2],
                    self.view_rect[3],
                    self.renderer.as_ref().map(|r| r.size()),
                    self.frames.overlapped
                );
            }
            self.write_stats();
            if self.script.exit {
                let bad = self.gpu.validation_messages() > 0
                    || self.outcome.lock().map(|o| o.error.is_some()).unwrap_or(true);
                self.exit_signal
                    .send(if bad { ExitCode::FAILURE } else { ExitCode::SUCCESS });
            }
        }
    }

    /// The last frame shows a converged image at the full internal size.
    fn converged_full(&self) -> bool {
        let full = self.internal_size();
        match (&self.last_report, &self.renderer) {
            (Some(rep), Some(r)) => pacer::image_converged(rep) && r.size() == full,
            _ => false,
        }
    }

    /// Scripted mode: one step of `--orbit` (2° about the pivot, around the world up axis).
    fn script_orbit(&mut self) {
        if self.script.frames.is_none() || self.script.orbit_left == 0 || self.scene.is_none() {
            return;
        }
        if self.loader.is_loading() || self.last_report.is_none() {
            return;
        }
        self.script.orbit_left -= 1;
        let cam = nav::orbit(
            &self.nav.cam,
            self.nav.pivot,
            self.nav.world_up.vector(),
            2f32.to_radians(),
            0.0,
        );
        self.apply(Command::Camera {
            cam,
            pivot: self.nav.pivot,
        });
    }

    /// Writes `--stats` (once; an error is fatal in scripted mode).
    fn write_stats(&mut self) {
        let Some(log) = self.script.stats.take() else {
            return;
        };
        match log.write(
            &self.gpu.info,
            self.pacer.target_ms(pacing(&self.prefs, self.render_scale)),
            &self.scene_spec,
            (self.frames.limit, self.frames.overlapped),
        ) {
            Ok(()) => log::info!(
                "stats written to {} ({} frames, median moving {:.1} ms, still {:.1} ms)",
                log.path().display(),
                log.frames.len(),
                log.median_wall_ms(true).unwrap_or(f64::NAN),
                log.median_wall_ms(false).unwrap_or(f64::NAN)
            ),
            Err(e) => self.fatal(format!("{e:#}")),
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
        if self.shut_down {
            return;
        }
        self.shut_down = true;
        self.maybe_save_prefs(true);
        if let Err(e) = self.complete_frames(0) {
            log::warn!("the last frames: {e:#}");
        }
        self.frames.clear();
        self.write_stats();
        self.gpu.wait_idle();
        self.shots = shots::Shots::default();
        self.renderer = None;
        self.scene_gpu = None;
        self.presenter.destroy();
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// `MODEL-YYYYMMDD-HHMMSS` in local time, the model's name made safe for a file name.
fn screenshot_name(model: &str, t: jiff::Zoned) -> String {
    let model: String = model
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    let model = model.trim_start_matches('.');
    let model = if model.is_empty() { "hrtao" } else { model };
    format!("{model}-{}", t.strftime("%Y%m%d-%H%M%S"))
}

/// `folder/NAME.png`, or `folder/NAME-2.png`, `-3`… when that file exists (two shots in one second).
fn unique_path(folder: &Path, name: &str) -> PathBuf {
    (1..)
        .map(|i| match i {
            1 => folder.join(format!("{name}.png")),
            _ => folder.join(format!("{name}-{i}.png")),
        })
        .find(|p| !p.exists())
        .expect("a free name")
}

/// The internal resolution of the view `rect` at `scale` (1 when the swapchain cannot blit: the output is
/// copied 1:1).
fn internal_size(rect: [i32; 4], can_scale: bool, scale: f32) -> (u32, u32) {
    let scale = if can_scale { scale } else { 1.0 };
    let w = ((rect[2].max(1) as f32) * scale).round().max(1.0) as u32;
    let h = ((rect[3].max(1) as f32) * scale).round().max(1.0) as u32;
    (w.min(16384), h.min(16384))
}

/// The window's colour around and behind the 3D view, by the UI's theme.
fn background(dark: bool) -> [f32; 4] {
    if dark {
        [0.11, 0.11, 0.12, 1.0]
    } else {
        [0.93, 0.93, 0.94, 1.0]
    }
}

/// What pacing follows of the user's settings.
fn pacing(prefs: &Prefs, render_scale: f32) -> pacer::Pacing<'_> {
    pacer::Pacing {
        auto_budget: prefs.auto_budget,
        target_ms: prefs.frame_target_ms,
        rays_per_frame: prefs.rays_per_frame,
        render_scale,
        settings: &prefs.settings,
    }
}

/// Milliseconds from `a` to `b` (0 when `b` is earlier).
fn ms_between(a: Instant, b: Instant) -> f64 {
    b.saturating_duration_since(a).as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_and_sizes() {
        let t = jiff::Timestamp::from_second(1_704_067_200)
            .unwrap()
            .to_zoned(jiff::tz::TimeZone::UTC);
        assert_eq!(screenshot_name("gearbox", t.clone()), "gearbox-20240101-000000");
        assert_eq!(screenshot_name("../a b", t.clone()), "_a_b-20240101-000000");
        assert_eq!(screenshot_name("", t), "hrtao-20240101-000000");
        let dir = std::env::temp_dir().join(format!("hrtao-unique-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let first = unique_path(&dir, "m");
        assert_eq!(first, dir.join("m.png"));
        std::fs::write(&first, b"").unwrap();
        assert_eq!(unique_path(&dir, "m"), dir.join("m-2.png"));
        std::fs::remove_dir_all(&dir).unwrap();
        use crate::cli::parse_size;
        assert_eq!(parse_size("480x270").unwrap(), (480, 270));
        assert!(parse_size("0x10").is_err() && parse_size("abc").is_err());
    }
}
