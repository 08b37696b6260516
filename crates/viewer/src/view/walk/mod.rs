//! Walk mode: through a building at eye height on its floors, as BIM viewers walk (G or the panel's switch; Esc
//! leaves it). The body (`walker.rs`) keeps the eye at the eye height above the floor, climbs steps, stops at
//! walls and slides along them, at a walking speed in metres per second; the mouse looks around (left drag),
//! W/A/S/D walk, Shift runs. Its gravity and collision rays are traced on the device by the renderer's own ray
//! backend, in the frames the view renders anyway (`FrameDesc::probes`), and answered a frame later: a frame
//! never waits for them. Hidden parts and section planes are honoured (the rays trace what the view shows).
//! `--walk-path` scripts a walk (`path.rs`).
pub mod path;
pub mod walker;

use std::time::Instant;

use glam::Vec3;
use hrtao_core::camera::Projection;
use hrtao_core::gpu::{ProbeHit, ProbeRay};
use hrtao_core::Camera;
use hrtao_scene::Scene;
use serde::Serialize;

use super::command::{Command, ViewState};
use super::nav::{self, Nav};
use super::ui_probe;
use crate::setup::metres_per_unit;
pub use walker::{Floor, WalkInput, WalkSettings, Walker};

/// How far ahead of the eye the walking camera's target lies, in metres (the orbit pivot when leaving).
const LOOK_DISTANCE_M: f32 = 2.0;
/// A double-clicked surface whose normal's cosine with the up axis is above this is a floor to stand on.
pub const FLOOR_COS: f32 = 0.7;
/// A model whose horizontal extent is at least this many metres is walked in: a double-click on its floor
/// stands there (on a smaller one, a part on a desk, it sets the orbit pivot as always).
const ROOM_M: f32 = 2.0;
/// A scripted walk reaches a waypoint within this distance, in metres.
const REACH_M: f32 = 0.15;

/// What the walk records per frame of `--stats` (`"walk"`), in the file's coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WalkStat {
    pub blocked: bool,
    /// The height of the floor under the body along the up axis (None: not known, or none below).
    pub floor: Option<f64>,
    /// Frames between the ask of the rays the body last learnt from and their answer (at least 1).
    pub answer_lag: u32,
}

/// The walk's state (the panels own it: `ui::Panels::walk`).
#[derive(Default)]
pub struct Walk {
    /// The body, while walking.
    walker: Option<Walker>,
    /// This frame's keys (`input.rs`).
    pub input: WalkInput,
    last_tick: Option<Instant>,
    /// `--walk-path`, read at start; walked once the scene is open.
    pub script: Option<path::WalkPathFile>,
    running: Option<path::WalkPath>,
    /// "no floor below" was said for this walk.
    told_no_floor: bool,
}

impl Walk {
    /// Stops walking (another scene opened).
    pub fn leave(&mut self) {
        self.walker = None;
        self.running = None;
    }

    pub fn walking(&self) -> bool {
        self.walker.is_some()
    }

    /// The rays the next frame should trace (none when not walking).
    pub fn rays(&self) -> &[ProbeRay] {
        self.walker.as_ref().map_or(&[], |w| w.rays())
    }

    /// The rays of `rays()` went into a frame.
    pub fn submitted(&mut self) {
        if let Some(w) = &mut self.walker {
            w.submitted();
        }
    }

    /// A finished frame's probe hits.
    pub fn hits(&mut self, hits: &[ProbeHit]) {
        if let Some(w) = &mut self.walker {
            w.hits(hits);
        }
    }

    /// The walk needs frames rendered (their rays): falling, moving, or waiting for an answer.
    pub fn wants_frames(&self) -> bool {
        match &self.walker {
            Some(w) => {
                w.floor() == Floor::Unknown
                    || w.waiting() > 0
                    || self.input != WalkInput::default()
                    || self.running.is_some()
                    || matches!(w.floor(), Floor::At(f) if (w.feet().dot(w_up(w)) - f).abs() > 1e-6)
            }
            None => false,
        }
    }

    /// A scripted walk is under way (the script waits for it).
    pub fn script_running(&self) -> bool {
        self.running.is_some() || (self.script.is_some() && self.walker.is_none())
    }

    /// This frame's `--stats` record, in the file's coordinates (`origin`).
    pub fn stat(&self, origin: [f64; 3]) -> Option<(WalkStat, [f64; 3])> {
        let w = self.walker.as_ref()?;
        let o = glam::DVec3::from(origin);
        let eye = w.eye().as_dvec3() + o;
        let up = w_up(w).as_dvec3();
        Some((
            WalkStat {
                blocked: w.blocked(),
                floor: match w.floor() {
                    Floor::At(f) => Some(f as f64 + o.dot(up)),
                    _ => None,
                },
                answer_lag: w.answer_lag,
            },
            eye.to_array(),
        ))
    }
}

fn w_up(w: &Walker) -> Vec3 {
    w.eye() - w.feet()
}

/// The panel's row: the walk switch and the body's measures.
pub fn panel(ui: &mut egui::Ui, state: &ViewState, walking: bool) -> Vec<Command> {
    let mut out = Vec::new();
    let mut on = walking;
    let r = ui.checkbox(&mut on, "Walk (G)").on_hover_text(
        "Walk through the model at eye height: W/A/S/D walk, Shift runs, left drag looks around, Esc \
             leaves. Gravity holds you on the floor, steps are climbed and walls stop you. Double-click a \
             floor to stand there.",
    );
    ui_probe::note("walk", r.rect, ui.ctx().pixels_per_point());
    if on != walking {
        out.push(Command::Walk(on));
    }
    let mut s = state.prefs.walk;
    egui::Grid::new("walk settings").num_columns(2).show(ui, |ui| {
        for (label, v, range, tip) in [
            (
                "eye height",
                &mut s.eye_height_m,
                0.3..=3.0,
                "The eye above the floor, in metres.",
            ),
            (
                "step height",
                &mut s.step_height_m,
                0.05..=1.0,
                "The highest step climbed, in metres.",
            ),
            (
                "body radius",
                &mut s.radius_m,
                0.05..=1.0,
                "How near walls come, in metres.",
            ),
            (
                "speed",
                &mut s.speed_m_s,
                0.2..=10.0,
                "Walking speed in metres per second (Shift: ×3).",
            ),
        ] {
            ui.label(label);
            ui.add(
                egui::DragValue::new(v)
                    .range(range)
                    .speed(0.01)
                    .suffix(if label == "speed" { " m/s" } else { " m" }),
            )
            .on_hover_text(tip);
            ui.end_row();
        }
    });
    if s != state.prefs.walk {
        let mut p = state.prefs.clone();
        p.walk = s;
        out.push(Command::Prefs(Box::new(p)));
    }
    out
}

/// What the walk reads of the viewer.
pub struct WalkView<'a> {
    pub scene: &'a Scene,
    /// The open scene's file or spec (the bundled scene is in millimetres).
    pub spec: &'a str,
    pub nav: &'a Nav,
    pub settings: &'a WalkSettings,
}

impl WalkView<'_> {
    fn metres_per_unit(&self) -> f32 {
        metres_per_unit(self.scene, crate::setup::is_bundled(Some(self.spec)))
    }
}

impl Walk {
    /// Walk mode on (standing below the camera's eye, or at `at`) or off: the camera to walk with and the
    /// toast.
    pub fn set(&mut self, on: bool, at: Option<Vec3>, v: &WalkView) -> Vec<Command> {
        if !on {
            if self.walker.take().is_some() {
                self.running = None;
                log::info!("walk mode off");
            }
            return Vec::new();
        }
        let up = v.nav.world_up;
        let upv = up.vector();
        let m = v.metres_per_unit();
        let s = v.settings.sanitized();
        let eye_height = s.eye_height_m / m;
        let feet = at.unwrap_or_else(|| nav::eye(&v.nav.cam) - upv * eye_height);
        let b = v.scene.bounds();
        let height = (b.max - b.min).dot(upv).abs();
        let walker = Walker::new(up, 1.0 / m, s, feet, height);
        // Level the view (keep where it looks around the up axis) in perspective.
        let fwd = nav::forward(&v.nav.cam);
        let level = fwd - upv * fwd.dot(upv);
        let level = if level.length() > 1e-3 {
            level.normalize()
        } else {
            nav::cam_up(&v.nav.cam).normalize()
        };
        let mut at_eye = *v.nav;
        at_eye.cam.projection = Projection::Perspective;
        let (cam, pivot) = walk_camera(&at_eye, walker.eye(), level, m);
        log::info!(
            "walk mode on at {:?} (eye height {} m, {} scene units per metre)",
            walker.eye().to_array(),
            s.eye_height_m,
            1.0 / m
        );
        self.walker = Some(walker);
        self.last_tick = None;
        self.told_no_floor = false;
        vec![
            Command::Camera { cam, pivot },
            Command::toast("walking: W/A/S/D walk, Shift runs, drag looks, Esc leaves", false),
        ]
    }

    /// Whether a double-click on a floor stands there: while walking, and on a model at least room-sized.
    pub fn here(&self, v: &WalkView) -> bool {
        if self.walking() {
            return true;
        }
        let m = v.metres_per_unit();
        let b = v.scene.bounds();
        let up = v.nav.world_up.vector();
        let d = b.max - b.min;
        let horizontal = (d - up * d.dot(up)).abs().max_element();
        horizontal * m >= ROOM_M
    }

    /// The walk's step of this frame: the keys (or the scripted path, started once the view shows an image
    /// and no load runs) move the body, the camera follows.
    pub fn tick(&mut self, v: &WalkView, ready: bool) -> Vec<Command> {
        if self.walker.is_none() {
            if let Some(file) = self.script.clone().filter(|_| ready) {
                let p = path::WalkPath::new(&file, v.scene.origin, v.nav.world_up);
                log::info!(
                    "scripted walk from {:?} through {} waypoints",
                    file.start,
                    file.waypoints.len()
                );
                let start = p.start;
                self.script = None;
                let out = self.set(true, Some(start), v);
                self.running = Some(p);
                return out;
            }
            return Vec::new();
        }
        let mut out = Vec::new();
        let m = v.metres_per_unit();
        let now = Instant::now();
        let dt = self
            .last_tick
            .map_or(0.0, |t| now.duration_since(t).as_secs_f32());
        self.last_tick = Some(now);
        let Some(w) = self.walker.as_mut() else {
            return out;
        };
        let mut forward = nav::forward(&v.nav.cam);
        let mut input = self.input;
        if let Some(p) = &mut self.running {
            match p.heading(w.feet(), w.blocked(), dt, REACH_M / m) {
                Some(dir) if w.floor() != Floor::Unknown => {
                    forward = dir;
                    input = WalkInput {
                        forward: 1.0,
                        ..WalkInput::default()
                    };
                }
                Some(_) => {}
                None => {
                    log::info!(
                        "scripted walk done: {} waypoints reached, {} given up",
                        p.reached,
                        p.given_up
                    );
                    self.running = None;
                }
            }
        }
        w.step(dt, input, forward);
        let eye = w.eye();
        // Window tests follow the eye (`HRTAO_UI_PROBE`), in the file's coordinates.
        let o = glam::DVec3::from(v.scene.origin);
        let e = eye.as_dvec3() + o;
        ui_probe::note_text("walk eye", &format!("{:.3} {:.3} {:.3}", e.x, e.y, e.z));
        let no_floor = w.floor() == Floor::None;
        let upv = v.nav.world_up.vector();
        let walk_running = self.running.is_some();
        let look = if walk_running {
            let f = forward - upv * forward.dot(upv);
            f.normalize_or_zero()
        } else {
            nav::forward(&v.nav.cam)
        };
        let told = self.told_no_floor;
        self.told_no_floor |= no_floor;
        if no_floor && !told {
            out.push(Command::toast("no floor below: walking level", false));
        }
        // A body at rest leaves the camera bit for bit (a re-derived one would be a new view each frame).
        let turned = walk_running && (look - nav::forward(&v.nav.cam)).length() > 1e-4;
        if look != Vec3::ZERO && (eye != nav::eye(&v.nav.cam) || turned) {
            let (cam, pivot) = walk_camera(v.nav, eye, look, m);
            out.push(Command::Camera { cam, pivot });
        }
        out
    }
}

/// The walking camera at `eye` looking along `forward` (its target a few metres ahead), and its pivot; `nav`'s
/// own when that camera is the same or not valid.
fn walk_camera(nav: &Nav, eye: Vec3, forward: Vec3, metres_per_unit: f32) -> (Camera, Vec3) {
    let d = LOOK_DISTANCE_M / metres_per_unit;
    let forward = forward.normalize();
    let world_up = nav.world_up.vector();
    // The up vector orthogonal to the view (nav keeps it so); looking straight up or down, the camera's own.
    let up = if forward.dot(world_up).abs() < 0.99 {
        world_up
    } else {
        nav::cam_up(&nav.cam)
    };
    let cam = nav::set(&nav.cam, eye, eye + forward * d, up);
    if cam != nav.cam && cam.validate().is_ok() {
        (cam, nav::target(&cam))
    } else {
        (nav.cam, nav.pivot)
    }
}
