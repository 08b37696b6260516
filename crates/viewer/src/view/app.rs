//! The window's event loop (winit's `ApplicationHandler`) and egui's platform glue (egui-winit). On `resumed` it
//! opens the window, the device, the presenter and the viewer; it hands window events to egui and the viewer,
//! and paints (UI pass, then `Viewer::paint`, whose frame loop records the view and egui through
//! egui-ash-renderer) on `RedrawRequested` and when a repaint egui was asked for comes due. Otherwise it waits:
//! for input, or until that time (`ControlFlow::WaitUntil`), so a viewer at rest sleeps. `run` is `hrtao view`:
//! the arguments checked, the loop, and the process's outcome (the first error, the validation messages).
use std::cell::Cell;
use std::process::ExitCode;
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use hrtao_core::{ContextOptions, Gpu};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, DeviceId, StartCause, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::raw_window_handle::HasDisplayHandle;
use winit::window::{Window, WindowId};

use super::present::Presenter;
use super::script::ScriptHooks;
use super::Viewer;
use crate::cli::ViewArgs;

/// How the viewer asks the loop to end (the first code asked for is the process's).
#[derive(Clone, Default)]
pub(crate) struct ExitSignal(Rc<Cell<Option<ExitCode>>>);

impl ExitSignal {
    pub fn send(&self, code: ExitCode) {
        if self.0.get().is_none() {
            self.0.set(Some(code));
        }
    }

    fn requested(&self) -> Option<ExitCode> {
        self.0.get()
    }
}

/// How the viewer ends the run: the event loop's exit request, and the outcome the process reports.
pub(super) struct Exit {
    pub signal: ExitSignal,
    outcome: Arc<Mutex<Outcome>>,
}

impl Exit {
    /// Remembers the first error for the exit status.
    pub fn error(&self, msg: &str) {
        let mut o = self.outcome.lock().unwrap_or_else(|p| p.into_inner());
        if o.error.is_none() {
            o.error = Some(msg.to_string());
        }
    }

    /// An error was remembered.
    pub fn failed(&self) -> bool {
        self.outcome.lock().map(|o| o.error.is_some()).unwrap_or(true)
    }
}

/// egui asked for a repaint (from any thread): wakes the loop.
struct Wake;

/// When egui wants the next paint. egui's repaint callback (any thread, also inside a UI pass) records the
/// earliest requested time and wakes the loop; the loop paints when that time has come and otherwise sleeps
/// until it, or until the next event.
struct RepaintSchedule {
    next: Arc<Mutex<Option<Instant>>>,
}

impl RepaintSchedule {
    fn new(ctx: &egui::Context, proxy: EventLoopProxy<Wake>) -> Self {
        let next = Arc::new(Mutex::new(Some(Instant::now())));
        let shared = next.clone();
        let proxy = Mutex::new(proxy);
        ctx.set_request_repaint_callback(move |info| {
            let now = Instant::now();
            let when = now
                .checked_add(info.delay)
                .unwrap_or(now + Duration::from_secs(86_400));
            let mut next = shared.lock().unwrap_or_else(|p| p.into_inner());
            if next.is_none_or(|t| when < t) {
                *next = Some(when);
                drop(next);
                let _ = proxy.lock().unwrap_or_else(|p| p.into_inner()).send_event(Wake);
            }
        });
        Self { next }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Option<Instant>> {
        self.next.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A paint starts: the requests made before it are served by it.
    fn clear(&self) {
        *self.lock() = None;
    }

    fn due(&self) -> bool {
        self.lock().is_some_and(|t| t <= Instant::now())
    }

    fn control_flow(&self) -> ControlFlow {
        match *self.lock() {
            Some(t) => ControlFlow::WaitUntil(t),
            None => ControlFlow::Wait,
        }
    }
}

/// The open window: the viewer (which owns the device objects, the surface included) is dropped before the
/// window it presents to.
struct Running {
    viewer: Viewer,
    egui: egui_winit::State,
    info: egui::ViewportInfo,
    /// The window changed (size, position, focus, scale, visibility): `info` is read again before the next UI
    /// pass. Reading it costs synchronous round trips to the window system (on X11 a dozen), so not every frame.
    info_stale: bool,
    window: Window,
}

struct App {
    args: ViewArgs,
    hooks: ScriptHooks,
    outcome: Arc<Mutex<Outcome>>,
    ctx: egui::Context,
    repaint: RepaintSchedule,
    exit: ExitSignal,
    running: Option<Running>,
}

/// What ties the viewer to the app and the scripted run: the script's hooks, and the exit request and the
/// outcome the process reports.
pub(super) struct Links {
    pub hooks: ScriptHooks,
    pub exit: Exit,
}

/// What the process reports when the window closes.
#[derive(Default)]
pub(super) struct Outcome {
    error: Option<String>,
    gpu: Option<Arc<Gpu>>,
}

/// Checks the arguments, runs the window and reports how it ended: the first error, the validation layer's
/// messages, or the exit code.
pub(super) fn run(args: &ViewArgs) -> Result<()> {
    let hooks = ScriptHooks::parse(args)?;
    if args.sections.section.len() > hrtao_core::gpu::MAX_SECTIONS as usize {
        bail!(
            "at most {} section planes are supported",
            hrtao_core::gpu::MAX_SECTIONS
        );
    }
    let unset = |v: &str| std::env::var_os(v).is_none_or(|x| x.is_empty());
    if unset("DISPLAY") && unset("WAYLAND_DISPLAY") {
        bail!(
            "no display: set DISPLAY (e.g. run under `xvfb-run -a`) or use `hrtao render` for headless use"
        );
    }
    let outcome = Arc::new(Mutex::new(Outcome::default()));
    let code = run_loop(args, hooks, outcome.clone());
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

/// Opens the window and runs the loop until the viewer or the user ends it.
fn run_loop(args: &ViewArgs, hooks: ScriptHooks, outcome: Arc<Mutex<Outcome>>) -> Result<ExitCode> {
    let event_loop = EventLoop::<Wake>::with_user_event()
        .build()
        .context("cannot open the window system's event loop")?;
    event_loop.set_control_flow(ControlFlow::Wait);
    let ctx = egui::Context::default();
    let repaint = RepaintSchedule::new(&ctx, event_loop.create_proxy());
    let mut app = App {
        args: args.clone(),
        hooks,
        outcome,
        ctx,
        repaint,
        exit: ExitSignal::default(),
        running: None,
    };
    event_loop
        .run_app(&mut app)
        .context("the window's event loop failed")?;
    // Whatever is still open goes now, before the device (held by the outcome) is released.
    if let Some(r) = app.running.take() {
        drop(r);
    }
    Ok(app.exit.requested().unwrap_or(ExitCode::SUCCESS))
}

impl App {
    /// The window, the device, the presenter and the viewer.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Running> {
        let (w, h) = self.args.size.unwrap_or((1280, 800));
        let builder = egui::ViewportBuilder::default()
            .with_title("hrtao")
            // Wayland app_id and X11 WM_CLASS: the desktop entry packaging/hrtao.desktop matches it.
            .with_app_id(super::APP_ID)
            .with_inner_size([w as f32, h as f32])
            .with_drag_and_drop(true);
        let window =
            egui_winit::create_window(&self.ctx, event_loop, &builder).context("cannot open the window")?;
        egui_winit::apply_viewport_builder_to_window(&self.ctx, &window, &builder);
        // Instance extensions for the window system; ash-window's list is 'static.
        let display = event_loop
            .display_handle()
            .context("the window system has no display handle")?
            .as_raw();
        let surface_extensions = ash_window::enumerate_required_extensions(display)
            .map(|list| {
                list.iter()
                    .map(|&p| unsafe { std::ffi::CStr::from_ptr(p) })
                    .collect()
            })
            .unwrap_or_default();
        // The preferences first: they name the ray backend the device is opened with.
        let prefs_path = (!self.args.no_config).then(|| {
            self.args
                .config
                .clone()
                .unwrap_or_else(super::prefs::default_path)
        });
        let (prefs_file, prefs, mut prefs_msg) = super::prefs::PrefsFile::open(prefs_path);
        let mut opts = ContextOptions {
            validation: self.args.device.validation || hrtao_core::context::validation_requested_by_env(),
            device: self.args.device.device.clone(),
            ray_backend: super::prefs::ray_backend(self.args.device.ray_backend, prefs.ray_backend),
            surface_extensions,
            ..Default::default()
        };
        let gpu = match Gpu::new(&opts) {
            // A saved backend this device lacks (the preferences came from another machine): the device's own.
            Err(e) if self.args.device.ray_backend.is_none() && opts.ray_backend.is_some() => {
                let saved = opts.ray_backend.take().map_or("", |b| b.name());
                prefs_msg = Some(format!(
                    "the saved ray backend `{saved}` cannot be used here ({e:#}): the device's own is used"
                ));
                Gpu::new(&opts)?
            }
            r => r?,
        };
        self.outcome.lock().unwrap_or_else(|p| p.into_inner()).gpu = Some(gpu.clone());
        let presenter = Presenter::new(&gpu, &window)?;
        let max_texture_side = gpu.limits.max_image_dimension2_d as usize;
        let egui = egui_winit::State::new(
            self.ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_texture_side),
        );
        let mut viewer = Viewer::new(
            gpu,
            presenter,
            &self.args,
            Links {
                hooks: self.hooks.clone(),
                exit: Exit {
                    signal: self.exit.clone(),
                    outcome: self.outcome.clone(),
                },
            },
            self.ctx.clone(),
            (prefs_file, prefs, prefs_msg),
        );
        // The display's refresh: a GPU's frame-time target (none under Xvfb: the pacer assumes 60 Hz).
        viewer.display_refresh(window.current_monitor().and_then(|m| m.refresh_rate_millihertz()));
        let mut info = egui::ViewportInfo::default();
        egui_winit::update_viewport_info(&mut info, &self.ctx, &window, true);
        Ok(Running {
            viewer,
            egui,
            info,
            info_stale: false,
            window,
        })
    }

    /// One frame: egui's UI pass over the input gathered since the last one, its platform output and viewport
    /// commands, then the viewer's frame with egui's shapes on top.
    fn paint(&mut self) {
        self.repaint.clear();
        let Some(r) = self.running.as_mut() else {
            return;
        };
        if std::mem::take(&mut r.info_stale) {
            egui_winit::update_viewport_info(&mut r.info, &self.ctx, &r.window, false);
        }
        let mut raw = r.egui.take_egui_input(&r.window);
        raw.viewports = std::iter::once((egui::ViewportId::ROOT, r.info.clone())).collect();
        let viewer = &mut r.viewer;
        let output = self.ctx.run_ui(raw, |ui| viewer.ui_pass(ui));
        r.info.events.clear();
        r.egui.handle_platform_output(&r.window, output.platform_output);
        if let Some(vp) = output.viewport_output.get(&egui::ViewportId::ROOT) {
            let mut actions = Vec::new();
            r.info_stale |= !vp.commands.is_empty();
            egui_winit::process_viewport_commands(
                &self.ctx,
                &mut r.info,
                vp.commands.iter().cloned(),
                &r.window,
                &mut actions,
            );
        }
        let primitives = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        let frame = super::frame_loop::UiFrame {
            primitives,
            pixels_per_point: output.pixels_per_point,
            textures: output.textures_delta,
        };
        r.viewer.paint(r.window.inner_size(), frame);
    }

    /// Ends the loop when the viewer asked for it.
    fn check_exit(&mut self, event_loop: &ActiveEventLoop) {
        if self.exit.requested().is_some() {
            event_loop.exit();
        }
    }
}

impl ApplicationHandler<Wake> for App {
    fn new_events(&mut self, _: &ActiveEventLoop, cause: StartCause) {
        if let (Some(r), false) = (self.running.as_mut(), matches!(cause, StartCause::Init)) {
            r.viewer.frame_loop.latency.wake();
        }
    }

    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(r) => {
                self.running = Some(r);
                self.paint();
            }
            Err(e) => {
                let mut o = self.outcome.lock().unwrap_or_else(|p| p.into_inner());
                o.error.get_or_insert(format!("{e:#}"));
                drop(o);
                self.exit.send(ExitCode::FAILURE);
            }
        }
        self.check_exit(event_loop);
    }

    fn user_event(&mut self, _: &ActiveEventLoop, _: Wake) {
        // The schedule holds the time; `about_to_wait` acts on it.
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, id: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        if r.window.id() != id {
            return;
        }
        match &event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                return;
            }
            WindowEvent::RedrawRequested => {
                self.paint();
                self.check_exit(event_loop);
                return;
            }
            WindowEvent::Resized(_) | WindowEvent::ScaleFactorChanged { .. } => {
                r.viewer.frame_loop.presenter.dirty = true;
                r.info_stale = true;
            }
            WindowEvent::Moved(_) | WindowEvent::Focused(_) | WindowEvent::Occluded(_) => r.info_stale = true,
            _ => {}
        }
        let response = r.egui.on_window_event(&r.window, &event);
        if response.repaint {
            r.window.request_redraw();
        }
        // Events egui consumed (typing in a field) are not the 3D view's input; the pointer over the view is
        // seen in egui's input (`Latency::ui_pass`).
        if !response.consumed {
            r.viewer.frame_loop.latency.event(&event);
        }
        self.check_exit(event_loop);
    }

    fn device_event(&mut self, _: &ActiveEventLoop, _: DeviceId, event: DeviceEvent) {
        if let Some(r) = self.running.as_mut() {
            r.viewer.frame_loop.latency.device_event(&event);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.repaint.due() {
            self.paint();
        }
        self.check_exit(event_loop);
        event_loop.set_control_flow(self.repaint.control_flow());
    }

    fn exiting(&mut self, _: &ActiveEventLoop) {
        if let Some(mut r) = self.running.take() {
            r.viewer.shutdown();
            drop(r);
        }
    }
}
