//! The view cube in the 3D view's top right corner (as FreeCAD, Onshape or xeokit draw it): a cube turned with
//! the camera, so it shows the direction the view looks in, its faces named after the standard views, and a
//! small X/Y/Z triad (red, green, blue). A click on a face gives that standard view (as keys 1/3/7 and Ctrl+…),
//! a click on a corner the isometric view from that corner; the face or corner under the pointer lights up.
//!
//! The cube lives in an `egui::Area` of its own over the view: the layer above takes the pointer, so a click on
//! the cube neither picks nor selects in the scene, and a drag or the wheel over it leaves the camera alone.
//! The geometry (projection, which face or corner lies under a point) is plain functions, tested below.
use egui::{Color32, Pos2, Rect, Sense, Shape, Stroke};
use glam::{Vec2, Vec3};
use hrtao_core::camera::UpAxis;
use hrtao_core::Camera;

use super::command::{Command, ViewState};
use super::input::{self, CameraButton};
use super::nav::{self, StdView};
use super::ui_probe;

/// The cube's square, in egui points, and its distance from the view's top right corner.
const SIZE: f32 = 116.0;
const MARGIN: f32 = 10.0;
/// The height of the background screenshot's overlay in the same corner (ui.rs `shot_overlay`).
const SHOT_OVERLAY: f32 = 90.0;
/// How close to a corner (in the cube's half-sizes, on screen) a point takes the corner rather than a face.
const CORNER_RADIUS: f32 = 0.3;
/// A face seen closer to edge-on than this is not drawn and cannot be clicked.
const EDGE_ON: f32 = 1e-3;

/// The six faces, each named after the standard view that looks at it.
pub const FACES: [StdView; 6] = [
    StdView::Front,
    StdView::Back,
    StdView::Right,
    StdView::Left,
    StdView::Top,
    StdView::Bottom,
];

/// What a point of the cube is: a face (its standard view) or a corner (its signs along the world axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    Face(StdView),
    Corner([i8; 3]),
}

/// The camera's orientation: right, up and forward (the view direction), orthonormal.
#[derive(Clone, Copy, Debug)]
pub struct Axes {
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
}

impl Axes {
    pub fn of(c: &Camera) -> Axes {
        Axes {
            right: nav::right(c),
            up: nav::cam_up(c),
            forward: nav::forward(c),
        }
    }

    /// Where a point of the cube (centre 0, half-size 1, world axes) appears, in half-sizes: x right, y down.
    pub fn project(&self, p: Vec3) -> Vec2 {
        Vec2::new(p.dot(self.right), -p.dot(self.up))
    }

    /// How squarely a face of outward normal `n` faces the viewer: 1 head-on, ≤ 0 turned away.
    pub fn facing(&self, n: Vec3) -> f32 {
        -n.dot(self.forward)
    }
}

pub fn label(v: StdView) -> &'static str {
    match v {
        StdView::Front => "Front",
        StdView::Back => "Back",
        StdView::Right => "Right",
        StdView::Left => "Left",
        StdView::Top => "Top",
        StdView::Bottom => "Bottom",
        StdView::Iso => "Iso",
    }
}

/// The outward normal of the face a standard view looks at (the view looks against it).
pub fn face_normal(v: StdView, up: UpAxis) -> Vec3 {
    -nav::std_view_dirs(v, up).0
}

/// The four corners of the face of outward normal `n` (an axis), in order around it.
pub fn face_corners(n: Vec3) -> [Vec3; 4] {
    let u = if n.x.abs() > 0.5 { Vec3::Y } else { Vec3::X };
    let w = n.cross(u);
    [n + u + w, n - u + w, n - u - w, n + u - w]
}

/// The corner with these signs along the world axes.
pub fn corner_point(s: [i8; 3]) -> Vec3 {
    Vec3::new(s[0] as f32, s[1] as f32, s[2] as f32)
}

/// The eight corners' signs.
fn corners() -> impl Iterator<Item = [i8; 3]> {
    (0..8).map(|i| [1 - 2 * (i & 1), 1 - 2 * ((i >> 1) & 1), 1 - 2 * ((i >> 2) & 1)])
}

/// The faces turned toward the viewer, most squarely facing first.
pub fn visible_faces(a: &Axes, up: UpAxis) -> Vec<StdView> {
    let mut v: Vec<StdView> = FACES
        .into_iter()
        .filter(|&f| a.facing(face_normal(f, up)) > EDGE_ON)
        .collect();
    v.sort_by(|x, y| {
        a.facing(face_normal(*y, up))
            .total_cmp(&a.facing(face_normal(*x, up)))
    });
    v
}

/// A corner is seen when one of its three faces is.
fn corner_visible(a: &Axes, s: [i8; 3]) -> bool {
    let c = corner_point(s);
    [Vec3::X * c.x, Vec3::Y * c.y, Vec3::Z * c.z]
        .into_iter()
        .any(|n| a.facing(n) > EDGE_ON)
}

/// Is `p` inside the convex polygon `poly` (either winding)?
fn inside(poly: &[Vec2], p: Vec2) -> bool {
    let mut sign = 0.0f32;
    for (i, &q) in poly.iter().enumerate() {
        let r = poly[(i + 1) % poly.len()];
        let c = (r - q).perp_dot(p - q);
        if c * sign < 0.0 {
            return false;
        }
        if c != 0.0 {
            sign = c;
        }
    }
    true
}

/// What lies under the point `p` of the projected cube (half-sizes, as `Axes::project`): a seen corner within
/// `CORNER_RADIUS` (the nearest), else the seen face containing it, else nothing.
pub fn hit(a: &Axes, up: UpAxis, p: Vec2) -> Option<Target> {
    let corner = corners()
        .filter(|&s| corner_visible(a, s))
        .map(|s| (a.project(corner_point(s)).distance(p), s))
        .filter(|&(d, _)| d < CORNER_RADIUS)
        .min_by(|x, y| x.0.total_cmp(&y.0));
    if let Some((_, s)) = corner {
        return Some(Target::Corner(s));
    }
    visible_faces(a, up)
        .into_iter()
        .find(|&f| {
            let poly = face_corners(face_normal(f, up)).map(|c| a.project(c));
            inside(&poly, p)
        })
        .map(Target::Face)
}

/// The camera a target asks for: a face's standard view (as its key gives), or the view from a corner toward
/// the scene's centre, framing it, in the current projection (as the isometric view, key 0).
pub fn command(state: &ViewState, target: Target) -> Option<Command> {
    match target {
        Target::Face(v) => input::camera_button(state, CameraButton::View(v)),
        Target::Corner(s) => {
            let b = state.scene?.bounds();
            let centre = b.center();
            let oriented = Camera {
                eye: (centre + corner_point(s).normalize()).to_array(),
                target: centre.to_array(),
                up: state.nav.world_up.vector().to_array(),
                ..state.view_cam()
            };
            let (cam, pivot) = nav::fit(&oriented, b.min, b.max);
            Some(Command::Camera {
                cam: Camera {
                    width: state.nav.cam.width,
                    height: state.nav.cam.height,
                    ..cam
                },
                pivot,
            })
        }
    }
}

fn target_name(t: Target, up: UpAxis) -> String {
    match t {
        Target::Face(v) => label(v).to_string(),
        Target::Corner(s) => {
            let c = corner_point(s);
            let names: Vec<&str> = FACES
                .into_iter()
                .filter(|&f| face_normal(f, up).dot(c) > 0.5)
                .map(label)
                .collect();
            format!("{} corner", names.join("-"))
        }
    }
}

/// The view cube over the 3D view.
#[derive(Default)]
pub struct ViewCube;

impl ViewCube {
    /// Draws the cube in the top right corner of `ui`'s rectangle (the 3D view) and returns the camera a click
    /// asks for.
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let view = ui.max_rect();
        if state.scene.is_none() || view.width() < 2.0 * SIZE || view.height() < 2.0 * SIZE {
            return Vec::new();
        }
        // Below the background screenshot's progress and Cancel, which take the same corner while the panel is
        // hidden.
        let below = if state.shot.is_some() { SHOT_OVERLAY } else { 0.0 };
        let rect = Rect::from_min_size(
            Pos2::new(view.max.x - MARGIN - SIZE, view.min.y + MARGIN + below),
            egui::vec2(SIZE, SIZE),
        );
        ui_probe::note("view cube", rect, ui.ctx().pixels_per_point());
        let axes = Axes::of(&state.nav.cam);
        let up = state.nav.world_up;
        let mut out = Vec::new();
        egui::Area::new(egui::Id::new("view cube"))
            .fixed_pos(rect.min)
            .movable(false)
            .show(ui.ctx(), |ui| {
                let (rect, resp) = ui.allocate_exact_size(rect.size(), Sense::click());
                let centre = rect.center();
                // The cube's silhouette (√3 half-sizes at most) fits the square, clear of the triad.
                let scale = 0.5 * SIZE / 3f32.sqrt() * 0.82;
                let to_cube = |p: Pos2| Vec2::new(p.x - centre.x, p.y - centre.y) / scale;
                let to_screen = |v: Vec2| centre + egui::vec2(v.x, v.y) * scale;
                let hovered = resp.hover_pos().and_then(|p| hit(&axes, up, to_cube(p)));
                draw(ui.painter(), rect, &axes, up, hovered, &to_screen);
                if resp.clicked() {
                    let target = resp
                        .interact_pointer_pos()
                        .and_then(|p| hit(&axes, up, to_cube(p)));
                    if let Some(t) = target {
                        log::info!("view cube: {} view", target_name(t, up));
                        out.extend(command(state, t));
                    }
                }
            });
        out
    }
}

const FACE_FILL: Color32 = Color32::from_rgb(206, 212, 222);
const HOVER_FILL: Color32 = Color32::from_rgb(100, 160, 235);
const EDGE: Color32 = Color32::from_rgb(70, 74, 82);

fn draw(
    painter: &egui::Painter,
    rect: Rect,
    a: &Axes,
    up: UpAxis,
    hovered: Option<Target>,
    to_screen: &dyn Fn(Vec2) -> Pos2,
) {
    let shade = |c: Color32, k: f32| {
        let f = |v: u8| (v as f32 * k).round().clamp(0.0, 255.0) as u8;
        Color32::from_rgb(f(c.r()), f(c.g()), f(c.b()))
    };
    // The seen faces of a convex cube do not overlap: no depth order needed.
    for f in visible_faces(a, up) {
        let n = face_normal(f, up);
        let facing = a.facing(n);
        let mut pts: Vec<Pos2> = face_corners(n).iter().map(|&c| to_screen(a.project(c))).collect();
        // Clockwise on screen (y down), as egui's convex polygons are.
        let area: f32 = (0..4)
            .map(|i| {
                let (p, q) = (pts[i], pts[(i + 1) % 4]);
                p.x * q.y - q.x * p.y
            })
            .sum();
        if area < 0.0 {
            pts.reverse();
        }
        let fill = if hovered == Some(Target::Face(f)) {
            HOVER_FILL
        } else {
            shade(FACE_FILL, 0.72 + 0.28 * facing)
        };
        painter.add(Shape::convex_polygon(pts, fill, Stroke::new(1.0, EDGE)));
        if facing > 0.3 {
            painter.text(
                to_screen(a.project(n)),
                egui::Align2::CENTER_CENTER,
                label(f),
                egui::FontId::proportional(10.0 + 3.0 * facing),
                Color32::from_gray(25),
            );
        }
    }
    for s in corners().filter(|&s| corner_visible(a, s)) {
        let at = to_screen(a.project(corner_point(s)));
        if hovered == Some(Target::Corner(s)) {
            painter.circle_filled(at, 7.0, HOVER_FILL);
        } else {
            painter.circle_filled(at, 2.0, EDGE);
        }
    }
    // The world axes, from the square's bottom left corner.
    let origin = rect.left_bottom() + egui::vec2(13.0, -13.0);
    for (axis, name, color) in [
        (Vec3::X, "X", Color32::from_rgb(220, 50, 50)),
        (Vec3::Y, "Y", Color32::from_rgb(40, 170, 60)),
        (Vec3::Z, "Z", Color32::from_rgb(50, 100, 230)),
    ] {
        let d = a.project(axis);
        let tip = origin + egui::vec2(d.x, d.y) * 11.0;
        painter.line_segment([origin, tip], Stroke::new(2.0, color));
        painter.text(
            origin + egui::vec2(d.x, d.y) * 17.0,
            egui::Align2::CENTER_CENTER,
            name,
            egui::FontId::proportional(10.0),
            color,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The camera of a standard view, as keys 1/3/7 and Ctrl+… give it.
    fn view_axes(v: StdView, up: UpAxis) -> Axes {
        let (cam, _) = nav::std_view(&Camera::default(), v, up, Vec3::splat(-1.0), Vec3::splat(2.0));
        Axes::of(&cam)
    }

    fn looking(dir: Vec3, up: Vec3) -> Axes {
        let c = Camera {
            eye: (-dir).to_array(),
            target: [0.0; 3],
            up: up.to_array(),
            ..Camera::default()
        };
        Axes::of(&c)
    }

    #[test]
    fn a_standard_view_shows_its_face_alone_and_its_centre_hits_it() {
        for up in [UpAxis::Z, UpAxis::Y] {
            for f in FACES {
                let a = view_axes(f, up);
                assert_eq!(visible_faces(&a, up), [f], "{f:?} view, {up:?} up");
                // The face's centre is the middle of the cube's picture.
                let centre = a.project(face_normal(f, up));
                assert!(centre.length() < 1e-5, "{f:?}: {centre}");
                assert_eq!(hit(&a, up, centre), Some(Target::Face(f)), "{f:?}, {up:?}");
                // Halfway to an edge: still the face; outside the square: nothing.
                assert_eq!(hit(&a, up, Vec2::new(0.5, 0.0)), Some(Target::Face(f)));
                assert_eq!(hit(&a, up, Vec2::new(1.2, 0.0)), None);
            }
        }
    }

    /// In the top view the front face is at the bottom of the picture (the view's up is the back), and the top
    /// face's corners are clickable.
    #[test]
    fn the_top_view_has_front_at_the_bottom_and_corners_at_its_corners() {
        let up = UpAxis::Z;
        let a = view_axes(StdView::Top, up);
        let front = a.project(face_normal(StdView::Front, up));
        assert!(front.y > 0.9 && front.x.abs() < 1e-5, "{front}");
        // Screen x is world +X in the top view: the corner at the picture's bottom right is (+X, -Y, +Z).
        assert_eq!(
            hit(&a, up, Vec2::new(0.95, 0.95)),
            Some(Target::Corner([1, -1, 1]))
        );
        assert_eq!(
            hit(&a, up, Vec2::new(-0.95, -0.95)),
            Some(Target::Corner([-1, 1, 1]))
        );
    }

    /// Seen from above and in front, off the diagonals: the three seen faces are hit at their centres, the middle
    /// of the picture is the top face, and the corners behind are not seen.
    #[test]
    fn an_oblique_view_hits_each_seen_face_at_its_centre() {
        let up = UpAxis::Z;
        let a = looking(-Vec3::new(0.3, -0.5, 1.0).normalize(), Vec3::Z);
        let seen = visible_faces(&a, up);
        assert_eq!(seen, [StdView::Top, StdView::Front, StdView::Right]);
        for f in seen {
            let n = face_normal(f, up);
            assert_eq!(hit(&a, up, a.project(n)), Some(Target::Face(f)), "{f:?}");
        }
        assert_eq!(hit(&a, up, Vec2::ZERO), Some(Target::Face(StdView::Top)));
        assert!(!corner_visible(&a, [-1, 1, -1]));
        assert!(corner_visible(&a, [1, -1, 1]));
    }

    /// The isometric view looks at its corner: the corner is the middle of the picture, and clicking it gives the
    /// same view direction as key 0.
    #[test]
    fn the_iso_corner_is_the_middle_of_the_iso_view() {
        for (up, corner) in [(UpAxis::Z, [1, -1, 1]), (UpAxis::Y, [1, 1, 1])] {
            let a = view_axes(StdView::Iso, up);
            assert_eq!(visible_faces(&a, up).len(), 3);
            assert_eq!(hit(&a, up, Vec2::ZERO), Some(Target::Corner(corner)), "{up:?}");
            let (dir, _) = nav::std_view_dirs(StdView::Iso, up);
            assert!((-corner_point(corner).normalize() - dir).length() < 1e-6);
        }
    }

    #[test]
    fn corner_names() {
        assert_eq!(
            target_name(Target::Corner([1, -1, 1]), UpAxis::Z),
            "Front-Right-Top corner"
        );
        assert_eq!(target_name(Target::Face(StdView::Top), UpAxis::Y), "Top");
    }
}
