//! The viewer's per-frame GPU loop: the swapchain (`Presenter`), the renderer, the pacer, the frames' clock,
//! the frames in flight, the last report and the latency instruments, the screenshots recorded into the frames
//! (`Shots`) and `--stats`. A frame: acquire, plan (the pacer), record (a background screenshot's tile, the view,
//! the blit, egui, a window capture), submit, present; later its completion feeds the pacer and the statistics.
//! It reads the viewer through a `FrameView` and never reaches into it: what the viewer must act on comes back
//! as `Event`s, applied as commands are (`Viewer::happened`, view/mod.rs).
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;
use hrtao_core::buffer::Buffer;
use hrtao_core::gpu::GPixel;
use hrtao_core::{AoSettings, Camera, FrameDesc, FrameReport, Gpu, Output, Renderer, SceneGpu};
use hrtao_scene::Scene;

use super::prefs::Prefs;
use super::present::Presenter;
use super::walk::Walk;
use super::{frames, latency, pacer, shot, shots, stats, ui_probe};
use crate::cli::ViewArgs;

/// What a frame tells the viewer, applied as commands are.
pub(super) enum Event {
    /// A message for the user.
    Toast { text: String, error: bool },
    /// An unrecoverable error: shown, and the exit status of a scripted run.
    Fatal(String),
    /// A screenshot failed (fatal in a scripted run with a background screenshot).
    ShotFailed(String),
    /// A rendered frame completed: the scripted run counts it.
    Rendered,
    /// `--exit-after`: the run ends.
    Exit(ExitCode),
}

/// What egui's UI pass produced for the frame: its triangles, their scale, and the textures it changed.
pub(crate) struct UiFrame {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub pixels_per_point: f32,
    pub textures: egui::TexturesDelta,
}

/// What a frame reads of the viewer. The walk (`Walk`), whose probe rays travel with the frames, is lent
/// beside it.
pub(super) struct FrameView<'a> {
    pub scene: Option<(&'a Scene, &'a SceneGpu)>,
    pub cam: Camera,
    pub prefs: &'a Prefs,
    /// The user's render scale: the internal resolution of a still image, and the cap while moving.
    pub render_scale: f32,
    /// A scripted run is counting frames.
    pub scripted: bool,
}

impl FrameView<'_> {
    fn pacing(&self) -> pacer::Pacing<'_> {
        pacing(self.prefs, self.render_scale)
    }
}

/// A frame begun (`FrameLoop::begin`): the CPU split measured so far and its stopwatch.
pub(super) struct FrameStart {
    split: stats::CpuSplit,
    laps: stats::Laps,
}

/// The renderer's output to present: its buffer, width and height.
type ViewOutput = (vk::Buffer, u32, u32);

/// The presented image copied for `--screenshot-ui`, read after the frame.
pub(super) struct UiCapture {
    path: PathBuf,
    buf: Buffer,
    size: (u32, u32),
    bgra: bool,
}

pub(super) struct FrameLoop {
    gpu: Arc<Gpu>,
    egui_ctx: egui::Context,
    pub presenter: Presenter,
    pub renderer: Option<Renderer>,
    /// Frame pacing: what each frame renders (size, ray budget, slices) or holds, and when the loop wakes.
    pub pacer: pacer::Pacer,
    /// The stamps of the view's frames (statistics, and the pacer's clock).
    pub clock: stats::FrameStamps,
    /// Frames submitted and not completed.
    pub frames: frames::Frames,
    pub last_report: Option<FrameReport>,
    /// Presentation and input stamps, `--ao-out`, `--exit-after`.
    pub latency: latency::Latency,
    /// Screenshots asked for, rendering in the background or being written.
    pub shots: shots::Shots,
    /// `--stats`.
    pub stats: Option<stats::StatsLog>,
    /// `--screenshot-ui`: the window is captured with the next presented frame (the PNG's path).
    pub capture_ui: Option<PathBuf>,
    /// Where the 3D view lies in the window (x, y, width, height in pixels).
    pub view_rect: [i32; 4],
    /// Two UI passes agreed on the view's rectangle: the first scene can be framed.
    pub laid_out: bool,
    shut_down: bool,
}

impl FrameLoop {
    /// The loop of the viewer's window on `gpu`: the pacer starts from the device's class (the display's
    /// refresh follows: `Pacer::display_refresh`), the frames in flight from the preferences.
    pub fn new(
        gpu: &Arc<Gpu>,
        egui_ctx: &egui::Context,
        presenter: Presenter,
        args: &ViewArgs,
        prefs: &Prefs,
        render_scale: f32,
    ) -> FrameLoop {
        // The device's class and display: the frame-time target, the first budget, the moving frames' filter
        // and scale (0.35 on a software device, full on a GPU).
        let device = pacer::DeviceModel::new(gpu.info.is_software, None);
        let moving_scale = device.first_moving_scale();
        let frames_in_flight = super::prefs::frames_in_flight(
            std::env::var("HRTAO_FRAMES_IN_FLIGHT").ok().as_deref(),
            prefs.frames_in_flight,
            gpu.info.is_software,
        );
        log::info!("{frames_in_flight} frame(s) in flight");
        FrameLoop {
            gpu: gpu.clone(),
            egui_ctx: egui_ctx.clone(),
            presenter,
            renderer: None,
            pacer: pacer::Pacer::new(
                prefs.rays_per_frame,
                moving_scale.min(render_scale),
                device,
                Duration::ZERO,
            ),
            clock: stats::FrameStamps::new(),
            frames: frames::Frames::new(frames_in_flight),
            last_report: None,
            latency: latency::Latency::new(args.ao_out.clone(), args.exit_after),
            shots: shots::Shots::default(),
            stats: args.stats.clone().map(stats::StatsLog::new),
            capture_ui: None,
            view_rect: [0, 0, 1, 1],
            laid_out: false,
            shut_down: false,
        }
    }

    /// The swapchain blits the internal image (a render scale other than 1 is possible).
    pub fn can_scale(&self) -> bool {
        self.presenter.blit_ok || self.presenter.images.is_empty()
    }

    /// Internal resolution at `scale` (1 when the swapchain cannot blit: the output is copied 1:1).
    pub fn internal_size_at(&self, scale: f32) -> (u32, u32) {
        internal_size(self.view_rect, self.can_scale(), scale)
    }

    /// The 3D view's rectangle as a UI pass laid it out; whether the view is laid out now.
    pub fn set_view_rect(&mut self, rect: [i32; 4]) {
        // Laid out once two UI passes agree: the side panel grows to fit its content over the first passes,
        // and the first scene is framed and rendered at the size the view keeps.
        if !self.laid_out {
            self.laid_out = rect == self.view_rect;
            self.egui_ctx.request_repaint();
        }
        self.view_rect = rect;
    }

    /// A new scene is on the device: the renderer (made once) forgets the old one's AO, primary visibility is
    /// chosen for this scene, the passes warm up and the pacer starts over.
    pub fn scene_installed(
        &mut self,
        scene: (&Scene, &SceneGpu),
        cam: Camera,
        settings: &AoSettings,
        primary: crate::cli::PrimaryChoice,
        render_scale: f32,
        prefs: &Prefs,
    ) -> Result<()> {
        if self.renderer.is_none() {
            self.renderer = Some(Renderer::new(&self.gpu)?);
        }
        let (w, h) = self.internal_size_at(render_scale);
        let mut probe_rq_ms = f64::NAN;
        if let Some(r) = &mut self.renderer {
            let (scene, scene_gpu) = scene;
            // A different scene: the cached AO belongs to the old geometry.
            r.clear_cache()?;
            // Rasterised or ray-traced primary visibility, whichever is faster for this scene here.
            let probe = Camera {
                width: w,
                height: h,
                ..cam
            };
            let frame = FrameDesc::new(scene_gpu, scene.f(), probe, settings);
            probe_rq_ms = crate::setup::choose_primary(&self.gpu, r, primary, false, &frame)?.1;
            // The first frames after opening answer input as soon as any other (no pipeline compiles in them).
            let t = Instant::now();
            r.warm_up(&FrameDesc {
                jitter: true,
                ..FrameDesc::new(scene_gpu, scene.f(), probe, settings)
            })?;
            log::info!("passes warmed up in {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
        }
        self.pacer
            .scene_installed(probe_rq_ms, w as u64 * h as u64, pacing(prefs, render_scale));
        Ok(())
    }

    /// The surface under a point of the view (fractions of its width and height) in the last frame's G-buffer.
    pub fn pick(&self, at: [f32; 2]) -> Option<hrtao_core::Result<Option<GPixel>>> {
        match &self.renderer {
            Some(r) if (0.0..1.0).contains(&at[0]) && (0.0..1.0).contains(&at[1]) => {
                let (iw, ih) = r.size();
                let (x, y) = ((at[0] * iw as f32) as u32, (at[1] * ih as f32) as u32);
                self.gpu.wait_idle();
                Some(r.pick(x, y))
            }
            _ => None,
        }
    }

    /// A frame starts after its UI pass: None when there is nothing to draw (shut down; minimised: nothing to
    /// present, and the loop does not spin).
    pub fn begin(&mut self, size: winit::dpi::PhysicalSize<u32>) -> Option<FrameStart> {
        if self.shut_down {
            return None;
        }
        let mut split = stats::CpuSplit {
            ui: ms_between(self.clock.ui_started, self.clock.ui_done),
            ..Default::default()
        };
        let mut laps = stats::Laps::start_at(self.clock.ui_done);
        split.tessellate = laps.lap();
        if size.width == 0 || size.height == 0 {
            std::thread::sleep(Duration::from_millis(30));
            return None;
        }
        Some(FrameStart { split, laps })
    }

    /// The next frame must find no frame in flight: a screenshot is taken before it, or its results are read
    /// from buffers the frame after it overwrites.
    pub fn exclusive(&self) -> bool {
        self.shots.pending.is_some() || self.frames_to_keep() == 0
    }

    /// Frames in flight to keep after submitting one: the limit less one, none while a frame's results are
    /// read from buffers the next frame overwrites (a background screenshot's tiles, `--ao-out`) or the window
    /// is captured.
    fn frames_to_keep(&self) -> usize {
        let exclusive = self.shots.rendering() || self.latency.dumps_ao() || self.capture_ui.is_some();
        if exclusive {
            0
        } else {
            self.frames.limit - 1
        }
    }

    /// The frame's plan, recording, submission and presentation. Returns how many frames to keep in flight
    /// (the viewer completes the others), or None when no swapchain image could be drawn into.
    pub fn record(
        &mut self,
        size: winit::dpi::PhysicalSize<u32>,
        start: FrameStart,
        ui: &UiFrame,
        view: &FrameView,
        walk: &mut Walk,
    ) -> Result<Option<usize>> {
        let FrameStart { mut split, mut laps } = start;
        let Some(index) = self.next_image(size)? else {
            return Ok(None);
        };
        let plan = self.plan(view);
        split.acquire = laps.lap();
        let t0 = Instant::now();
        let cmd = self.presenter.begin_frame()?;
        // One frame of the background screenshot's current tile, before the view's own passes.
        let shot = self.shots.rendering();
        let shot_error = match view.scene {
            Some((scene, sg)) => self.shots.record(cmd, sg, scene.f()).err(),
            _ => None,
        };
        let (src, rendered) = self.record_view_frame(cmd, &plan, view, walk)?;
        // The input this frame answers: what came before it was recorded (not before it completed).
        let input = rendered.then(|| self.latency.take_input(plan.changed)).flatten();
        self.record_blit_and_ui(cmd, index, src, ui, (&mut split, &mut laps))?;
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
                ..view.cam
            },
        });
        Ok(Some(keep))
    }

    /// The pacer's plan of the frame (hold, settle or render; size, budget, slices), the 3D view's rectangle
    /// clamped to the swapchain first.
    fn plan(&mut self, view: &FrameView) -> pacer::FramePlan {
        self.view_rect = self.presenter.clamp(self.view_rect);
        let (rect, can_scale) = (self.view_rect, self.can_scale());
        let size_at = move |scale| internal_size(rect, can_scale, scale);
        self.pacer.plan(pacer::PlanInputs {
            now: self.clock.now(),
            camera: &view.cam,
            pacing: view.pacing(),
            output: self.renderer.as_ref().map(|r| r.size()),
            has_image: self.last_report.is_some(),
            scripted: view.scripted,
            shooting: self.shots.rendering(),
            size_at: &size_at,
        })
    }

    /// Records the blit of the view's output `src` into the 3D view's rectangle, and egui over it (their CPU
    /// times into `split`).
    fn record_blit_and_ui(
        &mut self,
        cmd: vk::CommandBuffer,
        index: u32,
        src: Option<ViewOutput>,
        ui: &UiFrame,
        (split, laps): (&mut stats::CpuSplit, &mut stats::Laps),
    ) -> Result<()> {
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

    /// Records the view's own frame as `plan` says: renders (a frame, or a round's visibility ahead of its
    /// slices), or presents the output again (held, settling, or already converged on this view). Returns the
    /// output to present (buffer, width, height) and whether a frame was rendered.
    fn record_view_frame(
        &mut self,
        cmd: vk::CommandBuffer,
        plan: &pacer::FramePlan,
        view: &FrameView,
        walk: &mut Walk,
    ) -> Result<(Option<ViewOutput>, bool)> {
        let (Some(r), Some((scene, sg))) = (&mut self.renderer, view.scene) else {
            return Ok((None, false));
        };
        let (iw, ih) = plan.size;
        let settings = plan.settings(&view.prefs.settings);
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
            probes: walk.rays(),
            ..FrameDesc::new(
                sg,
                scene.f(),
                Camera {
                    width: iw,
                    height: ih,
                    ..view.cam
                },
                &settings,
            )
        };
        // A converged image of this very view is already in the output: present it again (expose events, UI
        // repaints) instead of rendering. Scripted runs count rendered frames: they always render, except during
        // a background screenshot, where the view rests once converged as it would for a user.
        let scripted = view.scripted && !self.shots.in_background();
        let settling = self.pacer.settles(r.shows(&frame));
        let walking = walk.wants_frames();
        let render = !plan.hold && !settling && (scripted || walking || !r.shows_final(&frame));
        // Each round of a still image in slices starts with the view's visibility drawn in a frame of its own
        // (`Renderer::record_visibility`): input that comes meanwhile waits for the draw alone, and the view
        // shows the last image until the round's first slice.
        if render && !plan.moving && r.record_visibility(cmd, &frame)? {
            let (w, h) = r.size();
            return Ok((Some((r.output_buffer().raw, w, h)), false));
        }
        if render {
            r.record_frame(cmd, &frame)?;
            walk.submitted();
        }
        Ok((Some((r.output_buffer().raw, iw, ih)), render))
    }

    /// Scripted UI capture (`--screenshot-ui`): records the copy of the presented image (3D view and UI).
    fn record_ui_capture(&mut self, cmd: vk::CommandBuffer, index: u32) -> Result<Option<UiCapture>> {
        if !self.presenter.readback_ok {
            return Ok(None);
        }
        let Some(path) = self.capture_ui.take() else {
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

    /// Completes the oldest frame in flight: while more than `keep` are in flight (waiting for it), or with
    /// `keep` None once the device has finished it (without waiting). None when there is no such frame; else
    /// what the viewer must act on and whether reading its results succeeded.
    pub fn complete_next(
        &mut self,
        keep: Option<usize>,
        view: &FrameView,
        walk: &mut Walk,
    ) -> Option<(Vec<Event>, Result<()>)> {
        let popped = match keep {
            Some(keep) => self.frames.pop_over(keep),
            None => match self.frames.oldest_slot() {
                Some(slot) if self.presenter.done(slot) => {
                    Some(self.frames.pop_over(0).expect("a frame in flight"))
                }
                _ => None,
            },
        };
        let f = popped?;
        let mut events = Vec::new();
        let result = (|| {
            if !f.waited || keep.is_none() {
                self.presenter.wait(f.slot)?;
            }
            self.complete(f, view, walk, &mut events)
        })();
        Some((events, result))
    }

    /// After a frame completed: the background screenshot's tile, the window capture, the view's report.
    fn complete(
        &mut self,
        mut f: frames::Submitted,
        view: &FrameView,
        walk: &mut Walk,
        events: &mut Vec<Event>,
    ) -> Result<()> {
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
            self.shots.finish_frame(f.rendered).unwrap_or_else(|e| {
                events.push(Event::ShotFailed(e));
                0.0
            })
        } else {
            0.0
        };
        if let Some(e) = f.shot_error.take() {
            // Dropped only now: its commands were in the frame just completed.
            self.shots.cancel();
            events.push(Event::ShotFailed(format!("screenshot failed: {e:#}")));
        }
        self.finish_ui_capture(f.capture.take(), events)?;
        if f.rendered {
            self.frame_rendered(f, gpu_wall, shot_ms, view, walk)?;
            events.push(Event::Rendered);
        }
        Ok(())
    }

    /// After the frame: writes the UI capture's PNG (a surface that cannot be read back fails the run).
    fn finish_ui_capture(&mut self, capture: Option<UiCapture>, events: &mut Vec<Event>) -> Result<()> {
        let Some(UiCapture {
            path,
            buf,
            size: (w, h),
            bgra,
        }) = capture
        else {
            if self.capture_ui.is_some() && !self.presenter.readback_ok {
                events.push(Event::Fatal(
                    "this surface cannot be read back (no TRANSFER_SRC)".into(),
                ));
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
        events.push(match hrtao_core::imageio::write_png(&path, w, h, &px) {
            Ok(()) => Event::Toast {
                text: format!("window captured: {}", path.display()),
                error: false,
            },
            Err(e) => Event::Fatal(format!("cannot write {}: {e}", path.display())),
        });
        Ok(())
    }

    /// After a rendered frame: its report, what the pacer learns from it, the statistics and the AO dumps.
    fn frame_rendered(
        &mut self,
        f: frames::Submitted,
        gpu_wall: f64,
        shot_ms: f64,
        view: &FrameView,
        walk: &mut Walk,
    ) -> Result<()> {
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
        let full = self.internal_size_at(view.render_scale);
        let Some(r) = self.renderer.as_mut() else {
            return Ok(());
        };
        let report = r.finish_frame(gpu_wall)?;
        walk.hits(&report.probe_hits);
        let walk_stat = view.scene.and_then(|(s, _)| walk.stat(s.origin));
        let converged = pacer::image_converged(&report) && r.size() == full;
        let input_ms = input;
        let stats_index = self.stats.as_ref().map_or(0, |log| log.frames.len());
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
        self.pacer.observe(measured, view.pacing());
        if let Some(log) = &mut self.stats {
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

    /// Asks for another frame while something is still changing (the pacer decides; `busy`: the viewer waits
    /// for frames, as a screenshot or a capture does); otherwise the event loop waits for events.
    pub fn repaint(&mut self, busy: bool, viewing: bool, loading: bool, render_scale: f32) -> Option<Event> {
        let now = Instant::now();
        let repaint = self.pacer.repaint(pacer::RepaintInputs {
            now: self.clock.now(),
            busy: busy || self.shots.busy() || self.capture_ui.is_some(),
            viewing: self.renderer.is_some() && viewing,
            converged: self.converged_full(render_scale),
            loading,
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
            latency::ExitAfter::Now => Some(Event::Exit(ExitCode::SUCCESS)),
            latency::ExitAfter::WakeIn(d) => {
                self.egui_ctx.request_repaint_after(d);
                None
            }
            latency::ExitAfter::No => None,
        }
    }

    /// The last frame shows a converged image at the full internal size.
    pub fn converged_full(&self, render_scale: f32) -> bool {
        let full = self.internal_size_at(render_scale);
        match (&self.last_report, &self.renderer) {
            (Some(rep), Some(r)) => pacer::image_converged(rep) && r.size() == full,
            _ => false,
        }
    }

    /// Takes a screenshot of the 3D view without UI (at the view's size unless the request names one): renders
    /// it with the view's renderer (its world-space cache is warm and survives the resize) and writes the PNG.
    pub fn take_screenshot(&mut self, req: shots::ShotRequest, view: &FrameView) -> Result<PathBuf> {
        let size = req
            .size
            .unwrap_or((self.view_rect[2].max(1) as u32, self.view_rect[3].max(1) as u32));
        let (Some(r), Some((scene, sg))) = (&mut self.renderer, view.scene) else {
            bail!("no scene is open");
        };
        let cam = Camera {
            width: size.0,
            height: size.1,
            ..view.cam
        };
        // The view's frame at another size (RGBA output): the next view frame restarts its still image.
        let frame = FrameDesc {
            jitter: true,
            budget: Some(self.pacer.budget()),
            ..FrameDesc::new(sg, scene.f(), cam, &view.prefs.settings)
        };
        for _ in 0..req.frames.max(1) {
            r.render(&frame)?;
        }
        let rgba = r.read_rgba()?;
        shots::write_png(&req.path, size, &rgba)?;
        Ok(req.path)
    }

    /// Starts a background screenshot of the current view at `size` (one at a time): the message for the user,
    /// or the error.
    pub fn start_shot(
        &mut self,
        size: (u32, u32),
        path: PathBuf,
        view: &FrameView,
    ) -> Result<String, String> {
        // A slice costs about what a moving frame of the view costs (the frame-time target).
        let (w, h) = self.internal_size_at(self.pacer.moving_scale().min(view.render_scale));
        let (gpu, settings, cam) = (&self.gpu, &view.prefs.settings, &view.cam);
        let primary = view.scene.and(self.renderer.as_ref()).map(|r| r.primary());
        self.shots.start(size, || {
            // The folder first: a bad destination fails now, not after minutes of rendering.
            shots::create_folder(&path)?;
            let primary = primary.ok_or_else(|| anyhow!("no scene is open"))?;
            let pixels = w as u64 * h as u64;
            shot::BackgroundShot::new(gpu, settings, cam, size, path, pixels, primary)
        })
    }

    /// Polls the PNG writer of a background screenshot: the toast when it is written (recorded in `--stats`),
    /// or the failure.
    pub fn poll_saving(&mut self) -> Option<Event> {
        match self.shots.poll_saving()? {
            Ok(sm) => {
                let text = format!(
                    "screenshot saved: {} ({}×{}, {} tiles, {} frames, {:.1} s)",
                    sm.path.display(),
                    sm.size[0],
                    sm.size[1],
                    sm.tiles,
                    sm.frames,
                    sm.seconds
                );
                if let Some(log) = &mut self.stats {
                    log.screenshot = Some(sm);
                }
                Some(Event::Toast { text, error: false })
            }
            Err(e) => Some(Event::ShotFailed(e)),
        }
    }

    /// The scripted run's last line: its frames, the last frame's times and sizes.
    pub fn log_script_end(&self, n: u32) {
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
    }

    /// Writes `--stats` (once): None when there is nothing to write, else the error.
    pub fn write_stats(&mut self, spec: &str, target_ms: f64) -> Option<Result<(), String>> {
        let log = self.stats.take()?;
        Some(
            match log.write(
                &self.gpu.info,
                target_ms,
                spec,
                (self.frames.limit, self.frames.overlapped),
            ) {
                Ok(()) => {
                    log::info!(
                        "stats written to {} ({} frames, median moving {:.1} ms, still {:.1} ms)",
                        log.path().display(),
                        log.frames.len(),
                        log.median_wall_ms(true).unwrap_or(f64::NAN),
                        log.median_wall_ms(false).unwrap_or(f64::NAN)
                    );
                    Ok(())
                }
                Err(e) => Err(format!("{e:#}")),
            },
        )
    }

    /// The loop stops: frames are no longer drawn (the viewer completes those in flight first).
    pub fn shut_down(&mut self) -> bool {
        !std::mem::replace(&mut self.shut_down, true)
    }

    /// The device is idle: the screenshots and the renderer are released.
    pub fn release(&mut self) {
        self.shots = shots::Shots::default();
        self.renderer = None;
    }
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
pub(super) fn pacing(prefs: &Prefs, render_scale: f32) -> pacer::Pacing<'_> {
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
