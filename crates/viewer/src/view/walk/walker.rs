//! The walker's body: a cylinder of the body radius standing on the floor, its eye at the eye height, moved at a
//! walking speed in metres per second (independent of the frame rate), held onto the floor by gravity, climbing
//! steps up to the step height and stopped by walls, along which it slides. Pure: it asks probe rays
//! ([`Walker::rays`]) and learns from their hits whenever they come back ([`Walker::hits`], a frame or two
//! later: the frame never waits for them), so it runs the same against the device's rays and against the
//! CPU's in the tests.
//!
//! The rays of one ask: one floor ray straight down from the knee (the step height above the feet) at the
//! position the body is heading to, then collision rays in `DIRECTIONS` horizontal directions at `HEIGHTS`
//! heights (just above a step, the waist, the eye). A collision hit is an obstacle: a point of a surface with
//! its horizontal normal, which the body may not come nearer than its radius to (the plane of the surface, for
//! the body's points within its radius of the hit's side line). The obstacles of the newest answer are kept.
use std::collections::VecDeque;

use glam::Vec3;
use hrtao_core::camera::UpAxis;
use hrtao_core::gpu::{ProbeHit, ProbeRay};
use serde::{Deserialize, Serialize};

/// Horizontal directions of the collision rays.
pub const DIRECTIONS: usize = 16;
/// Heights of the collision rays: fractions of the way from just above a step to the eye.
const HEIGHTS: [f32; 3] = [0.0, 0.5, 1.0];
/// Rays of one ask: the floor ray, then the collision rays.
pub const RAYS: usize = 1 + DIRECTIONS * HEIGHTS.len();
/// The longest time step: a slower frame walks less than its time (a hitch never jumps through a wall).
pub const MAX_DT_S: f32 = 0.25;
/// Metres per second squared.
const GRAVITY_M_S2: f32 = 9.81;
/// How far beyond the body the collision rays look, in metres (at least; faster walking looks further).
const LOOKAHEAD_M: f32 = 1.0;
/// A move shorter than this share of the asked one is blocked.
const BLOCKED_SHARE: f32 = 0.25;

/// The walk's measures, in metres (converted by the file's unit).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct WalkSettings {
    /// The eye above the floor.
    pub eye_height_m: f32,
    /// The highest step climbed (and stepped down without falling).
    pub step_height_m: f32,
    /// The body's radius: how near a wall it comes.
    pub radius_m: f32,
    /// Walking speed (Shift: `RUN_FACTOR` times).
    pub speed_m_s: f32,
}

impl Default for WalkSettings {
    fn default() -> Self {
        WalkSettings {
            eye_height_m: 1.7,
            step_height_m: 0.35,
            radius_m: 0.25,
            speed_m_s: 1.4,
        }
    }
}

/// Shift walks this many times faster.
pub const RUN_FACTOR: f32 = 3.0;

impl WalkSettings {
    /// Every measure finite and positive, the step below the eye, the speed at most 100 m/s.
    pub fn sanitized(self) -> WalkSettings {
        let d = WalkSettings::default();
        let ok = |v: f32, max: f32| v.is_finite() && v > 0.0 && v <= max;
        let eye = if ok(self.eye_height_m, 100.0) {
            self.eye_height_m
        } else {
            d.eye_height_m
        };
        WalkSettings {
            eye_height_m: eye,
            step_height_m: if ok(self.step_height_m, eye) {
                self.step_height_m
            } else {
                d.step_height_m.min(eye * 0.5)
            },
            radius_m: if ok(self.radius_m, 10.0) {
                self.radius_m
            } else {
                d.radius_m
            },
            speed_m_s: if ok(self.speed_m_s, 100.0) {
                self.speed_m_s
            } else {
                d.speed_m_s
            },
        }
    }
}

/// What moves the walker this frame: forward (+) or back, right (+) or left, each in -1..=1, and running.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WalkInput {
    pub forward: f32,
    pub right: f32,
    pub run: bool,
}

/// An obstacle: a point of a surface and the surface's horizontal unit normal, toward the side the ray came from.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Obstacle {
    at: Vec3,
    normal: Vec3,
}

/// What the floor rays have found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Floor {
    /// No answer yet: the body stays where it is.
    Unknown,
    /// The height (along the up axis) of the floor under the body.
    At(f32),
    /// The floor ray found nothing below: the body keeps its height ("walking level").
    None,
}

pub struct Walker {
    up: UpAxis,
    /// Scene units per metre.
    scale: f32,
    settings: WalkSettings,
    /// The point on the floor under the eye, in scene coordinates.
    feet: Vec3,
    /// Along the up axis, scene units per second (negative: falling).
    vertical_speed: f32,
    floor: Floor,
    obstacles: Vec<Obstacle>,
    /// The rays asked and not answered, oldest first.
    pending: VecDeque<Vec<ProbeRay>>,
    /// The rays the next frame traces.
    next: Vec<ProbeRay>,
    /// The last step asked to move and moved less than `BLOCKED_SHARE` of it.
    blocked: bool,
    /// How far below the knee the floor ray looks (the model's height and then some).
    fall_range: f32,
    /// Asks between the newest answer's and now (at least 1: an answer never comes in its own frame).
    pub answer_lag: u32,
    /// Asks made (the next ask's tag).
    asked: u64,
}

impl Walker {
    /// A walker standing at `feet` (it falls onto the floor below once the floor ray answers), in a scene with
    /// `units_per_metre` whose up axis is `up` and whose extent along it is about `model_height`.
    pub fn new(
        up: UpAxis,
        units_per_metre: f32,
        settings: WalkSettings,
        feet: Vec3,
        model_height: f32,
    ) -> Walker {
        let scale = if units_per_metre.is_finite() && units_per_metre > 0.0 {
            units_per_metre
        } else {
            1.0
        };
        let mut w = Walker {
            up,
            scale,
            settings: settings.sanitized(),
            feet,
            vertical_speed: 0.0,
            floor: Floor::Unknown,
            obstacles: Vec::new(),
            pending: VecDeque::new(),
            next: Vec::new(),
            blocked: false,
            fall_range: model_height.abs().max(scale * 10.0) * 2.0,
            answer_lag: 0,
            asked: 0,
        };
        w.next = w.ask(Vec3::ZERO);
        w
    }

    fn m(&self, metres: f32) -> f32 {
        metres * self.scale
    }

    pub fn feet(&self) -> Vec3 {
        self.feet
    }

    /// The eye: the feet plus the eye height along the up axis.
    pub fn eye(&self) -> Vec3 {
        self.feet + self.up.vector() * self.m(self.settings.eye_height_m)
    }

    pub fn floor(&self) -> Floor {
        self.floor
    }

    pub fn blocked(&self) -> bool {
        self.blocked
    }

    /// The height of a point along the up axis.
    fn height(&self, p: Vec3) -> f32 {
        p.dot(self.up.vector())
    }

    fn horizontal(&self, v: Vec3) -> Vec3 {
        let up = self.up.vector();
        v - up * v.dot(up)
    }

    /// The rays the next frame should trace.
    pub fn rays(&self) -> &[ProbeRay] {
        &self.next
    }

    /// The rays of `rays()` went into a frame: their answer comes with that frame's report.
    pub fn submitted(&mut self) {
        if !self.next.is_empty() {
            self.pending.push_back(std::mem::take(&mut self.next));
        }
    }

    /// Rays asked and not answered.
    pub fn waiting(&self) -> usize {
        self.pending.len()
    }

    /// A finished frame's probe hits: the answer to the ask their tag names (older asks, whose frames were
    /// dropped, are forgotten; a frame that traced none answers nothing).
    pub fn hits(&mut self, hits: &[ProbeHit]) {
        let Some(tag) = hits.first().map(|h| h.tag) else {
            return;
        };
        let Some(k) = self
            .pending
            .iter()
            .position(|a| a.first().is_some_and(|r| r.tag == tag))
        else {
            return;
        };
        let rays = self.pending.drain(..=k).next_back().expect("the answered ask");
        if rays.len() != hits.len() {
            return;
        }
        // Used by the next step: one more than the asks made since.
        self.answer_lag = (self.asked as u32).wrapping_sub(tag) + 1;
        let up = self.up.vector();
        if let (Some(r), Some(h)) = (rays.first(), hits.first()) {
            self.floor = match h.distance() {
                Some(t) => Floor::At(self.height(Vec3::from(r.origin)) - t),
                None => Floor::None,
            };
        }
        self.obstacles = rays
            .iter()
            .zip(hits)
            .skip(1)
            .filter_map(|(r, h)| {
                let t = h.distance()?;
                let n = Vec3::from(h.normal);
                let nh = n - up * n.dot(up);
                // A floor or a ceiling met by a horizontal ray (a slope) is no wall.
                if nh.length() < 0.5 {
                    return None;
                }
                Some(Obstacle {
                    at: Vec3::from(r.origin) + Vec3::from(r.dir) * t,
                    normal: nh.normalize(),
                })
            })
            .collect();
    }

    /// Moves the body by `input` over `dt` seconds, looking along `forward` (its horizontal part walks).
    pub fn step(&mut self, dt: f32, input: WalkInput, forward: Vec3) {
        let dt = if dt.is_finite() {
            dt.clamp(0.0, MAX_DT_S)
        } else {
            0.0
        };
        let up = self.up.vector();
        let fwd = self.horizontal(forward).normalize_or_zero();
        let right = fwd.cross(up).normalize_or_zero();
        let mut wish = fwd * input.forward.clamp(-1.0, 1.0) + right * input.right.clamp(-1.0, 1.0);
        if wish.length() > 1.0 {
            wish = wish.normalize();
        }
        let speed = self.m(self.settings.speed_m_s) * if input.run { RUN_FACTOR } else { 1.0 };
        let velocity = wish * speed;
        let start = self.feet;
        let mut feet = start;
        if self.floor != Floor::Unknown {
            feet += velocity * dt;
            feet = self.collide(feet);
        }
        let asked = (velocity * dt).length();
        let moved = self.horizontal(feet - start).length();
        self.blocked = asked > 0.0 && moved < BLOCKED_SHARE * asked;
        // Along the up axis: onto the floor, up a step, or falling.
        let step = self.m(self.settings.step_height_m);
        let mut h = self.height(feet);
        match self.floor {
            Floor::At(floor) if floor >= h => {
                if floor - h <= step * 1.01 {
                    h = floor;
                    self.vertical_speed = 0.0;
                } else {
                    // Higher than a step under the body: a wall the collision rays missed. Stay.
                    feet = start;
                    h = self.height(start);
                    self.blocked = asked > 0.0;
                }
            }
            Floor::At(floor) => {
                if self.vertical_speed == 0.0 && h - floor <= step * 1.01 {
                    h = floor;
                } else {
                    self.vertical_speed -= self.m(GRAVITY_M_S2) * dt;
                    h = (h + self.vertical_speed * dt).max(floor);
                    if h <= floor {
                        self.vertical_speed = 0.0;
                    }
                }
            }
            Floor::None | Floor::Unknown => self.vertical_speed = 0.0,
        }
        self.feet = self.horizontal(feet) + up * h;
        // The floor ray looks where the body will be when its answer is used: as far again as it moved (after
        // the walls) for each ask its answers lag behind.
        let ahead = self.horizontal(self.feet - start) * self.answer_lag.clamp(1, 4) as f32;
        self.next = self.ask(ahead);
    }

    /// Pushes `feet` out of every obstacle it comes nearer than the radius to (twice: a corner's two walls).
    fn collide(&self, mut feet: Vec3) -> Vec3 {
        let r = self.m(self.settings.radius_m);
        for _ in 0..2 {
            for o in &self.obstacles {
                let rel = self.horizontal(feet - o.at);
                let d = rel.dot(o.normal);
                let lateral = (rel - o.normal * d).length();
                if lateral < r && d < r && d > -r {
                    feet += o.normal * (r - d);
                }
            }
        }
        feet
    }

    /// The rays of one ask from the body at `feet`, heading `ahead` further next frame.
    fn ask(&mut self, ahead: Vec3) -> Vec<ProbeRay> {
        self.asked += 1;
        let tag = self.asked as u32;
        let up = self.up.vector();
        let step = self.m(self.settings.step_height_m);
        let eye = self.m(self.settings.eye_height_m);
        let knee = (step + self.m(0.05)).min(eye);
        let mut rays = Vec::with_capacity(RAYS);
        rays.push(ProbeRay::new(
            self.feet + ahead + up * knee,
            -up,
            knee + self.fall_range,
            tag,
        ));
        let look = self.m(self.settings.radius_m) + self.m(LOOKAHEAD_M).max(ahead.length() * 4.0);
        let [e1, e2, _] = self.up.frame().map(|v| v.as_vec3());
        for f in HEIGHTS {
            let origin = self.feet + up * (knee + (eye - knee) * f);
            for k in 0..DIRECTIONS {
                let a = k as f32 * std::f32::consts::TAU / DIRECTIONS as f32;
                rays.push(ProbeRay::new(origin, e1 * a.cos() + e2 * a.sin(), look, tag));
            }
        }
        rays
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axis-aligned box world answering rays on the CPU (slab test), as the device would.
    struct Boxes(Vec<(Vec3, Vec3)>);

    impl Boxes {
        fn trace(&self, r: &ProbeRay) -> ProbeHit {
            let (o, d) = (Vec3::from(r.origin), Vec3::from(r.dir));
            let mut best = ProbeHit {
                t: -1.0,
                ..Default::default()
            };
            for &(lo, hi) in &self.0 {
                let (mut t0, mut t1, mut axis) = (r.tmin, r.tmax, 0);
                let mut ok = true;
                for i in 0..3 {
                    if d[i].abs() < 1e-9 {
                        if o[i] < lo[i] || o[i] > hi[i] {
                            ok = false;
                        }
                        continue;
                    }
                    let (a, b) = ((lo[i] - o[i]) / d[i], (hi[i] - o[i]) / d[i]);
                    let (a, b) = (a.min(b), a.max(b));
                    if a > t0 {
                        t0 = a;
                        axis = i;
                    }
                    t1 = t1.min(b);
                }
                if ok && t0 <= t1 && t0 >= r.tmin && (best.t < 0.0 || t0 < best.t) {
                    let mut n = [0.0; 3];
                    n[axis] = -d[axis].signum();
                    best = ProbeHit {
                        normal: n,
                        t: t0,
                        ..Default::default()
                    };
                }
            }
            best.tag = r.tag;
            best
        }
    }

    /// Walks `w` toward `to` (horizontal) for `frames` frames of `dt`, answering each ask `lag` frames late.
    fn walk(
        w: &mut Walker,
        world: &Boxes,
        to: Vec3,
        frames: usize,
        dt: f32,
        lag: usize,
    ) -> Vec<(Vec3, Floor)> {
        let mut in_flight: VecDeque<Vec<ProbeHit>> = VecDeque::new();
        let mut track = Vec::new();
        for _ in 0..frames {
            let d = (to - w.feet()) * Vec3::new(1.0, 1.0, 0.0);
            let input = WalkInput {
                forward: if d.length() > 0.05 { 1.0 } else { 0.0 },
                ..Default::default()
            };
            w.step(dt, input, d);
            in_flight.push_back(w.rays().iter().map(|r| world.trace(r)).collect());
            w.submitted();
            if in_flight.len() > lag {
                let hits = in_flight.pop_front().unwrap();
                w.hits(&hits);
            }
            track.push((w.feet(), w.floor()));
        }
        track
    }

    /// A floor at z = 0, a wall at x in [4, 4.2] with a door at y in [3, 4] (up to 2.1), and a stair of 17 steps of
    /// 3/17 m along x from 6.5 onto a slab at z = 3 from x = 11.26: the building of the walk's IFC test, in metres.
    fn building() -> Boxes {
        let b = |lo: [f32; 3], hi: [f32; 3]| (Vec3::from(lo), Vec3::from(hi));
        let mut v = vec![
            b([0.0, 0.0, -0.2], [14.0, 8.0, 0.0]),
            b([4.0, 0.0, 0.0], [4.2, 3.0, 2.8]),
            b([4.0, 4.0, 0.0], [4.2, 8.0, 2.8]),
            b([4.0, 3.0, 2.1], [4.2, 4.0, 2.8]),
            b([11.26, 0.0, 2.8], [14.0, 8.0, 3.0]),
        ];
        for k in 1..=17 {
            let x = 6.5 + 0.28 * (k - 1) as f32;
            v.push(b([x, 6.8, 0.0], [x + 0.28, 7.8, k as f32 * 3.0 / 17.0]));
        }
        Boxes(v)
    }

    fn walker(at: Vec3, scale: f32) -> Walker {
        Walker::new(UpAxis::Z, scale, WalkSettings::default(), at * scale, 3.2 * scale)
    }

    #[test]
    fn it_falls_onto_the_floor_and_keeps_its_eye_at_the_eye_height() {
        let world = building();
        let mut w = walker(Vec3::new(2.0, 1.5, 1.0), 1.0);
        let track = walk(&mut w, &world, Vec3::new(2.0, 1.5, 0.0), 30, 0.1, 1);
        assert_eq!(track.last().unwrap().1, Floor::At(0.0));
        assert!((w.eye().z - 1.7).abs() < 1e-4, "{}", w.eye());
        // It fell: the first frames were above the floor.
        assert!(track[2].0.z > 0.5 && track[2].0.z < 1.0, "{track:?}");
    }

    #[test]
    fn a_wall_stops_it_at_the_radius_and_it_slides_along() {
        let world = building();
        for (lag, dt) in [(1, 0.1), (2, 0.25), (1, 1.0 / 60.0)] {
            let mut w = walker(Vec3::new(2.0, 1.5, 0.0), 1.0);
            let track = walk(&mut w, &world, Vec3::new(6.0, 1.5, 0.0), 120, dt, lag);
            let furthest = track.iter().map(|p| p.0.x).fold(f32::MIN, f32::max);
            assert!(
                furthest <= 4.0 - 0.25 + 1e-3,
                "lag {lag} dt {dt}: beyond the wall: x {furthest}"
            );
            assert!(furthest > 3.7, "lag {lag}: stopped early at {furthest}");
            assert!(w.blocked(), "blocked");
            // Sliding: heading diagonally into the wall, it moves along y.
            let y0 = w.feet().y;
            walk(&mut w, &world, Vec3::new(6.0, 2.7, 0.0), 20, dt.max(0.1), lag);
            assert!(w.feet().y > y0 + 0.3 && w.feet().x <= 3.75 + 1e-3, "{}", w.feet());
        }
    }

    #[test]
    fn it_passes_the_door_and_climbs_the_stair_in_millimetres() {
        let world = Boxes(
            building()
                .0
                .into_iter()
                .map(|(a, b)| (a * 1000.0, b * 1000.0))
                .collect(),
        );
        let mut w = walker(Vec3::new(2.0, 3.5, 0.0), 1000.0);
        let mut track = walk(&mut w, &world, Vec3::new(5.5, 3.5, 0.0) * 1000.0, 60, 0.1, 1);
        assert!(w.feet().x > 5400.0, "through the door: {}", w.feet());
        track.extend(walk(
            &mut w,
            &world,
            Vec3::new(6.0, 7.3, 0.0) * 1000.0,
            60,
            0.1,
            1,
        ));
        track.extend(walk(
            &mut w,
            &world,
            Vec3::new(12.5, 7.3, 0.0) * 1000.0,
            120,
            0.1,
            1,
        ));
        assert!((w.feet().z - 3000.0).abs() < 1.0, "upstairs: {}", w.feet());
        assert!(w.feet().x > 12000.0, "{}", w.feet());
        // On the stair the feet stand on some step (never inside one, never more than a step above).
        for (p, _) in &track {
            if p.x > 6500.0 && p.x < 11260.0 && p.y > 6800.0 {
                let k = ((p.x - 6500.0) / 280.0).ceil().max(1.0);
                let top = k * 3000.0 / 17.0;
                assert!(
                    p.z >= top - 1.0 && p.z <= top + 3000.0 / 17.0 + 1.0,
                    "{p} over step {k}"
                );
            }
        }
    }

    #[test]
    fn with_no_floor_below_it_walks_level() {
        let world = Boxes(Vec::new());
        let mut w = walker(Vec3::new(0.0, 0.0, 5.0), 1.0);
        walk(&mut w, &world, Vec3::new(3.0, 0.0, 5.0), 30, 0.1, 1);
        assert_eq!(w.floor(), Floor::None);
        assert_eq!(w.feet().z, 5.0);
        assert!(w.feet().x > 2.5);
    }

    #[test]
    fn walking_speed_does_not_depend_on_the_frame_rate() {
        let world = building();
        let mut ends = Vec::new();
        for dt in [1.0 / 60.0, 0.1, 0.2] {
            let mut w = walker(Vec3::new(0.5, 1.5, 0.0), 1.0);
            walk(&mut w, &world, Vec3::new(0.5, 1.5, 0.0), 5, dt, 1);
            let x0 = w.feet().x;
            let frames = (2.0 / dt).round() as usize;
            walk(&mut w, &world, Vec3::new(3.5, 1.5, 0.0), frames, dt, 1);
            ends.push(w.feet().x - x0);
        }
        for e in &ends {
            assert!((e - 2.8).abs() < 0.05, "2 s at 1.4 m/s: {ends:?}");
        }
    }
}
