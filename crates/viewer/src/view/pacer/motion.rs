//! When the view moves and when the image is done: the convergence test that lets the viewer rest, and the
//! internal resolution that follows from motion (reduced while the camera moves, full once it rests).
use std::time::Duration;

use hrtao_core::{AoSettings, FrameReport};

/// The one place that decides whether the image still changes (more frames would refine it) or is done and the
/// viewer may rest: the renderer's own end of the still-camera refinement (`Renderer::converged`).
pub fn image_converged(report: &FrameReport) -> bool {
    report.converged
}

/// The smallest render scale while moving (the user's render-scale setting caps it from above), in views up to
/// `MIN_MOVING_PIXELS / 0.35²` (1280×800).
pub const MIN_MOVING_SCALE: f32 = 0.35;
/// A larger view's moving frames may shrink to this many pixels (0.35 of 1280×800): a CPU's moving frame at
/// 0.35 of a 1080p view costs twice the target in its pixels alone.
pub const MIN_MOVING_PIXELS: f64 = 0.35 * 0.35 * 1280.0 * 800.0;

/// The smallest moving scale of a view of `view_pixels` at scale 1: `MIN_MOVING_SCALE`, or in a larger view
/// the scale of `MIN_MOVING_PIXELS`.
pub fn min_moving_scale(view_pixels: f64) -> f32 {
    if view_pixels.is_nan() || view_pixels <= MIN_MOVING_PIXELS {
        return MIN_MOVING_SCALE;
    }
    ((MIN_MOVING_PIXELS / view_pixels).sqrt() as f32).min(MIN_MOVING_SCALE)
}
/// À-trous filter iterations while the camera moves on a CPU (`DeviceModel::moving_filter_iterations`; the
/// user's setting caps it; still images get the setting). Each iteration is a full pass over the internal
/// image: on lavapipe the filter's 3 default iterations were about a sixth of a moving frame
/// (docs/benchmarks.md, viewer orbit), and a moving image is replaced a frame later.
pub const MOVING_FILTER_ITERATIONS: u32 = 1;

/// The renderer's settings for one frame: the user's `settings`, with the filter cut to `moving_filter`
/// iterations while `moving`.
pub fn frame_settings(settings: &AoSettings, moving: bool, moving_filter: u32) -> AoSettings {
    let mut s = settings.clone();
    if moving {
        s.filter.filter_iterations = s.filter.filter_iterations.min(moving_filter);
    }
    s
}

/// The view counts as still once the camera has not changed for this long and for `STILL_FRAMES` frames.
pub const STILL_AFTER: Duration = Duration::from_millis(150);
pub const STILL_FRAMES: u32 = 1;

/// Tracks camera motion and picks the internal render scale: the adaptive moving scale while the camera moves
/// (so a frame meets the frame-time target), the full scale (the user's cap) once it rests.
#[derive(Debug, Clone)]
pub struct Motion {
    last_change: Duration,
    frames_since_change: u32,
    /// Scale used while moving; adapted to the frame-time target within [MIN_MOVING_SCALE, cap].
    pub moving_scale: f32,
    /// The smallest moving scale of the current view (`min_moving_scale`).
    floor: f32,
    /// A pointer drag on the view is in progress (moving even when a frame brings no new delta).
    dragging: bool,
    /// The drag in progress has moved something (the camera, a section plane, a part).
    drag_acted: bool,
}

impl Motion {
    pub fn new(moving_scale: f32, now: Duration) -> Motion {
        Motion {
            last_change: now,
            frames_since_change: 0,
            moving_scale,
            floor: MIN_MOVING_SCALE,
            dragging: false,
            drag_acted: false,
        }
    }

    /// The view's drag state for this frame: `dragging` while a button is held on the view (or fly keys are
    /// down), `acted` when this frame's drag moved something.
    pub fn drag(&mut self, dragging: bool, acted: bool) {
        self.dragging = dragging;
        self.drag_acted = dragging && (self.drag_acted || acted);
    }

    /// A button is held on the view and its drag has not moved anything yet: the motion that follows is the
    /// input to answer, so the view holds its image (renders nothing, asks for no frame) rather than start a
    /// frame the motion would wait for. Latency wins over refinement: a still image pauses for the press.
    pub fn holds(&self) -> bool {
        self.dragging && !self.drag_acted
    }

    /// Records one frame: `changed` when its camera differs from the previous frame's.
    pub fn frame(&mut self, changed: bool, now: Duration) {
        if changed {
            self.last_change = now;
            self.frames_since_change = 0;
        } else {
            self.frames_since_change = self.frames_since_change.saturating_add(1);
        }
    }

    /// True while the camera moves (or has just stopped).
    pub fn moving(&self, now: Duration) -> bool {
        self.dragging
            || self.frames_since_change < STILL_FRAMES
            || now.saturating_sub(self.last_change) < STILL_AFTER
    }

    /// The view has not moved this frame (`changed` false) but does not count as still yet: within STILL_AFTER
    /// of its last change, or a drag that has acted pauses. A frame rendered now would refine the moving image
    /// at the moving scale, to be replaced by the still image once the view counts as still.
    pub fn settling(&self, changed: bool, now: Duration) -> bool {
        !changed && self.moving(now)
    }

    /// How long until the view counts as still if nothing moves it meanwhile; None during a drag (its motion
    /// or release, input both, end the wait).
    pub fn still_in(&self, now: Duration) -> Option<Duration> {
        (!self.dragging).then(|| {
            (self.last_change + STILL_AFTER)
                .saturating_sub(now)
                .max(Duration::from_millis(1))
        })
    }

    /// The view measures `view_pixels` at scale 1: the moving scale's floor follows it.
    pub fn view(&mut self, view_pixels: f64) {
        self.floor = min_moving_scale(view_pixels);
    }

    /// The render scale for the next frame; `cap` is the user's render-scale setting.
    pub fn scale(&self, cap: f32, now: Duration) -> f32 {
        if self.moving(now) {
            self.moving_scale.clamp(self.floor.min(cap), cap)
        } else {
            cap
        }
    }

    /// Adapts the moving scale to the frame-time target (an upper bound) after a moving frame of `frame_ms`
    /// (area ∝ scale²).
    pub fn adapt(&mut self, frame_ms: f64, target_ms: f64, cap: f32) {
        let s = self.moving_scale;
        let next = if frame_ms > target_ms {
            s * 0.9
        } else if frame_ms < target_ms * 0.7 {
            s * 1.05
        } else {
            s
        };
        self.moving_scale = next.clamp(self.floor.min(cap), cap);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_scale_once_still_reduced_while_moving() {
        let t0 = Duration::from_secs(100);
        let mut m = Motion::new(0.35, t0);
        m.frame(true, t0);
        assert!(m.moving(t0));
        assert_eq!(m.scale(1.0, t0), 0.35);
        // The user's setting caps the scale, also while moving.
        assert_eq!(m.scale(0.2, t0), 0.2);
        let later = t0 + STILL_AFTER + Duration::from_millis(1);
        m.frame(false, later);
        assert!(!m.moving(later));
        assert_eq!(m.scale(1.0, later), 1.0);
        m.drag(true, false);
        assert!(m.moving(later));
    }

    #[test]
    fn a_press_holds_the_view_until_its_drag_moves_something() {
        let mut m = Motion::new(0.35, Duration::ZERO);
        assert!(!m.holds());
        // Pressed: nothing moved yet.
        m.drag(true, false);
        assert!(m.holds());
        // The first motion acts; a pause mid-drag does not hold (it settles: `settling`).
        m.drag(true, true);
        assert!(!m.holds());
        m.drag(true, false);
        assert!(!m.holds());
        // Released, then a new press holds again.
        m.drag(false, false);
        assert!(!m.holds());
        m.drag(true, false);
        assert!(m.holds());
    }

    #[test]
    fn a_view_that_stopped_settles_until_the_still_deadline() {
        let t0 = Duration::from_secs(100);
        let mut m = Motion::new(0.35, t0);
        m.frame(true, t0);
        assert!(!m.settling(true, t0), "a frame that moves the camera renders");
        // No change 40 ms later: settling, woken at the still deadline.
        let t1 = t0 + Duration::from_millis(40);
        m.frame(false, t1);
        assert!(m.settling(false, t1));
        assert_eq!(m.still_in(t1), Some(STILL_AFTER - Duration::from_millis(40)));
        // At the deadline the view is still: its still image starts.
        let t2 = t0 + STILL_AFTER;
        m.frame(false, t2);
        assert!(!m.moving(t2) && !m.settling(false, t2));
        // A drag that has moved the view and pauses settles with no deadline: its motion or release wakes it.
        m.drag(true, true);
        assert!(m.settling(false, t2));
        assert_eq!(m.still_in(t2), None);
        m.drag(false, false);
        assert!(!m.settling(false, t2));
    }

    #[test]
    fn moving_frames_filter_less_still_frames_keep_the_setting() {
        let user = {
            let mut s = AoSettings::default();
            s.filter.filter_iterations = 4;
            s
        };
        assert_eq!(
            frame_settings(&user, true, MOVING_FILTER_ITERATIONS)
                .filter
                .filter_iterations,
            MOVING_FILTER_ITERATIONS
        );
        assert_eq!(frame_settings(&user, false, 1), user);
        assert_eq!(frame_settings(&user, true, 4), user);
        // Only the filter changes, and a setting below the moving one stays.
        let off = {
            let mut s = user.clone();
            s.filter.filter_iterations = 0;
            s
        };
        assert_eq!(frame_settings(&off, true, 1), off);
        let moving = frame_settings(&user, true, MOVING_FILTER_ITERATIONS);
        assert_eq!(
            {
                let mut s = moving.clone();
                s.filter.filter_iterations = 4;
                s
            },
            user
        );
        assert!(moving.validate().is_ok());
    }

    #[test]
    fn moving_scale_follows_the_frame_time_target() {
        let mut m = Motion::new(1.0, Duration::ZERO);
        for _ in 0..100 {
            m.adapt(500.0, 100.0, 1.0);
        }
        assert_eq!(m.moving_scale, MIN_MOVING_SCALE);
        for _ in 0..100 {
            m.adapt(10.0, 100.0, 0.8);
        }
        assert_eq!(m.moving_scale, 0.8);
    }

    /// Up to 1280×800 the moving scale stops at 0.35; a 1080p view's at the same pixel count (0.246). Fails
    /// with the floor left at `MIN_MOVING_SCALE` for every view.
    #[test]
    fn a_larger_views_moving_frames_shrink_to_the_same_pixels() {
        assert_eq!(min_moving_scale(862.0 * 800.0), MIN_MOVING_SCALE);
        assert_eq!(min_moving_scale(1280.0 * 800.0), MIN_MOVING_SCALE);
        assert_eq!(min_moving_scale(f64::NAN), MIN_MOVING_SCALE);
        let hd = min_moving_scale(1920.0 * 1080.0);
        assert!((hd - 0.2464).abs() < 1e-3, "{hd}");
        let mut m = Motion::new(1.0, Duration::ZERO);
        m.view(1920.0 * 1080.0);
        for _ in 0..100 {
            m.adapt(500.0, 100.0, 1.0);
        }
        assert_eq!(m.moving_scale, hd);
    }
}
