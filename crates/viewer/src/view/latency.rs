//! Instruments of scripted runs that measure what a user sees: when each frame was presented and which input it
//! answers (on the system's monotonic clock, which an external benchmark stamps its own input with), the view's
//! AO per frame (`--ao-out`) with its roughness, and `--exit-after` (end a user-like run once it rests, a while
//! after the last input).
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use hrtao_core::Renderer;
use winit::event::{DeviceEvent, WindowEvent};

/// Milliseconds on CLOCK_MONOTONIC: the clock of Python's `time.monotonic()` on Linux, and of `Instant`.
pub fn monotonic_ms() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec; CLOCK_MONOTONIC exists on every Linux.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) } == 0;
    if !ok {
        return f64::NAN;
    }
    ts.tv_sec as f64 * 1e3 + ts.tv_nsec as f64 * 1e-6
}

/// Whether a window event is user input that can move the camera (pointer, wheel, keys). egui-ash keeps the
/// events egui consumes (the pointer over the 3D view) from the app: those are seen in egui's input instead
/// (`ui_pass`).
pub fn is_input(event: &WindowEvent) -> bool {
    matches!(
        event,
        WindowEvent::MouseInput { .. }
            | WindowEvent::CursorMoved { .. }
            | WindowEvent::MouseWheel { .. }
            | WindowEvent::KeyboardInput { .. }
            | WindowEvent::Touch(_)
    )
}

/// Whether a device event (raw input, delivered while the window has the focus) is user input that can move the
/// camera: pointer motion and buttons, the wheel, keys.
pub fn is_device_input(event: &DeviceEvent) -> bool {
    matches!(
        event,
        DeviceEvent::MouseMotion { .. }
            | DeviceEvent::MouseWheel { .. }
            | DeviceEvent::Button { .. }
            | DeviceEvent::Key(_)
    )
}

/// Whether egui's input of this UI pass holds user input that can move the camera.
pub fn egui_has_input(ctx: &egui::Context) -> bool {
    ctx.input(|i| {
        i.raw.events.iter().any(|e| {
            matches!(
                e,
                egui::Event::PointerMoved(_)
                    | egui::Event::PointerButton { .. }
                    | egui::Event::MouseWheel { .. }
                    | egui::Event::Zoom(_)
                    | egui::Event::Key { .. }
                    | egui::Event::Touch { .. }
            )
        })
    })
}

/// The scripted instruments of one viewer.
pub struct Latency {
    /// The monotonic times of the earliest and the latest input event received since the last rendered frame.
    pending_input_ms: Option<(f64, f64)>,
    /// The start of the first event-loop iteration since the last UI pass: events arrive right after it.
    wake_ms: Option<f64>,
    /// `--ao-out DIR` and the number of the next frame written there.
    ao_out: Option<PathBuf>,
    ao_frames: u32,
    /// `--ao-out`: the still frames of the current still image written so far (their index in the stats and
    /// their PFM), measured once the image converges.
    still_frames: Vec<(usize, PathBuf)>,
    /// `--exit-after SECONDS`: the run ends at the first rest this long after the last input (or the start).
    exit_after: Option<Duration>,
    last_input: Instant,
}

/// What `--exit-after` asks for after a frame.
#[derive(Debug, PartialEq)]
pub enum ExitAfter {
    /// Not asked for, or the viewer is busy: nothing to do.
    No,
    /// At rest and the time has come: exit now.
    Now,
    /// At rest before the time: wake up then (the event loop would otherwise wait for input).
    WakeIn(Duration),
}

impl Latency {
    pub fn new(ao_out: Option<PathBuf>, exit_after: Option<f64>) -> Latency {
        Latency {
            pending_input_ms: None,
            wake_ms: None,
            ao_out,
            ao_frames: 0,
            still_frames: Vec::new(),
            exit_after: exit_after.map(|s| Duration::from_secs_f64(s.clamp(0.0, 1e6))),
            last_input: Instant::now(),
        }
    }

    /// A window event arrived: input is stamped (the earliest since the last rendered frame is kept).
    pub fn event(&mut self, event: &WindowEvent) {
        if is_input(event) {
            self.input();
        }
    }

    /// A device event arrived: input is stamped as by `event`.
    pub fn device_event(&mut self, event: &DeviceEvent) {
        if is_device_input(event) {
            self.input();
        }
    }

    fn input(&mut self) {
        self.input_at(monotonic_ms());
    }

    fn input_at(&mut self, ms: f64) {
        self.last_input = Instant::now();
        self.pending_input_ms = Some(
            self.pending_input_ms
                .map_or((ms, ms), |(first, last)| (first.min(ms), last.max(ms))),
        );
    }

    /// An event-loop iteration starts (winit's NewEvents): the events it delivers come right after.
    pub fn wake(&mut self) {
        self.wake_ms.get_or_insert_with(monotonic_ms);
    }

    /// A UI pass starts with egui's input (`had_input`: `egui_has_input`). Its input events were received at
    /// the start of the first event-loop iteration since the previous UI pass: exactly while the viewer renders
    /// continuously (one iteration per frame; events that come during a frame wait for the next iteration), and
    /// possibly earlier than the event when the viewer rested and a timer woke it first. A pass without input
    /// ends what was pending: input that moved nothing by then (a drag's release) is not credited to a later move.
    /// Frames' AO is written (`--ao-out`): read from the renderer's buffers when the frame completes.
    pub fn dumps_ao(&self) -> bool {
        self.ao_out.is_some()
    }

    pub fn ui_pass(&mut self, had_input: bool) {
        let wake = self.wake_ms.take();
        if had_input {
            self.input_at(wake.unwrap_or_else(monotonic_ms));
        } else {
            self.pending_input_ms = None;
        }
    }

    /// A frame was rendered: the stamps of the earliest and the latest input it answers when its camera changed
    /// (`moved`). Input that has not moved the camera yet stays pending while input goes on: a drag's press (egui
    /// moves nothing before the pointer moves with the button down) is credited to the first frame the drag
    /// moves, and that frame's latest input is the motion that moved it.
    pub fn take_input(&mut self, moved: bool) -> Option<(f64, f64)> {
        if moved {
            self.pending_input_ms.take()
        } else {
            None
        }
    }

    /// `--ao-out`: writes the renderer's AO of the frame just completed (number `index` in the stats) as
    /// `DIR/frame_NNNN.pfm` and returns the roughness of the frames it can measure now (their stats index and
    /// `hrtao_core::metrics::roughness`: occluded flat pixels by the frame's own AO < 0.95; None when no pixel
    /// qualifies). A frame in slices holds only its slice's samples in the G-buffer, so a still image's frames
    /// are measured at the end of the round that completes them (`round_end`: the last slice, or any whole
    /// frame), all on that round's G-buffer, which then holds the view's samples at every pixel. A moving frame
    /// is measured on its own; a still image abandoned mid-round leaves the frames of that round unmeasured.
    /// Nothing without `--ao-out`.
    pub fn dump_ao(
        &mut self,
        renderer: &Renderer,
        index: usize,
        still: bool,
        round_end: bool,
    ) -> Result<Vec<(usize, Option<f32>)>> {
        let Some(dir) = &self.ao_out else {
            return Ok(Vec::new());
        };
        let (w, h) = renderer.size();
        let ao = renderer.read_ao()?;
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let path = dir.join(format!("frame_{:04}.pfm", self.ao_frames));
        hrtao_core::imageio::write_pfm(&path, w, h, &ao)
            .with_context(|| format!("cannot write {}", path.display()))?;
        self.ao_frames += 1;
        let rough = |ao: &[f32], gbuffer: &[hrtao_core::gpu::GPixel]| {
            hrtao_core::metrics::roughness(ao, gbuffer, w as usize, h as usize)
        };
        if !still {
            self.still_frames.clear();
            return Ok(vec![(index, rough(&ao, &renderer.read_gbuffer()?))]);
        }
        self.still_frames.push((index, path));
        if !round_end {
            return Ok(Vec::new());
        }
        let gbuffer = renderer.read_gbuffer()?;
        let mut out = Vec::new();
        for (i, path) in self.still_frames.drain(..) {
            let (fw, fh, ao) = hrtao_core::imageio::read_pfm(&path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            // A frame of another render size (the still image restarted at full size) is not comparable.
            out.push((
                i,
                if (fw, fh) == (w, h) {
                    rough(&ao, &gbuffer)
                } else {
                    None
                },
            ));
        }
        Ok(out)
    }

    /// `--exit-after`: whether the run ends now (`resting`: the image converged and the viewer waits for input).
    pub fn exit_after(&self, resting: bool, now: Instant) -> ExitAfter {
        match self.exit_after {
            Some(d) if resting => match (self.last_input + d).checked_duration_since(now) {
                Some(d) if !d.is_zero() => ExitAfter::WakeIn(d),
                _ => ExitAfter::Now,
            },
            _ => ExitAfter::No,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotonic_ms_is_the_clock_of_instant() {
        // Instant is CLOCK_MONOTONIC on Linux: two readings bracket one of ours.
        let a = monotonic_ms();
        std::thread::sleep(Duration::from_millis(5));
        let b = monotonic_ms();
        assert!(b - a >= 5.0 && b - a < 1000.0, "{a} {b}");
        // /proc/uptime counts from boot as CLOCK_BOOTTIME; without a suspend it equals CLOCK_MONOTONIC (±1 s).
        let up: f64 = std::fs::read_to_string("/proc/uptime")
            .ok()
            .and_then(|s| s.split_whitespace().next()?.parse().ok())
            .unwrap_or(b / 1e3);
        assert!(b / 1e3 <= up + 1.0, "monotonic {b} ms, uptime {up} s");
    }

    #[test]
    fn input_is_credited_to_the_frame_that_moves() {
        let mut l = Latency::new(None, None);
        assert_eq!(l.take_input(true), None);
        let before = monotonic_ms();
        let focus = WindowEvent::Focused(true);
        l.event(&focus);
        assert_eq!(l.take_input(true), None, "focus is not input");
        let press = WindowEvent::MouseWheel {
            device_id: winit::event::DeviceId::dummy(),
            delta: winit::event::MouseScrollDelta::LineDelta(0.0, 1.0),
            phase: winit::event::TouchPhase::Moved,
        };
        l.event(&press);
        let (t, _) = l.pending_input_ms.unwrap();
        std::thread::sleep(Duration::from_millis(2));
        l.event(&press);
        let (first, last) = l.pending_input_ms.unwrap();
        assert_eq!(first, t, "the earliest event is kept");
        assert!(last >= t + 2.0, "and the latest: {t} {last}");
        assert!(t >= before);
        // A frame that did not move keeps them for the first frame that moves; then the next input is stamped
        // afresh.
        assert_eq!(l.take_input(false), None);
        assert_eq!(l.take_input(true), Some((t, last)));
        assert_eq!(l.take_input(true), None);
        l.event(&press);
        let (t2, t2_last) = l.take_input(true).unwrap();
        assert!(t2 >= last && t2_last == t2);
    }

    #[test]
    fn egui_input_is_stamped_at_the_iteration_that_delivered_it() {
        let mut l = Latency::new(None, None);
        l.wake();
        let w = l.wake_ms.unwrap();
        std::thread::sleep(Duration::from_millis(3));
        l.wake();
        assert_eq!(l.wake_ms, Some(w), "the first iteration since the last UI pass");
        l.ui_pass(false);
        assert_eq!((l.wake_ms, l.pending_input_ms), (None, None));
        l.wake();
        let w2 = l.wake_ms.unwrap();
        assert!(w2 >= w + 3.0);
        l.ui_pass(true);
        assert_eq!(l.take_input(true), Some((w2, w2)));
        // Input that moved nothing (a release) is dropped by the next pass without input.
        l.ui_pass(true);
        assert_eq!(l.take_input(false), None);
        l.ui_pass(false);
        assert_eq!(l.take_input(true), None);
        let ctx = egui::Context::default();
        let mut raw = egui::RawInput::default();
        raw.events.push(egui::Event::PointerMoved(egui::pos2(3.0, 4.0)));
        // No painting here: the passes' texture changes are dropped on purpose.
        ctx.run_ui(raw, |ui| assert!(egui_has_input(ui.ctx())))
            .drop_without_applying_deltas();
        ctx.run_ui(egui::RawInput::default(), |ui| assert!(!egui_has_input(ui.ctx())))
            .drop_without_applying_deltas();
    }

    #[test]
    fn exit_after_waits_for_rest_and_time() {
        let l = Latency::new(None, Some(10.0));
        let now = Instant::now();
        assert_eq!(l.exit_after(false, now), ExitAfter::No);
        assert!(matches!(l.exit_after(true, now), ExitAfter::WakeIn(d) if d > Duration::from_secs(9)));
        assert_eq!(l.exit_after(true, now + Duration::from_secs(11)), ExitAfter::Now);
        assert_eq!(Latency::new(None, None).exit_after(true, now), ExitAfter::No);
        // Input restarts the wait.
        let mut l = Latency::new(None, Some(10.0));
        std::thread::sleep(Duration::from_millis(20));
        let later = Instant::now();
        l.event(&WindowEvent::CursorMoved {
            device_id: winit::event::DeviceId::dummy(),
            position: (1.0, 2.0).into(),
        });
        assert!(matches!(
            l.exit_after(true, later + Duration::from_millis(9995)),
            ExitAfter::WakeIn(_)
        ));
    }
}
