//! Simulated devices driving the pacer through a scripted navigation, on a clock the tests control: a frame
//! costs the device's fixed cost, its pixels' passes, its filter iterations and the AO rays it traces at the
//! rate of the view's kind (rays into cached geometry, or into unseen geometry, where every pixel's cells are
//! young and the rays reach farther); a display's vsync makes the loop wait for the next refresh (FIFO). The
//! script at 1920×1080: the scene opens, an orbit over cached geometry, a pan into unseen geometry, a stop,
//! then still frames until the image converges.
use std::time::Duration;

use hrtao_core::renderer::AA_FRAMES;
use hrtao_core::{AoSettings, Camera};

use super::*;

const VIEW: (u32, u32) = (1920, 1080);

/// A device as the pacer sees it.
struct SimDevice {
    name: &'static str,
    software: bool,
    refresh_mhz: Option<u32>,
    fixed_ms: f64,
    /// Per pixel of a frame, its AO rays and filter left out (primary visibility, cell finder, per-pixel AO,
    /// composite), nanoseconds.
    pixel_ns: f64,
    /// Per pixel and à-trous iteration, nanoseconds.
    filter_ns: f64,
    /// Ray-query primary rays (the scene's probe), per millisecond.
    primary_rays_per_ms: f64,
    /// AO rays into cached geometry, and into unseen geometry, per millisecond.
    seen_rays_per_ms: f64,
    unseen_rays_per_ms: f64,
}

/// lavapipe: 0.25 Mrays/s into unseen geometry (san_francisco's measured rate), twice that into cached
/// geometry; 30 ms a frame of submission and UI; its raster passes at 4 Mpixels/s; the probe's ray-query primary
/// rays at 1.7 Mrays/s (the bundled scene's 459 ms at 960×800); Xvfb reports no refresh; no pass times (its
/// raster primary's timestamps do not measure, `Renderer::timestamps_measure`).
const LAVAPIPE: SimDevice = SimDevice {
    name: "lavapipe",
    software: true,
    refresh_mhz: None,
    fixed_ms: 30.0,
    pixel_ns: 250.0,
    filter_ns: 60.0,
    primary_rays_per_ms: 1_700.0,
    seen_rays_per_ms: 500.0,
    unseen_rays_per_ms: 250.0,
};

/// An RTX-class GPU at 144 Hz: 5 Grays/s into cached geometry, half that into unseen (the paper's Quadro RTX
/// 8000 traced 0.8-3.4 Grays/s on first frames, Table 2); 0.5 ms fixed; its passes at 1 ns a pixel (Table 2:
/// cell finder and per-pixel AO ~1.8 ms at 1080p), the filter at 0.07 ns a pixel and iteration.
const RTX: SimDevice = SimDevice {
    name: "RTX-class",
    software: false,
    refresh_mhz: Some(144_000),
    fixed_ms: 0.5,
    pixel_ns: 1.0,
    filter_ns: 0.07,
    primary_rays_per_ms: 10e6,
    seen_rays_per_ms: 5e6,
    unseen_rays_per_ms: 2.5e6,
};

/// A mid-range GPU at 60 Hz: 1 Grays/s into cached geometry, 2 ms fixed, passes 2.5× the RTX's.
const MID_RANGE: SimDevice = SimDevice {
    name: "mid-range",
    software: false,
    refresh_mhz: Some(60_000),
    fixed_ms: 2.0,
    pixel_ns: 2.5,
    filter_ns: 0.2,
    primary_rays_per_ms: 2e6,
    seen_rays_per_ms: 1e6,
    unseen_rays_per_ms: 0.5e6,
};

/// What a view shows the rays.
#[derive(Clone, Copy, PartialEq, Debug)]
enum View {
    /// Cached geometry: a twentieth of the pixels' cells still take rays (silhouettes, LOD changes).
    Seen,
    /// Unseen geometry: every pixel's cells are young.
    Unseen,
}

impl View {
    fn young_share(self) -> f64 {
        match self {
            View::Seen => 0.05,
            View::Unseen => 1.0,
        }
    }
}

/// One rendered frame of the run.
#[derive(Clone, Debug)]
struct Frame {
    view: View,
    moving: bool,
    /// The frame's cost on the device (the wait for the display left out), milliseconds.
    cost_ms: f64,
    rays: u64,
    pixels: u64,
    size: (u32, u32),
}

impl Frame {
    fn rays_per_pixel(&self) -> f64 {
        self.rays as f64 / self.pixels as f64
    }
}

/// The device's cost of a frame of `plan` at `view`, the rays it traced, and its pass time of the rays.
fn cost(d: &SimDevice, plan: &FramePlan, view: View, settings: &AoSettings) -> (f64, u64, f64) {
    let slice_pixels = plan.size.0 as f64 * plan.size.1 as f64 / (plan.lattice * plan.lattice) as f64;
    let b = plan.budget;
    let granted = b.rays_per_pixel as f64 * b.trace_fraction as f64 * slice_pixels;
    let (rays, rate) = if plan.moving {
        (granted * view.young_share(), view_rate(d, view))
    } else {
        // A still image traces its own rays for every pixel of the slice.
        (granted, d.seen_rays_per_ms)
    };
    let iterations = plan.settings(settings).filter.filter_iterations as f64;
    let ray_ms = rays / rate;
    let ms = d.fixed_ms + slice_pixels * (d.pixel_ns + iterations * d.filter_ns) * 1e-6 + ray_ms;
    (ms, rays as u64, ray_ms)
}

fn view_rate(d: &SimDevice, view: View) -> f64 {
    match view {
        View::Seen => d.seen_rays_per_ms,
        View::Unseen => d.unseen_rays_per_ms,
    }
}

/// The viewer's loop on a simulated device.
struct Run<'a> {
    d: &'a SimDevice,
    pacer: Pacer,
    settings: AoSettings,
    now: Duration,
    output: Option<(u32, u32)>,
    frames: Vec<Frame>,
    /// The still image's own rays and visits per pixel so far.
    still: (f64, f64),
    x: f32,
}

fn size_at(scale: f32) -> (u32, u32) {
    (
        ((VIEW.0 as f32 * scale).round() as u32).max(1),
        ((VIEW.1 as f32 * scale).round() as u32).max(1),
    )
}

impl<'a> Run<'a> {
    fn new(d: &'a SimDevice) -> Run<'a> {
        let device = DeviceModel::new(d.software, d.refresh_mhz);
        let scale = device.first_moving_scale();
        Run {
            d,
            pacer: Pacer::new(DEFAULT_RAYS_PER_FRAME, scale, device, Duration::ZERO),
            settings: AoSettings::default(),
            now: Duration::ZERO,
            output: None,
            frames: Vec::new(),
            still: (0.0, 0.0),
            x: 0.0,
        }
    }

    fn pacing(&self) -> Pacing<'_> {
        Pacing {
            auto_budget: true,
            target_ms: None,
            rays_per_frame: DEFAULT_RAYS_PER_FRAME,
            render_scale: 1.0,
            settings: &self.settings,
        }
    }

    fn target_ms(&self) -> f64 {
        self.pacer.target_ms(self.pacing())
    }

    /// The scene opens: its probe traces the view's primary rays (a CPU's timed on the wall clock, with its
    /// fixed cost; a GPU's by its timestamps).
    fn open(&mut self) {
        let px = VIEW.0 as u64 * VIEW.1 as u64;
        let fixed = if self.d.software { self.d.fixed_ms } else { 0.0 };
        let probe_ms = fixed + px as f64 / self.d.primary_rays_per_ms;
        let settings = self.settings.clone();
        let p = Pacing {
            settings: &settings,
            ..self.pacing()
        };
        self.pacer.scene_installed(probe_ms, px, p);
    }

    /// One turn of the loop: plan, render (or hold and settle), observe, and the repaint decision; returns
    /// whether the viewer came to rest.
    fn step(&mut self, camera_moves: bool, view: View) -> bool {
        if camera_moves {
            self.x += 0.01;
        }
        let cam = Camera {
            eye: [self.x, 0.0, 5.0],
            ..Camera::default()
        };
        let settings = self.settings.clone();
        let p = Pacing {
            settings: &settings,
            ..self.pacing()
        };
        let plan = self.pacer.plan(PlanInputs {
            now: self.now,
            camera: &cam,
            pacing: p,
            output: self.output,
            has_image: self.output.is_some(),
            scripted: false,
            shooting: false,
            size_at: &size_at,
        });
        if self.pacer.settles(true) || plan.hold {
            let repaint = self.pacer.repaint(self.repaint_inputs(false));
            self.now += match repaint.wake {
                Wake::After(d) => d,
                _ => Duration::from_millis(1),
            };
            return false;
        }
        let (cost_ms, rays, ray_ms) = cost(self.d, &plan, view, &settings);
        // FIFO: the loop waits for the next refresh.
        let interval = self.d.refresh_mhz.map_or(cost_ms, |mhz| {
            let vsync = 1e6 / mhz as f64;
            (cost_ms / vsync).ceil().max(1.0) * vsync
        });
        self.now += Duration::from_secs_f64(interval / 1e3);
        self.output = Some(plan.size);
        let converged = if plan.moving {
            self.still = (0.0, 0.0);
            false
        } else {
            let visits = 1.0 / (plan.lattice * plan.lattice) as f64;
            self.still.0 += plan.budget.rays_per_pixel as f64 * visits;
            self.still.1 += visits;
            self.still.0 >= settings.still.still_samples as f64 - 1e-9
                && self.still.1 >= AA_FRAMES as f64 - 1e-9
        };
        self.pacer.observe(
            FrameMeasurement {
                now: self.now,
                camera: cam,
                view_ms: interval,
                wait_ms: interval - cost_ms,
                rays,
                ray_ms: (!self.d.software).then_some(ray_ms),
                device_ms: cost_ms,
                render_ms: cost_ms,
                slices: plan.lattice * plan.lattice,
                shooting: false,
            },
            p,
        );
        self.frames.push(Frame {
            view,
            moving: plan.moving,
            cost_ms,
            rays,
            pixels: plan.size.0 as u64 * plan.size.1 as u64 / (plan.lattice * plan.lattice) as u64,
            size: plan.size,
        });
        self.pacer.repaint(self.repaint_inputs(converged)).resting
    }

    fn repaint_inputs(&self, converged: bool) -> RepaintInputs {
        RepaintInputs {
            now: self.now,
            busy: false,
            viewing: true,
            converged,
            loading: false,
        }
    }

    /// The script: open, orbit over cached geometry, pan into unseen geometry, stop until the image converges
    /// (at most `max_still` turns of the loop). Returns whether it came to rest.
    fn navigate(&mut self, orbit: usize, pan: usize, max_still: usize) -> bool {
        self.open();
        // The first frame: the scene's young map, all of it unseen.
        self.step(true, View::Unseen);
        for _ in 0..orbit {
            self.step(true, View::Seen);
        }
        for _ in 0..pan {
            self.step(true, View::Unseen);
        }
        (0..max_still).any(|_| self.step(false, View::Seen))
    }
}

fn p95(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    xs[((xs.len() as f64 * 0.95).ceil() as usize).clamp(1, xs.len()) - 1]
}

struct Outcome {
    target_ms: f64,
    first_rays_per_pixel: f64,
    pan_p95_ms: f64,
    worst_after_first_ms: f64,
    rested: bool,
    still_frames: usize,
    last: Frame,
}

fn drive(d: &SimDevice) -> Outcome {
    let mut run = Run::new(d);
    let rested = run.navigate(60, 40, 5_000);
    let frames = &run.frames;
    let pan: Vec<f64> = frames[61..101].iter().map(|f| f.cost_ms).collect();
    assert!(frames[61..101].iter().all(|f| f.view == View::Unseen && f.moving));
    let o = Outcome {
        target_ms: run.target_ms(),
        first_rays_per_pixel: frames[0].rays_per_pixel(),
        pan_p95_ms: p95(pan),
        worst_after_first_ms: frames[1..].iter().map(|f| f.cost_ms).fold(0.0, f64::max),
        rested,
        still_frames: frames.iter().filter(|f| !f.moving).count(),
        last: frames.last().cloned().expect("frames"),
    };
    eprintln!(
        "{}: target {:.2} ms, first frame {:.2} rays/px ({:.1} ms), pan p95 {:.2} ms, worst after the first \
         {:.2} ms, {} still frames, rested {}",
        d.name,
        o.target_ms,
        o.first_rays_per_pixel,
        frames[0].cost_ms,
        o.pan_p95_ms,
        o.worst_after_first_ms,
        o.still_frames,
        o.rested
    );
    o
}

/// The criteria on each device: the pan into unseen geometry at p95 ≤ 1.2× the target; no frame after
/// the first over 2× the target; the still image converges at the view's full size.
fn meets_the_target(d: &SimDevice) -> Outcome {
    let o = drive(d);
    assert!(
        o.pan_p95_ms <= 1.2 * o.target_ms,
        "{}: pan p95 {:.2} ms over 1.2 × {:.2}",
        d.name,
        o.pan_p95_ms,
        o.target_ms
    );
    assert!(
        o.worst_after_first_ms <= 2.0 * o.target_ms,
        "{}: a frame of {:.2} ms after the first, over 2 × {:.2}",
        d.name,
        o.worst_after_first_ms,
        o.target_ms
    );
    assert!(o.rested, "{}: the still image never converged", d.name);
    assert_eq!(o.last.size, VIEW, "{}: converged at the full size", d.name);
    o
}

/// Fails with the target left at 100 ms on a GPU (`DeviceModel::target_ms`), with the first budget capped at
/// the flat 300K rays (0.15 rays per pixel), with growth on unused rays (`budget::next_rays_per_frame`'s `used`)
/// together with the model's cap left out (the pan's first frames trace the budget grown over cached geometry).
#[test]
fn an_rtx_class_gpu_meets_its_refresh() {
    let o = meets_the_target(&RTX);
    assert!((o.target_ms - 1000.0 / 144.0).abs() < 1e-6, "{}", o.target_ms);
    assert!(o.first_rays_per_pixel >= 4.0, "{}", o.first_rays_per_pixel);
}

#[test]
fn a_mid_range_gpu_meets_its_refresh() {
    let o = meets_the_target(&MID_RANGE);
    assert!((o.target_ms - 1000.0 / 60.0).abs() < 1e-6, "{}", o.target_ms);
    assert!(o.first_rays_per_pixel >= 4.0, "{}", o.first_rays_per_pixel);
}

/// Fails with the moving scale's floor at 0.35 of a 1080p view (`motion::min_moving_scale`): the moving
/// frames' pixels alone cost more than the target.
#[test]
fn lavapipe_meets_100_ms() {
    let o = meets_the_target(&LAVAPIPE);
    assert_eq!(o.target_ms, device::SOFTWARE_TARGET_MS);
}

/// Rays granted over cached geometry and not traced do not grow the budget: after the orbit, the budget is
/// what fits in the target at the cached rays' cost, and the pan's first frame into unseen geometry stays
/// under 2× the target. Fails with the `used` condition left out of `budget::next_rays_per_frame` and the
/// model's cap left out (the budget grows 10 % a frame to 64 M rays: ~31 rays per pixel at 1080p).
#[test]
fn an_orbit_over_cached_geometry_does_not_grow_the_budget() {
    let mut run = Run::new(&RTX);
    run.open();
    run.step(true, View::Unseen);
    for _ in 0..200 {
        run.step(true, View::Seen);
    }
    let budget = run.pacer.rays_per_frame() as f64 / (VIEW.0 * VIEW.1) as f64;
    assert!(
        budget <= device::PAPER_RAYS_PER_PIXEL * 1.5,
        "{budget} rays per pixel"
    );
    run.step(true, View::Unseen);
    let swing = run.frames.last().expect("frame").cost_ms;
    assert!(swing <= 2.0 * run.target_ms(), "{swing} ms");
}

/// A CPU whose floor alone exceeds the target (a large scene on lavapipe: 120 ms a frame without rays): the
/// moving frames keep the rays of `device::MIN_RAY_SHARE` of the target instead of falling to the 1,000-ray
/// minimum, and spend about that share on them. Fails with the least left out of
/// `budget::next_rays_per_frame`'s cut (the pan traces 1,000 rays a frame).
#[test]
fn a_floor_over_the_target_keeps_the_rays_share() {
    const SLOW: SimDevice = SimDevice {
        name: "slow CPU",
        fixed_ms: 120.0,
        ..LAVAPIPE
    };
    let mut run = Run::new(&SLOW);
    run.navigate(60, 40, 0);
    let share = device::MIN_RAY_SHARE * run.target_ms();
    // The pan's first two frames trace the budget priced before it; the others that of the floor-bound frames.
    for (i, f) in run.frames[63..101].iter().enumerate() {
        let ray_ms = f.rays as f64 / SLOW.unseen_rays_per_ms;
        assert!(
            (0.5 * share..=1.5 * share).contains(&ray_ms),
            "pan frame {}: {} rays, {ray_ms:.1} ms of rays in a {:.1} ms frame",
            i + 2,
            f.rays,
            f.cost_ms
        );
    }
}
