//! The 3D view's mouse and keyboard: navigation (orbit, pan, zoom, fly, standard views), picking, moving the
//! selection and section planes, and the shortcuts. Input becomes commands (`Command`); the camera moves on a
//! copy of the view's `Nav`, sent once per frame.
use egui::{Key, PointerButton};
use glam::Vec3;
use hrtao_core::camera::Projection;
use hrtao_core::Camera;

use super::command::{Command, PickFor, ViewState};
use super::edits::{Action, Edit};
use super::measure::Measure;
use super::nav::{self, Nav, StdView};
use super::sections::SectionState;

const ORBIT_RAD_PER_PX: f32 = 0.008;
const LOOK_RAD_PER_PX: f32 = 0.004;

/// What the view's input may change besides the camera: the measure mode and the active section plane.
pub struct Tools<'a> {
    pub measure: &'a mut Measure,
    pub sections: &'a mut SectionState,
    pub fullscreen: &'a mut bool,
    /// Walk mode's keys this frame (`walk.rs`).
    pub walk: &'a mut super::walk::WalkInput,
}

/// The camera as input leaves it this frame (one `Command::Camera` if it moved).
struct Moves {
    nav: Nav,
    start: Nav,
}

impl Moves {
    fn new(nav: &Nav) -> Moves {
        Moves {
            nav: *nav,
            start: *nav,
        }
    }

    fn command(&self) -> Option<Command> {
        (self.nav != self.start).then_some(Command::Camera {
            cam: self.nav.cam,
            pivot: self.nav.pivot,
        })
    }
}

/// Mouse input over the 3D view (`rect`, egui points).
pub fn view_input(
    ctx: &egui::Context,
    resp: &egui::Response,
    rect: egui::Rect,
    state: &ViewState,
    tools: &mut Tools,
) -> Vec<Command> {
    let ppp = ctx.pixels_per_point();
    let delta = view_drag_delta(ctx, resp) * ppp;
    // A drag in progress keeps the view "moving" (reduced resolution) even in frames without a new delta;
    // a press whose drag has not moved yet holds the view (`Motion::holds`).
    // egui decides a press is a drag once the pointer has moved past the click distance (or stayed down past
    // the click time): the press is held from the moment the button goes down on the view.
    let acted = delta != egui::Vec2::ZERO;
    let mut out = vec![Command::Drag {
        dragging: resp.dragged() || resp.is_pointer_button_down_on(),
        moved: acted,
    }];
    if state.scene.is_none() {
        return out;
    }
    let mut m = Moves::new(state.nav);
    let (shift, ctrl) = ctx.input(|i| (i.modifiers.shift, i.modifiers.command));
    let world_up = m.nav.world_up.vector();
    let view_h = state.view_rect[3].max(1) as f32;
    // A press that has not moved changes nothing (no section plane or part moved, no camera re-derived).
    if acted {
        let primary = resp.dragged_by(PointerButton::Primary);
        if primary && ctrl && shift {
            out.extend(tools.sections.drag(&m.nav.cam, delta, view_h));
        } else if primary && ctrl && !state.selection.instances.is_empty() {
            out.extend(drag_move(state, delta));
        } else if resp.dragged_by(PointerButton::Middle) || (primary && shift) {
            // Pan moves the pivot with the view.
            let wpp = nav::world_per_pixel(&m.nav.cam, view_h);
            let d = (-delta.x * nav::right(&m.nav.cam) + delta.y * nav::cam_up(&m.nav.cam)) * wpp;
            m.nav.pivot += d;
            m.nav.cam = nav::pan(&m.nav.cam, delta.x, delta.y, view_h);
        } else if resp.dragged_by(PointerButton::Secondary) || (primary && state.walking) {
            // Look around (walking: the left drag too; the body turns with the view).
            m.nav.cam = nav::fly_look(
                &m.nav.cam,
                world_up,
                -delta.x * LOOK_RAD_PER_PX,
                -delta.y * LOOK_RAD_PER_PX,
            );
            m.nav.pivot = nav::target(&m.nav.cam);
        } else if primary {
            m.nav.cam = nav::orbit(
                &m.nav.cam,
                m.nav.pivot,
                world_up,
                -delta.x * ORBIT_RAD_PER_PX,
                -delta.y * ORBIT_RAD_PER_PX,
            );
        }
    }
    let scroll = wheel_points(ctx);
    if resp.hovered() && scroll != 0.0 {
        if let Some(pos) = resp.hover_pos() {
            let cam = Camera {
                width: state.view_rect[2].max(1) as u32,
                height: state.view_rect[3].max(1) as u32,
                ..m.nav.cam
            };
            let (x, y) = ((pos.x - rect.min.x) * ppp, (pos.y - rect.min.y) * ppp);
            let factor = (-scroll * 0.0025).exp();
            m.nav.cam = nav::zoom_to(&m.nav.cam, cam.ray(x - 0.5, y - 0.5), factor);
        }
    }
    out.extend(m.command());
    let at = |p: egui::Pos2| {
        [
            (p.x - rect.min.x) / rect.width().max(1e-6),
            (p.y - rect.min.y) / rect.height().max(1e-6),
        ]
    };
    let purpose = if resp.double_clicked() {
        Some(PickFor::Pivot)
    } else if resp.clicked() && tools.measure.active {
        Some(PickFor::Measure)
    } else if resp.clicked() {
        Some(if super::selection::click_toggles(ctx) {
            PickFor::Toggle
        } else {
            PickFor::Select
        })
    } else {
        None
    };
    if let (Some(purpose), Some(p)) = (purpose, resp.interact_pointer_pos()) {
        out.push(Command::Pick { at: at(p), purpose });
    }
    out
}

/// Ctrl+drag: move the selection along the world axis whose screen projection best matches the drag.
fn drag_move(state: &ViewState, delta: egui::Vec2) -> Option<Command> {
    let c = state.nav.cam;
    let (r, u) = (nav::right(&c), nav::cam_up(&c));
    let drag = glam::Vec2::new(delta.x, -delta.y);
    let mut best = (0.0f32, Vec3::X, glam::Vec2::X);
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        let s = glam::Vec2::new(axis.dot(r), axis.dot(u));
        if s.length() < 0.2 {
            continue;
        }
        let score = s.normalize().dot(drag.normalize()).abs();
        if score > best.0 {
            best = (score, axis, s);
        }
    }
    let (_, axis, s) = best;
    let wpp = nav::world_per_pixel(&c, state.view_rect[3].max(1) as f32);
    let amount = drag.dot(s.normalize()) * wpp / s.length();
    move_selection(state, axis * amount)
}

/// Moves the selection by a world offset (one edit for all selected instances: drags merge in undo).
pub fn move_selection(state: &ViewState, d: Vec3) -> Option<Command> {
    let scene = state.scene?;
    Edit::move_all(scene, &state.selection.instances, d).map(|e| Command::Edit(Action::Apply(e)))
}

/// Fits the camera to a box, keeping the view direction.
fn fit_box(m: &mut Moves, state: &ViewState, b: hrtao_scene::Aabb) {
    let (c, p) = nav::fit(&state.view_cam(), b.min, b.max);
    m.nav.cam = Camera {
        width: m.nav.cam.width,
        height: m.nav.cam.height,
        ..c
    };
    m.nav.pivot = p;
}

/// F with a selection: the selected instances' bounds; else (or when they are empty) the whole scene.
fn frame_selection(m: &mut Moves, state: &ViewState, scene: &hrtao_scene::Scene) {
    let b = state
        .selection
        .instances
        .iter()
        .map(|&i| scene.instance_bounds(i))
        .fold(hrtao_scene::Aabb::empty(), |a, b| a.union(&b));
    if b.is_empty() {
        return fit_box(m, state, scene.bounds());
    }
    log::info!(
        "framed the selection: {} instances, centre {:?}",
        state.selection.instances.len(),
        b.center().to_array()
    );
    fit_box(m, state, b);
}

fn std_view(m: &mut Moves, state: &ViewState, scene: &hrtao_scene::Scene, v: StdView) {
    let b = scene.bounds();
    let (c, p) = nav::std_view(&state.view_cam(), v, m.nav.world_up, b.min, b.max);
    m.nav.cam = Camera {
        width: m.nav.cam.width,
        height: m.nav.cam.height,
        ..c
    };
    m.nav.pivot = p;
}

/// Perspective / orthographic, keeping the framing at the pivot.
pub fn toggled_projection(nav: &Nav) -> Camera {
    let next = match nav.cam.projection {
        Projection::Perspective => Projection::Orthographic,
        Projection::Orthographic => Projection::Perspective,
    };
    let cam = nav::set_projection(&nav.cam, nav.pivot, next);
    log::info!(
        "projection: {next:?} (view height at the pivot {:.4})",
        nav::world_per_pixel(&cam, 1.0)
    );
    cam
}

/// A camera command for the panel's camera buttons.
pub fn camera_button(state: &ViewState, button: CameraButton) -> Option<Command> {
    let scene = state.scene?;
    let mut m = Moves::new(state.nav);
    match button {
        CameraButton::Fit => fit_box(&mut m, state, scene.bounds()),
        CameraButton::View(v) => std_view(&mut m, state, scene, v),
        CameraButton::Reset => {
            m.nav.cam = state.home;
            m.nav.pivot = nav::target(&state.home);
        }
    }
    m.command()
}

#[derive(Clone, Copy)]
pub enum CameraButton {
    Fit,
    View(StdView),
    Reset,
}

/// The wheel's vertical turn this frame in points, as it came (not eased over later frames as egui's scroll
/// delta is): a wheel notch zooms the view at once. A line counts 50 points.
fn wheel_points(ctx: &egui::Context) -> f32 {
    const POINTS_PER_LINE: f32 = 50.0;
    ctx.input(|i| {
        i.raw
            .events
            .iter()
            .map(|e| match e {
                egui::Event::MouseWheel { unit, delta, .. } => match unit {
                    egui::MouseWheelUnit::Point => delta.y,
                    egui::MouseWheelUnit::Line => delta.y * POINTS_PER_LINE,
                    egui::MouseWheelUnit::Page => delta.y * i.viewport_rect().height(),
                },
                _ => 0.0,
            })
            .sum()
    })
}

/// Is the user typing into a text field (then letters are text, not shortcuts)?
fn typing(ctx: &egui::Context) -> bool {
    ctx.memory(|m| m.focused())
        .is_some_and(|id| egui::TextEdit::load_state(ctx, id).is_some())
}

/// The shortcuts and fly keys (not while typing into a text field).
pub fn keyboard(ctx: &egui::Context, state: &ViewState, tools: &mut Tools) -> Vec<Command> {
    *tools.walk = super::walk::WalkInput::default();
    if typing(ctx) {
        return Vec::new();
    }
    let (pressed, down, mods, dt) = ctx.input(|i| {
        let keys = [
            Key::F,
            Key::Home,
            Key::Num1,
            Key::Num3,
            Key::Num7,
            Key::Num9,
            Key::Num0,
            Key::Num5,
            Key::F11,
            Key::Q,
            Key::Enter,
            Key::Delete,
            Key::H,
            Key::I,
            Key::U,
            Key::M,
            Key::Escape,
            Key::Z,
            Key::Y,
            Key::O,
            Key::R,
            Key::F5,
            Key::ArrowLeft,
            Key::ArrowRight,
            Key::ArrowUp,
            Key::ArrowDown,
            Key::PageUp,
            Key::PageDown,
            Key::G,
        ];
        // Each key with the modifiers held when it was pressed (a quick Ctrl+Z can press and release Ctrl
        // within one frame's events).
        let held = |k: Key| {
            i.events
                .iter()
                .rev()
                .find_map(|e| match e {
                    egui::Event::Key {
                        key,
                        pressed: true,
                        modifiers,
                        ..
                    } if *key == k => Some(*modifiers),
                    _ => None,
                })
                .unwrap_or(i.modifiers)
        };
        let pressed: Vec<(Key, egui::Modifiers)> = keys
            .into_iter()
            .filter(|k| i.key_pressed(*k))
            .map(|k| (k, held(k)))
            .collect();
        // Fly keys, not while Ctrl is held (Ctrl+Q quits, Ctrl+S…).
        let down: Vec<Key> = [Key::W, Key::A, Key::S, Key::D, Key::Q, Key::E]
            .into_iter()
            .filter(|k| i.key_down(*k) && !i.modifiers.command)
            .collect();
        (pressed, down, i.modifiers, i.stable_dt.min(0.25))
    });
    let mut out = Vec::new();
    let mut m = Moves::new(state.nav);
    let selected = !state.selection.instances.is_empty();
    for (k, mods) in pressed {
        // Keys that act without a scene.
        match k {
            Key::F11 => {
                *tools.fullscreen = !*tools.fullscreen;
                out.push(Command::Fullscreen(*tools.fullscreen));
                continue;
            }
            Key::Q if mods.command => {
                out.push(Command::Quit);
                continue;
            }
            Key::O if mods.command => {
                out.push(Command::OpenDialog);
                continue;
            }
            Key::F5 => {
                out.push(Command::Reload);
                continue;
            }
            Key::R if mods.command => {
                out.push(Command::Reload);
                continue;
            }
            Key::Escape if state.shot.as_ref().is_some_and(|s| s.2) => {
                out.push(Command::CancelScreenshot(" (Esc)"));
                continue;
            }
            Key::Escape if state.walking => {
                out.push(Command::Walk(false));
                continue;
            }
            Key::Escape if state.in_plan.is_some() => {
                out.push(Command::Plan(None));
                continue;
            }
            Key::G if !mods.command => {
                out.push(Command::Walk(!state.walking));
                continue;
            }
            Key::Escape if tools.measure.active => {
                tools.measure.points.clear();
                continue;
            }
            Key::Escape => {
                out.push(Command::SelectInstance(u32::MAX));
                continue;
            }
            Key::M => {
                tools.measure.active = !tools.measure.active;
                let on = if tools.measure.active { "on" } else { "off" };
                log::info!("measure mode {on}");
                continue;
            }
            Key::Z if mods.command && mods.shift => {
                out.push(Command::Edit(Action::Redo));
                continue;
            }
            Key::Z if mods.command => {
                out.push(Command::Edit(Action::Undo));
                continue;
            }
            Key::Y if mods.command => {
                out.push(Command::Edit(Action::Redo));
                continue;
            }
            Key::Delete => {
                out.push(Command::DeleteSelection);
                continue;
            }
            _ => {}
        }
        let Some(scene) = state.scene else {
            continue;
        };
        match k {
            Key::F if selected => frame_selection(&mut m, state, scene),
            Key::F | Key::Home => fit_box(&mut m, state, scene.bounds()),
            Key::Num1 if mods.command => std_view(&mut m, state, scene, StdView::Back),
            Key::Num3 if mods.command => std_view(&mut m, state, scene, StdView::Left),
            Key::Num7 if mods.command => std_view(&mut m, state, scene, StdView::Bottom),
            Key::Num1 => std_view(&mut m, state, scene, StdView::Front),
            Key::Num3 => std_view(&mut m, state, scene, StdView::Right),
            Key::Num7 => std_view(&mut m, state, scene, StdView::Top),
            Key::Num9 => m.nav.cam = nav::opposite(&m.nav.cam, m.nav.pivot),
            Key::Num0 => std_view(&mut m, state, scene, StdView::Iso),
            Key::Num5 => m.nav.cam = toggled_projection(&m.nav),
            Key::Enter => {
                m.nav.cam = state.home;
                m.nav.pivot = nav::target(&state.home);
            }
            Key::H | Key::I | Key::U => {
                let edit = match k {
                    Key::H => super::tree::hide_selection_edit(scene, state.selection),
                    Key::I => super::tree::isolate_edit(scene, state.selection),
                    _ => super::tree::show_all(scene),
                };
                out.extend(edit.map(|e| Command::Edit(Action::Apply(e))));
            }
            Key::ArrowLeft
            | Key::ArrowRight
            | Key::ArrowUp
            | Key::ArrowDown
            | Key::PageUp
            | Key::PageDown
                if selected =>
            {
                let step = state.move_step() * if mods.shift { 10.0 } else { 1.0 };
                let c = m.nav.cam;
                let dir = match k {
                    Key::ArrowLeft => -nav::right(&c),
                    Key::ArrowRight => nav::right(&c),
                    Key::ArrowUp => nav::cam_up(&c),
                    Key::ArrowDown => -nav::cam_up(&c),
                    Key::PageUp => nav::forward(&c),
                    _ => -nav::forward(&c),
                };
                out.extend(move_selection(state, dominant_axis(dir) * step));
            }
            _ => {}
        }
    }
    // Walking: the keys move the body (walk.rs steps it at walking speed); Q/E do nothing.
    if state.walking {
        for k in &down {
            match k {
                Key::W => tools.walk.forward += 1.0,
                Key::S => tools.walk.forward -= 1.0,
                Key::A => tools.walk.right -= 1.0,
                Key::D => tools.walk.right += 1.0,
                _ => {}
            }
        }
        tools.walk.run = mods.shift;
        if *tools.walk != super::walk::WalkInput::default() {
            out.push(Command::Drag {
                dragging: true,
                moved: true,
            });
        }
    } else if !down.is_empty() && state.scene.is_some() {
        out.push(Command::Drag {
            dragging: true,
            moved: true,
        });
        let speed = state.move_step() * 25.0 * if mods.shift { 4.0 } else { 1.0 } * dt;
        let mut local = Vec3::ZERO;
        for k in down {
            match k {
                Key::W => local.z += 1.0,
                Key::S => local.z -= 1.0,
                Key::A => local.x -= 1.0,
                Key::D => local.x += 1.0,
                Key::Q => local.y -= 1.0,
                _ => local.y += 1.0,
            }
        }
        m.nav.cam = nav::fly_move(&m.nav.cam, local * speed);
        m.nav.pivot = nav::target(&m.nav.cam);
    }
    out.extend(m.command());
    out
}

/// The signed world axis closest to `v`.
fn dominant_axis(v: Vec3) -> Vec3 {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        Vec3::X * v.x.signum()
    } else if a.y >= a.z {
        Vec3::Y * v.y.signum()
    } else {
        Vec3::Z * v.z.signum()
    }
}

/// The pointer's motion that a drag of the view answers this frame, in points. egui's `drag_delta` is the
/// pointer's whole motion since the previous frame, so on the frame a drag starts it also holds the motion before
/// the press (a hover and a press that a busy frame delivers together): the view would jump by a motion made with
/// no button down. A drag moves the view by the motion since its press, and from then on by each frame's.
fn view_drag_delta(ctx: &egui::Context, resp: &egui::Response) -> egui::Vec2 {
    if !resp.dragged() {
        return egui::Vec2::ZERO;
    }
    if resp.drag_started() {
        return ctx
            .input(|i| Some(i.pointer.latest_pos()? - i.pointer.press_origin()?))
            .unwrap_or_default();
    }
    resp.drag_delta()
}

#[cfg(test)]
mod tests {
    /// One frame of a bare egui context with a drag-sensing area over the whole screen, fed `events`: the drag
    /// delta the view answers.
    fn drag_frame(ctx: &egui::Context, events: Vec<egui::Event>) -> egui::Vec2 {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(400.0, 300.0),
            )),
            events,
            ..Default::default()
        };
        let mut delta = egui::Vec2::ZERO;
        // No painting here: the frame's texture changes are dropped on purpose.
        ctx.run_ui(input, |root| {
            egui::CentralPanel::default().show(root, |ui| {
                let rect = ui.max_rect();
                let resp = ui.allocate_rect(rect, egui::Sense::click_and_drag());
                delta = super::view_drag_delta(ui.ctx(), &resp);
            });
        })
        .drop_without_applying_deltas();
        delta
    }

    /// A hover and a press that arrive in one frame do not move the view by the hover's motion (egui's own
    /// `drag_delta` gives the hover's 40 points there); the motion after the press does, from the press on,
    /// including the part of it that came in the press's frame, once.
    #[test]
    fn a_drag_moves_the_view_by_the_motion_after_its_press() {
        use egui::{Event, PointerButton, Pos2};
        let press = |p: Pos2, pressed| Event::PointerButton {
            pos: p,
            button: PointerButton::Primary,
            pressed,
            modifiers: Default::default(),
        };
        let ctx = egui::Context::default();
        let (a, b) = (Pos2::new(100.0, 100.0), Pos2::new(140.0, 100.0));
        assert_eq!(drag_frame(&ctx, vec![Event::PointerMoved(a)]), egui::Vec2::ZERO);
        let d = drag_frame(&ctx, vec![Event::PointerMoved(b), press(b, true)]);
        assert_eq!(d, egui::Vec2::ZERO, "the hover's motion moved the view");
        let d = drag_frame(&ctx, vec![Event::PointerMoved(Pos2::new(150.0, 104.0))]);
        assert_eq!(d, egui::vec2(10.0, 4.0));
        // A press and motion after it in one frame: the motion since the press.
        let _ = drag_frame(&ctx, vec![press(Pos2::new(150.0, 104.0), false)]);
        let c = Pos2::new(200.0, 200.0);
        let d = drag_frame(
            &ctx,
            vec![
                Event::PointerMoved(c),
                press(c, true),
                Event::PointerMoved(Pos2::new(207.0, 195.0)),
            ],
        );
        // egui 0.36 decides the drag once the motion passes the click distance, which it may do a frame later:
        // the motion since the press is then answered whole, once.
        let later = drag_frame(&ctx, Vec::new());
        assert_eq!(d + later, egui::vec2(7.0, -5.0));
    }

    #[test]
    fn axes() {
        assert_eq!(
            super::dominant_axis(glam::Vec3::new(0.2, -0.9, 0.1)),
            -glam::Vec3::Y
        );
    }
}
