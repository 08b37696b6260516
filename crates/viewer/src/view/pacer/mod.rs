//! Frame pacing: everything that decides a frame of the view before the renderer records it, and learns from
//! it after. `Pacer::plan` says whether the frame holds the image in the output (a press that has not moved
//! anything), settles (the camera stopped a moment ago: the moving image stays until the view counts as still)
//! or renders, at which internal size, with which ray budget and which lattice of slices; `Pacer::observe` takes
//! the rendered frame's measurements (the frame-time target adapts the moving scale and the rays per frame, the
//! slices learn their cost); `Pacer::repaint` says when the loop wakes next. No device, window or clock in here:
//! time comes in as a `Duration` on the caller's monotonic clock, so tests replay event sequences with a clock
//! they control.
//!
//! - `device`: what the device affords: its class and display, the per-class defaults (frame-time target,
//!   first budget, moving filter and scale) and the moving frame's cost learned from the frames.
//! - `budget`: rays per frame (the frame-time target's controller) and their conversion to rays per pixel.
//! - `motion`: moving or still, the hold of a press, the settling after a stop, the moving render scale.
//! - `slices`: still frames in slices of the frame-time target.
//!
//! The ray budget has one form here: rays per frame (the user's, or the frame-time target's), turned into the
//! renderer's `RayBudget` of this frame by `plan` and nowhere else.
mod budget;
mod device;
mod motion;
#[cfg(test)]
mod sim;
mod slices;

use std::time::Duration;

use hrtao_core::{AoSettings, Camera, Mode, RayBudget};

pub use budget::{DEFAULT_RAYS_PER_FRAME, MAX_RAYS_PER_FRAME, MIN_RAYS_PER_FRAME};
pub use device::DeviceModel;
pub use motion::image_converged;

/// What the user set that pacing follows (preferences and the render scale), read each frame.
#[derive(Clone, Copy)]
pub struct Pacing<'a> {
    /// The frame-time target is on: the ray budget and the moving scale adapt to `target_ms`, still images are
    /// refined in slices.
    pub auto_budget: bool,
    /// The user's frame-time target; None: the device's (`DeviceModel::target_ms`).
    pub target_ms: Option<f32>,
    /// The user's rays per frame, used as they are with the frame-time target off.
    pub rays_per_frame: u32,
    /// The user's render scale: a still image's, and the cap of the moving scale.
    pub render_scale: f32,
    pub settings: &'a AoSettings,
}

/// What a frame's plan depends on besides the pacer's own state.
pub struct PlanInputs<'a> {
    pub now: Duration,
    /// The navigation camera.
    pub camera: &'a Camera,
    pub pacing: Pacing<'a>,
    /// The renderer's output size, and whether it holds a rendered image.
    pub output: Option<(u32, u32)>,
    pub has_image: bool,
    /// A scripted run counts rendered frames: it never holds.
    pub scripted: bool,
    /// A background screenshot renders inside the view's frames: it never holds or settles.
    pub shooting: bool,
    /// The internal resolution at a render scale.
    pub size_at: &'a dyn Fn(f32) -> (u32, u32),
}

/// The plan of one frame of the view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FramePlan {
    /// A press on the view that has not moved anything: present the output again.
    pub hold: bool,
    /// The view stopped less than `motion::STILL_AFTER` ago and the output shows the moving image: keep it, if
    /// the renderer's output shows this view (`Pacer::settles`).
    pub settle: bool,
    /// The view counts as moving: reduced scale, no slices, the moving filter.
    pub moving: bool,
    /// The camera differs from the last rendered frame's.
    pub changed: bool,
    /// The internal resolution.
    pub size: (u32, u32),
    pub budget: RayBudget,
    /// Slices of a still image: `lattice`² (1: whole frames).
    pub lattice: u32,
    /// À-trous iterations of a moving frame (`DeviceModel::moving_filter_iterations`).
    pub moving_filter: u32,
}

impl FramePlan {
    /// The renderer's settings for this frame: the user's, with the moving filter while moving.
    pub fn settings(&self, settings: &AoSettings) -> AoSettings {
        motion::frame_settings(settings, self.moving, self.moving_filter)
    }
}

/// What a rendered frame measured.
pub struct FrameMeasurement {
    pub now: Duration,
    /// The camera the frame rendered.
    pub camera: Camera,
    /// The view's share of the frame's wall time (a background screenshot's tile left out), milliseconds.
    pub view_ms: f64,
    /// The part of `view_ms` spent waiting for a swapchain image (a display's vsync), not the frame's cost.
    pub wait_ms: f64,
    /// AO rays the frame traced (`FrameReport::rays`).
    pub rays: u64,
    /// The ray-tracing update's GPU time, where the device's timestamps measure it.
    pub ray_ms: Option<f64>,
    /// The frame's wait for the device, milliseconds: a scene install's first frame counts this alone.
    pub device_ms: f64,
    /// From the command buffer's start to the present, milliseconds (the panel's render time).
    pub render_ms: f64,
    /// The slices of the image the frame drew into (`FrameReport::slices`).
    pub slices: u32,
    /// A background screenshot shared the frame.
    pub shooting: bool,
}

/// When the event loop wakes next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wake {
    /// Another frame now.
    Now,
    /// A frame after this long (input wakes the loop sooner).
    After(Duration),
    /// Only on input.
    Rest,
}

/// The repaint decision.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Repaint {
    pub wake: Wake,
    /// Nothing left to refine, nothing pending: the viewer rests.
    pub resting: bool,
    /// It rests from this frame on.
    pub came_to_rest: bool,
}

/// What the repaint decision depends on besides the pacer's own state.
pub struct RepaintInputs {
    pub now: Duration,
    /// A scripted run, a screenshot or a capture waits for frames.
    pub busy: bool,
    /// A scene is open on a renderer.
    pub viewing: bool,
    /// The last frame shows a converged image at the full internal size.
    pub converged: bool,
    /// A scene is loading (the panel shows its progress).
    pub loading: bool,
}

/// The loading progress's repaint interval.
const LOADING_REPAINT: Duration = Duration::from_millis(100);

pub struct Pacer {
    /// What the device affords, learned from the moving frames.
    device: DeviceModel,
    motion: motion::Motion,
    slicing: slices::Slicing,
    /// Rays per frame: the user's, or with the frame-time target on, the target's (from the scene's first
    /// budget on).
    rays_per_frame: u32,
    /// This frame's plan.
    plan: Option<FramePlan>,
    /// The last moving frame's wall time and work (`slices::frame_work`): the first estimate of a still frame.
    last_moving: Option<(f64, u64)>,
    /// The last moving frame's pixels (the device model's floor was measured at them).
    moving_pixels: u64,
    /// The next rendered frame counted a scene's install: the frame-time target skips it.
    installed: bool,
    /// The camera of the last rendered frame.
    last_camera: Option<Camera>,
    /// This frame held, or settled.
    holding: bool,
    settling: bool,
    /// The output holds a moving frame's image (reduced scale, not refined).
    shows_moving: bool,
    resting: bool,
    /// The panel's averages: render milliseconds and milliseconds between rendered frames.
    frame_ms_avg: f64,
    interval_ms_avg: f64,
    last_frame_at: Option<Duration>,
}

impl Pacer {
    /// `rays_per_frame`: the user's; `moving_scale`: the first moving frames' render scale (the device's
    /// `first_moving_scale` under the user's cap).
    pub fn new(rays_per_frame: u32, moving_scale: f32, device: DeviceModel, now: Duration) -> Pacer {
        Pacer {
            device,
            motion: motion::Motion::new(moving_scale, now),
            slicing: slices::Slicing::default(),
            rays_per_frame,
            plan: None,
            last_moving: None,
            moving_pixels: 0,
            installed: false,
            last_camera: None,
            holding: false,
            settling: false,
            shows_moving: false,
            resting: false,
            frame_ms_avg: 0.0,
            interval_ms_avg: 0.0,
            last_frame_at: None,
        }
    }

    /// The pointer's drag over the view (or fly keys): held, and whether it moved something this frame.
    pub fn drag(&mut self, dragging: bool, moved: bool) {
        self.motion.drag(dragging, moved);
    }

    /// A scene was installed (its primary-visibility probe traced `probe_ms` at `pixels`): with the frame-time
    /// target on, its rays per frame start from its own first budget (the old scene's, cut by a heavy scene or
    /// grown by a light one, would not fit), and its first frame's wall time, which counts the install, is not
    /// taken for the target.
    /// `pixels` counts the view at the user's render scale; the first moving frames draw the moving scale's share.
    pub fn scene_installed(&mut self, probe_ms: f64, pixels: u64, p: Pacing) {
        if p.auto_budget {
            let share = (self.motion.moving_scale / p.render_scale.max(1e-3)).min(1.0) as f64;
            let moving_pixels = (pixels as f64 * share * share) as u64;
            let target = self.target_ms(p);
            self.rays_per_frame = self.device.first_rays(probe_ms, pixels, moving_pixels, target);
            log::info!(
                "first ray budget: {} rays per frame ({:?} device, {target:.1} ms target)",
                self.rays_per_frame,
                self.device.class
            );
        }
        self.installed = true;
    }

    /// Plans the frame.
    pub fn plan(&mut self, i: PlanInputs) -> FramePlan {
        let p = i.pacing;
        if !p.auto_budget {
            self.rays_per_frame = p.rays_per_frame;
        }
        let changed = !self.last_camera.is_some_and(|c| same_view(&c, i.camera));
        // A press on the view that has not moved anything: the image already in the output stays.
        let hold = i.output.is_some()
            && self.motion.holds()
            && !changed
            && i.has_image
            && !i.scripted
            && !i.shooting;
        self.holding = hold;
        if !hold {
            self.motion.frame(changed, i.now);
        }
        let moving = self.motion.moving(i.now);
        // The camera stopped (or a drag pauses) less than STILL_AFTER ago: a frame now would only refine the
        // moving image at its reduced scale, which the still image replaces a moment later, and input that
        // comes meanwhile would wait for it. The output keeps the moving image instead (unless the renderer's
        // output no longer shows this view), and the loop wakes at the still deadline or on input.
        let settle =
            !hold && self.motion.settling(changed, i.now) && self.shows_moving && !i.shooting && i.has_image;
        let (vw, vh) = (i.size_at)(1.0);
        self.motion.view(vw as f64 * vh as f64);
        let size = match i.output {
            Some(size) if hold || settle => size,
            _ => (i.size_at)(self.motion.scale(p.render_scale, i.now)),
        };
        let mut budget = self
            .plan
            .map_or(per_pixel(self.rays_per_frame, size), |old| old.budget);
        if !hold && !settle {
            budget = per_pixel(self.rays_per_frame, size);
        }
        // Still frames in slices of the frame-time target (with the target on): one budget per still image.
        let lattice = if hold {
            1
        } else if moving || !p.auto_budget {
            self.slicing.moving();
            1
        } else {
            let target = slices::slice_target_ms(self.target_ms(p) as f32);
            let s = p.settings;
            // Refining: the rays that complete the own rays with the anti-aliasing; else the ray budget.
            let rays_per_pixel = if s.accumulates() {
                slices::still_rays_per_pixel(s.still.still_samples, hrtao_core::renderer::AA_FRAMES)
            } else {
                budget.rays_per_pixel
            };
            let work = slices::frame_work(size.0, size.1, rays_per_pixel as f64);
            // A slice's cost by the device model: the moving frames' floor per pixel (all of it, conservatively)
            // and their rays' cost.
            let pixels = size.0 as f64 * size.1 as f64;
            let priced = match (self.device.cost(), self.moving_pixels) {
                ((Some(floor), Some(per_ray)), moving_pixels) if moving_pixels > 0 => {
                    let per_pixel = floor / moving_pixels as f64;
                    Some(move |l: u32, r: u32| pixels / (l * l) as f64 * (per_pixel + r as f64 * per_ray))
                }
                _ => None,
            };
            budget = RayBudget {
                rays_per_pixel: self.slicing.still_budget_priced(
                    rays_per_pixel,
                    work,
                    self.last_moving,
                    target,
                    priced,
                ),
                trace_fraction: 1.0,
            };
            self.slicing.lattice()
        };
        let plan = FramePlan {
            hold,
            settle,
            moving,
            changed,
            size,
            budget,
            lattice,
            moving_filter: self
                .device
                .moving_filter_iterations(p.settings.filter.filter_iterations),
        };
        self.plan = Some(plan);
        plan
    }

    /// Whether this frame settles: it may (`FramePlan::settle`) and the renderer's output shows this view.
    pub fn settles(&mut self, output_shows_the_view: bool) -> bool {
        self.settling = self.plan.is_some_and(|p| p.settle) && output_shows_the_view;
        self.settling
    }

    /// After a rendered frame: the averages, the frame-time target (after a moving frame: a still image keeps
    /// its budget and size so that it converges) and the slices' cost (after a still one).
    pub fn observe(&mut self, m: FrameMeasurement, p: Pacing) {
        let Some(plan) = self.plan else {
            return;
        };
        if let Some(last) = self.last_frame_at {
            let dt = m.now.saturating_sub(last).as_secs_f64() * 1e3;
            self.interval_ms_avg = ema(self.interval_ms_avg, dt);
            self.device.observe_present(dt, m.wait_ms);
        }
        self.last_frame_at = Some(m.now);
        self.frame_ms_avg = ema(self.frame_ms_avg, m.render_ms);
        self.shows_moving = plan.moving;
        self.last_camera = Some(m.camera);
        // The first frame after a scene's install counted the install in its wall time: the frame-time target
        // skips it, and the first still image's lattice takes its device time alone (a young map's first frame:
        // at least a moving frame's cost).
        let installed = std::mem::take(&mut self.installed);
        // The frame's cost: its view's wall time less the wait for the swapchain (a FIFO display's refresh).
        let frame_ms = (m.view_ms - m.wait_ms.max(0.0)).max(0.0);
        if plan.moving {
            let b = plan.budget;
            let rays = b.rays_per_pixel as f64 * b.trace_fraction.clamp(0.0, 1.0) as f64;
            let work = slices::frame_work(plan.size.0, plan.size.1, rays);
            if installed {
                self.last_moving = Some((m.device_ms, work));
            } else {
                let granted = rays * (plan.size.0 as f64 * plan.size.1 as f64);
                self.device.observe(
                    frame_ms,
                    m.rays,
                    m.ray_ms,
                    plan.size.0 as u64 * plan.size.1 as u64,
                );
                self.frame_time_target(frame_ms, granted, m.rays, p);
                self.last_moving = Some((frame_ms, work));
                self.moving_pixels = plan.size.0 as u64 * plan.size.1 as u64;
            }
        } else if !installed && p.auto_budget && !m.shooting {
            // (A background screenshot's tiles share the frame: its cost is not the view's.)
            let target = slices::slice_target_ms(self.target_ms(p) as f32);
            self.slicing.observe(frame_ms, m.slices, target);
        }
    }

    /// The frame-time target, after a moving frame of `frame_ms` that traced `traced` of its `granted` rays:
    /// the moving render scale and, when the mode traces rays, the rays per frame follow it, sized by what the
    /// device model says fits.
    fn frame_time_target(&mut self, frame_ms: f64, granted: f64, traced: u64, p: Pacing) {
        if !p.auto_budget {
            return;
        }
        let target = self.target_ms(p);
        self.motion.adapt(frame_ms, target, p.render_scale);
        let mode = p.settings.display.mode;
        if mode.uses_hash() || mode == Mode::Rtao {
            let fits = self.device.rays_that_fit(target);
            self.rays_per_frame =
                budget::next_rays_per_frame(self.rays_per_frame, granted, traced, frame_ms, target, fits);
        }
    }

    /// The display's refresh rate, in millihertz (the window's monitor; None: unknown): a GPU's target.
    pub fn display_refresh(&mut self, refresh_mhz: Option<u32>) {
        self.device.display_refresh(refresh_mhz);
    }

    /// The frame-time target in force: the user's, or the device's (`DeviceModel::target_ms`).
    pub fn target_ms(&self, p: Pacing) -> f64 {
        p.target_ms
            .filter(|t| t.is_finite())
            .map_or(self.device.target_ms(), |t| t as f64)
            .max(1.0)
    }

    /// Asks for another frame while something still changes: the camera moves or has just stopped, the image has
    /// not converged at full resolution, something else is busy; a settling view wakes at its still deadline, a
    /// load polls its progress. A held view waits for the press's motion or release (input wakes the loop).
    pub fn repaint(&mut self, i: RepaintInputs) -> Repaint {
        let converging = i.viewing && !i.converged;
        let busy = i.busy
            || (!self.holding && !self.settling && (converging || (i.viewing && self.motion.moving(i.now))));
        let wake = if busy {
            Wake::Now
        } else if self.settling {
            self.motion.still_in(i.now).map_or(Wake::Rest, Wake::After)
        } else if i.loading {
            Wake::After(LOADING_REPAINT)
        } else {
            Wake::Rest
        };
        let resting = !busy && !i.loading && !self.holding && !self.settling;
        let came_to_rest = resting && !self.resting;
        self.resting = resting;
        Repaint {
            wake,
            resting,
            came_to_rest,
        }
    }

    /// The last plan's ray budget (a screenshot at the window's size renders with it).
    pub fn budget(&self) -> RayBudget {
        self.plan.map_or(
            RayBudget {
                rays_per_pixel: 1,
                trace_fraction: 1.0,
            },
            |p| p.budget,
        )
    }

    /// The moving render scale (a background screenshot's slices cost about a moving frame).
    pub fn moving_scale(&self) -> f32 {
        self.motion.moving_scale
    }

    /// The rays per frame in use.
    pub fn rays_per_frame(&self) -> u32 {
        self.rays_per_frame
    }

    /// The panel's averages: render milliseconds and milliseconds between rendered frames.
    pub fn averages(&self) -> (f64, f64) {
        (self.frame_ms_avg, self.interval_ms_avg)
    }
}

/// The renderer's budget for `rays_per_frame` at `size`.
fn per_pixel(rays_per_frame: u32, (w, h): (u32, u32)) -> RayBudget {
    let (rays_per_pixel, trace_fraction) = budget::per_pixel_budget(rays_per_frame, w, h);
    RayBudget {
        rays_per_pixel,
        trace_fraction,
    }
}

/// Same camera pose and lens (the image size is not part of the view).
fn same_view(a: &Camera, b: &Camera) -> bool {
    a.eye == b.eye
        && a.target == b.target
        && a.up == b.up
        && a.fov_y_deg == b.fov_y_deg
        && a.projection == b.projection
        && a.ortho_height == b.ortho_height
}

fn ema(avg: f64, x: f64) -> f64 {
    if avg == 0.0 {
        x
    } else {
        avg * 0.9 + x * 0.1
    }
}

/// Event sequences replayed on a clock the tests control: a 1000×800 view, frames rendered with the wall times
/// the tests choose.
#[cfg(test)]
mod tests {
    use super::motion::MIN_MOVING_SCALE;
    use super::*;

    const VIEW: (f32, f32) = (1000.0, 800.0);

    fn size_at(scale: f32) -> (u32, u32) {
        ((VIEW.0 * scale).round() as u32, (VIEW.1 * scale).round() as u32)
    }

    fn camera(x: f32) -> Camera {
        Camera {
            eye: [x, 0.0, 5.0],
            ..Camera::default()
        }
    }

    fn pacing(s: &AoSettings, auto_budget: bool, rays_per_frame: u32) -> Pacing<'_> {
        Pacing {
            auto_budget,
            target_ms: Some(100.0),
            rays_per_frame,
            render_scale: 1.0,
            settings: s,
        }
    }

    /// The rays a plan grants: the renderer traces them all in these replays.
    fn granted_rays(plan: &FramePlan) -> u64 {
        let b = plan.budget;
        (b.rays_per_pixel as f64 * b.trace_fraction as f64 * plan.size.0 as f64 * plan.size.1 as f64) as u64
    }

    /// A viewer's side of the pacer: its clock, the renderer's output, what it renders.
    struct Replay {
        pacer: Pacer,
        now: Duration,
        output: Option<(u32, u32)>,
    }

    impl Replay {
        fn new(rays_per_frame: u32) -> Replay {
            Replay {
                pacer: Pacer::new(
                    rays_per_frame,
                    MIN_MOVING_SCALE,
                    DeviceModel::new(true, None),
                    Duration::ZERO,
                ),
                now: Duration::ZERO,
                output: None,
            }
        }

        fn wait(&mut self, ms: u64) {
            self.now += Duration::from_millis(ms);
        }

        fn plan(&mut self, cam: &Camera, p: Pacing) -> FramePlan {
            self.pacer.plan(PlanInputs {
                now: self.now,
                camera: cam,
                pacing: p,
                output: self.output,
                has_image: self.output.is_some(),
                scripted: false,
                shooting: false,
                size_at: &size_at,
            })
        }

        /// The renderer draws the plan in `ms`, all of it the device's.
        fn render(&mut self, plan: &FramePlan, cam: &Camera, ms: f64, p: Pacing) {
            self.render_split(plan, cam, ms, ms, p);
        }

        /// The renderer draws the plan in `wall_ms`, `device_ms` of it the device's.
        fn render_split(&mut self, plan: &FramePlan, cam: &Camera, wall_ms: f64, device_ms: f64, p: Pacing) {
            self.wait(wall_ms as u64);
            self.output = Some(plan.size);
            self.pacer.observe(
                FrameMeasurement {
                    now: self.now,
                    camera: *cam,
                    view_ms: wall_ms,
                    wait_ms: 0.0,
                    rays: granted_rays(plan),
                    ray_ms: None,
                    device_ms,
                    render_ms: wall_ms,
                    slices: plan.lattice * plan.lattice,
                    shooting: false,
                },
                p,
            );
        }

        fn repaint(&mut self, converged: bool) -> Repaint {
            self.pacer.repaint(RepaintInputs {
                now: self.now,
                busy: false,
                viewing: true,
                converged,
                loading: false,
            })
        }
    }

    /// Drag → release → settle → still: a press that has not moved holds the image; the drag renders moving
    /// frames at the reduced scale; after the release the moving image stays (no frame) until the still deadline,
    /// which the loop wakes for; then still frames at full size in slices with whole rays per pixel, and the loop
    /// rests once the image has converged. Fails with the hold's `!changed` left out (a press with a camera moved
    /// by a key held the old image) and with settling left out (the release rendered a moving frame at once).
    #[test]
    fn drag_release_settle_then_still_slices_until_rest() {
        let s = AoSettings::default();
        let p = pacing(&s, true, 300_000);
        let mut r = Replay::new(300_000);
        let (a, b, c) = (camera(0.0), camera(1.0), camera(2.0));
        let first = r.plan(&a, p);
        assert!(first.moving && first.changed && !first.hold);
        assert_eq!(
            first.size,
            size_at(MIN_MOVING_SCALE),
            "the first frames at the moving scale"
        );
        r.render(&first, &a, 50.0, p);
        // A press that has not moved anything: the image in the output stays.
        r.wait(20);
        r.pacer.drag(true, false);
        let press = r.plan(&a, p);
        assert!(press.hold && press.size == first.size, "{press:?}");
        assert_eq!(r.repaint(false).wake, Wake::Rest, "a held view waits for input");
        // The press with a camera moved meanwhile (a fly key): not a hold.
        let keyed = r.plan(&c, p);
        assert!(!keyed.hold && keyed.changed, "{keyed:?}");
        r.render(&keyed, &c, 50.0, p);
        // The drag moves the camera: moving frames at the reduced scale, the budget per pixel of its size.
        r.pacer.drag(true, true);
        let drag = r.plan(&b, p);
        assert!(drag.moving && drag.changed && !drag.hold);
        assert!(drag.size.0 < 1000 && drag.lattice == 1);
        r.render(&drag, &b, 50.0, p);
        // Released 20 ms later: the moving image stays until the still deadline, and the loop wakes for it.
        r.wait(20);
        r.pacer.drag(false, false);
        let release = r.plan(&b, p);
        assert!(release.settle && !release.changed, "{release:?}");
        assert_eq!(release.size, drag.size, "the output's size: nothing is rendered");
        assert!(r.pacer.settles(true));
        match r.repaint(false).wake {
            Wake::After(d) => assert!(d <= motion::STILL_AFTER, "{d:?}"),
            w => panic!("a settling view wakes at its still deadline, not {w:?}"),
        }
        // Past the still deadline: still frames at full size, in slices, whole rays per pixel.
        r.wait(motion::STILL_AFTER.as_millis() as u64);
        let still = r.plan(&b, p);
        assert!(!still.moving && !still.settle && !still.hold);
        assert_eq!(still.size, size_at(1.0));
        assert!(
            still.lattice > 1,
            "a still image 5× the moving frame's work is sliced: {still:?}"
        );
        assert_eq!(still.budget.trace_fraction, 1.0);
        assert!(!r.pacer.settles(true), "a still frame never settles");
        r.render(&still, &b, 40.0, p);
        assert_eq!(r.repaint(false).wake, Wake::Now, "refining");
        let rest = r.repaint(true);
        assert!(rest.resting && rest.came_to_rest && rest.wake == Wake::Rest);
        assert!(!r.repaint(true).came_to_rest, "once");
    }

    /// A scene change: the budget that a heavy scene cut to 1,000 rays per frame (and the preferences saved) does
    /// not carry over; the new scene starts from its own (the rays its primary probe traced in a quarter of the
    /// target), and its first frame, whose wall time counts the install, does not move the target's budget.
    /// Fails with `scene_installed` keeping the old budget (the first frame traces 1,000 rays: a grainy image)
    /// and with the install frame taken for the target (the budget falls to a quarter).
    #[test]
    fn a_scene_starts_from_its_own_budget_not_the_last_scenes() {
        let s = AoSettings::default();
        let p = pacing(&s, true, 1_000);
        let mut r = Replay::new(1_000);
        r.pacer.scene_installed(459.0, 960 * 800, p);
        let own = r.pacer.rays_per_frame();
        assert!((41_000..43_000).contains(&own), "{own}");
        let a = camera(0.0);
        let first = r.plan(&a, p);
        let rays = first.budget.rays_per_pixel as f64
            * first.budget.trace_fraction as f64
            * (first.size.0 * first.size.1) as f64;
        assert!(
            rays > 30_000.0,
            "the first frame traces the scene's own budget: {first:?}"
        );
        // The install frame took 5 s (pipelines, BLAS): not the target's business.
        r.render(&first, &a, 5_000.0, p);
        assert_eq!(
            r.pacer.rays_per_frame(),
            own,
            "the install frame moved the budget"
        );
        // A moving frame over the target cuts it.
        let b = camera(1.0);
        let next = r.plan(&b, p);
        r.render(&next, &b, 200.0, p);
        assert!(r.pacer.rays_per_frame() < own);
        // A second scene starts from its own again, whatever the first one's budget became.
        r.pacer.scene_installed(459.0, 960 * 800, p);
        assert_eq!(r.pacer.rays_per_frame(), own);
    }

    /// A setting change: turning the frame-time target off takes the user's rays per frame and whole frames from
    /// the next frame on, and moving frames no longer move the budget or the scale; a mode that traces no rays
    /// leaves the budget alone. Fails with slices kept while the target is off (`moving || !auto_budget` without
    /// the second term) and with the target adapting while off.
    #[test]
    fn turning_the_frame_time_target_off_uses_the_users_budget_in_whole_frames() {
        let s = AoSettings::default();
        let on = pacing(&s, true, 300_000);
        let mut r = Replay::new(300_000);
        let (a, b) = (camera(0.0), camera(1.0));
        let moving = r.plan(&a, on);
        r.render(&moving, &a, 90.0, on);
        r.wait(500);
        let still = r.plan(&a, on);
        assert!(still.lattice > 1, "{still:?}");
        // The user turns the target off and sets 2 M rays per frame.
        let off = pacing(&s, false, 2_000_000);
        let next = r.plan(&a, off);
        assert_eq!(next.lattice, 1, "whole frames with the target off: {next:?}");
        assert_eq!(r.pacer.rays_per_frame(), 2_000_000);
        assert_eq!(
            next.budget.rays_per_pixel, 3,
            "2 M rays over 1000×800 pixels: {next:?}"
        );
        // A slow moving frame does not cut the user's budget or scale.
        let scale = r.pacer.moving_scale();
        let m = r.plan(&b, off);
        r.render(&m, &b, 900.0, off);
        assert_eq!(r.pacer.rays_per_frame(), 2_000_000);
        assert_eq!(r.pacer.moving_scale(), scale);
        // Back on, in a mode that traces no rays: the scale follows the target, the budget stays.
        let mut no_ao = s.clone();
        no_ao.display.mode = Mode::NoAo;
        let on_no_ao = pacing(&no_ao, true, 2_000_000);
        let c = camera(2.0);
        let m = r.plan(&c, on_no_ao);
        r.render(&m, &c, 900.0, on_no_ao);
        assert_eq!(r.pacer.rays_per_frame(), 2_000_000);
        assert!(r.pacer.moving_scale() < scale || scale == MIN_MOVING_SCALE);
    }

    /// On a GPU at 60 Hz with a FIFO display, a moving frame that cost 3 ms waits ~13.7 ms for the refresh: the
    /// wait is not its cost, so the budget whose rays it used grows (to what the model says fits), and the
    /// device's target is the refresh, not 100 ms. Fails with the wait counted (`frame_ms = m.view_ms`: every
    /// frame looks as long as the target and the budget never grows).
    #[test]
    fn a_gpu_frame_waiting_for_the_display_is_not_its_cost() {
        let s = AoSettings::default();
        let p = Pacing {
            target_ms: None,
            ..pacing(&s, true, 300_000)
        };
        let mut pacer = Pacer::new(
            300_000,
            1.0,
            DeviceModel::new(false, Some(60_000)),
            Duration::ZERO,
        );
        assert!((pacer.target_ms(p) - 1000.0 / 60.0).abs() < 1e-9);
        let mut now = Duration::ZERO;
        for i in 0..2 {
            let cam = camera(i as f32);
            let plan = pacer.plan(PlanInputs {
                now,
                camera: &cam,
                pacing: p,
                output: Some(size_at(1.0)),
                has_image: true,
                scripted: false,
                shooting: false,
                size_at: &size_at,
            });
            now += Duration::from_micros(16_667);
            pacer.observe(
                FrameMeasurement {
                    now,
                    camera: cam,
                    view_ms: 16.67,
                    wait_ms: 13.67,
                    rays: granted_rays(&plan),
                    ray_ms: Some(1.0),
                    device_ms: 3.0,
                    render_ms: 3.0,
                    slices: 1,
                    shooting: false,
                },
                p,
            );
        }
        assert!(pacer.rays_per_frame() > 300_000, "{}", pacer.rays_per_frame());
    }

    /// The first still image after a scene's install, with no moving frame after the install frame, is sliced
    /// from the install frame's device time (before, whole frames of seconds came first whenever the install
    /// frame outlasted the moving window). Fails when the install frame leaves no estimate (`last_moving` not
    /// set when `installed`).
    #[test]
    fn the_first_still_image_after_an_install_is_sliced_by_the_install_frames_device_time() {
        let s = AoSettings::default();
        let p = pacing(&s, true, 300_000);
        let mut r = Replay::new(300_000);
        r.pacer.scene_installed(459.0, 960 * 800, p);
        let a = camera(0.0);
        let first = r.plan(&a, p);
        assert!(first.moving);
        // The install frame: 3 s of wall time, 400 ms of it the device's (at the moving scale).
        r.render_split(&first, &a, 3_000.0, 400.0, p);
        // Past the moving window with no other frame: the still image at full size is sliced.
        let still = r.plan(&a, p);
        assert!(!still.moving && still.size == size_at(1.0));
        assert!(still.lattice > 1, "{still:?}");
    }
}
