//! CAD camera navigation as pure functions on [`Camera`] (no GPU): orbit around a pivot, pan, zoom toward the
//! cursor, fly, fit all and the standard views (F3D's 1/3/7/9 keys), in perspective or orthographic projection
//! (switched keeping the framing; front/right/top views are orthographic, as in CAD tools).
//!
//! The camera's `up` is always kept as the true camera up vector (orthogonal to the view direction), so views
//! looking straight down an axis stay valid; orbiting yaws around the scene's world up axis.
use glam::{Quat, Vec3};
use hrtao_core::camera::{Projection, UpAxis};
use hrtao_core::Camera;

/// The camera plus the point it orbits around.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nav {
    pub cam: Camera,
    pub pivot: Vec3,
    pub world_up: UpAxis,
}

/// Standard views (F3D numpad conventions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StdView {
    Front,
    Back,
    Right,
    Left,
    Top,
    Bottom,
    Iso,
}

pub fn eye(c: &Camera) -> Vec3 {
    Vec3::from(c.eye)
}
pub fn target(c: &Camera) -> Vec3 {
    Vec3::from(c.target)
}
pub fn forward(c: &Camera) -> Vec3 {
    (target(c) - eye(c)).normalize()
}
pub fn right(c: &Camera) -> Vec3 {
    forward(c).cross(Vec3::from(c.up)).normalize()
}
/// The orthogonalised camera up vector.
pub fn cam_up(c: &Camera) -> Vec3 {
    right(c).cross(forward(c)).normalize()
}
pub fn distance(c: &Camera) -> f32 {
    (target(c) - eye(c)).length()
}

/// `c` looking from `eye` at `target`, its up vector `up` made orthogonal to the view.
pub fn set(c: &Camera, eye: Vec3, target: Vec3, up: Vec3) -> Camera {
    let fwd = (target - eye).normalize();
    let r = fwd.cross(up).normalize();
    let up = r.cross(fwd).normalize();
    Camera {
        eye: eye.to_array(),
        target: target.to_array(),
        up: up.to_array(),
        ..*c
    }
}

/// Orbit by `yaw` radians around the world up axis through `pivot`, then `pitch` radians around the camera's
/// right axis through `pivot`. Distances to the pivot are preserved.
pub fn orbit(c: &Camera, pivot: Vec3, world_up: Vec3, yaw: f32, pitch: f32) -> Camera {
    // Nothing to do: the same camera, not one re-derived to its last bits (a new view for the renderer).
    if yaw == 0.0 && pitch == 0.0 {
        return *c;
    }
    let q = Quat::from_axis_angle(right(c), pitch);
    let q = Quat::from_axis_angle(world_up.normalize(), yaw) * q;
    let e = pivot + q * (eye(c) - pivot);
    let t = pivot + q * (target(c) - pivot);
    set(c, e, t, q * cam_up(c))
}

/// World units per pixel at the target distance (at any distance in orthographic) for an image `height` pixels
/// tall.
pub fn world_per_pixel(c: &Camera, height: f32) -> f32 {
    c.view_height_at(distance(c)) / height.max(1.0)
}

/// Pan so that content under the cursor follows a drag of (`dx`, `dy`) pixels (x right, y down) in a view
/// `height` pixels tall.
pub fn pan(c: &Camera, dx: f32, dy: f32, height: f32) -> Camera {
    if dx == 0.0 && dy == 0.0 {
        return *c;
    }
    let s = world_per_pixel(c, height);
    let delta = (-dx * right(c) + dy * cam_up(c)) * s;
    set(c, eye(c) + delta, target(c) + delta, cam_up(c))
}

/// Zoom toward the point under the cursor, where the cursor ray (`origin`, unit `dir`: `Camera::ray`) meets the
/// target plane, by `factor` (< 1 zooms in); that point stays under the cursor. Perspective: eye and target
/// scale about it. Orthographic: `ortho_height` scales by `factor` and the view shifts sideways (the eye keeps
/// its depth).
pub fn zoom_to(c: &Camera, (origin, dir): (Vec3, Vec3), factor: f32) -> Camera {
    let f = forward(c);
    let cos = dir.dot(f).max(1e-3);
    let p = origin + dir * ((target(c) - origin).dot(f) / cos);
    match c.projection {
        Projection::Perspective => zoom_about(c, p, factor),
        Projection::Orthographic => {
            let factor = factor.clamp(1e-3, 1e3);
            let shift = (p - target(c)) * (1.0 - factor);
            Camera {
                ortho_height: (c.ortho_height * factor).clamp(1e-9, 1e30),
                ..set(c, eye(c) + shift, target(c) + shift, cam_up(c))
            }
        }
    }
}

/// Scales eye and target about `p` by `factor` (the view direction is unchanged).
pub fn zoom_about(c: &Camera, p: Vec3, factor: f32) -> Camera {
    let factor = factor.clamp(1e-3, 1e3);
    let e = p + (eye(c) - p) * factor;
    let t = p + (target(c) - p) * factor;
    set(c, e, t, cam_up(c))
}

/// Fly: move eye and target by `local` = (right, up, forward) in world units.
pub fn fly_move(c: &Camera, local: Vec3) -> Camera {
    let d = right(c) * local.x + cam_up(c) * local.y + forward(c) * local.z;
    set(c, eye(c) + d, target(c) + d, cam_up(c))
}

/// Fly: turn the view direction around the eye (yaw around world up, pitch around the right axis).
pub fn fly_look(c: &Camera, world_up: Vec3, yaw: f32, pitch: f32) -> Camera {
    if yaw == 0.0 && pitch == 0.0 {
        return *c;
    }
    let q = Quat::from_axis_angle(world_up.normalize(), yaw) * Quat::from_axis_angle(right(c), pitch);
    let e = eye(c);
    set(c, e, e + q * (target(c) - e), q * cam_up(c))
}

/// Distance at which a sphere of `radius` fills the smaller of the view's angular extents.
pub fn fit_distance(c: &Camera, radius: f32) -> f32 {
    let aspect = c.width as f32 / c.height.max(1) as f32;
    let half_v = (c.fov_y_deg.to_radians() * 0.5).tan();
    let half = half_v.min(half_v * aspect).atan();
    radius.max(1e-6) / half.sin()
}

/// Keeps the view direction and the projection and frames the box `min..max`; returns the camera and the new
/// pivot (the centre). Orthographic: the bounding sphere fills the smaller image extent, and the eye stands
/// where the perspective fit would put it (so switching back to perspective frames the box too).
pub fn fit(c: &Camera, min: Vec3, max: Vec3) -> (Camera, Vec3) {
    let centre = (min + max) * 0.5;
    let radius = (max - min).length() * 0.5;
    let d = fit_distance(c, radius);
    let mut cam = set(c, centre - forward(c) * d, centre, cam_up(c));
    let aspect = c.width as f32 / c.height.max(1) as f32;
    cam.ortho_height = 2.0 * radius.max(1e-6) / aspect.min(1.0);
    (cam, centre)
}

/// Switches the projection keeping the framing at the pivot: the orthographic height is the perspective view
/// height at the pivot's depth, and back, the eye moves along the view direction until the pivot's depth
/// shows that height again (the target follows at the pivot's depth).
pub fn set_projection(c: &Camera, pivot: Vec3, projection: Projection) -> Camera {
    if c.projection == projection {
        return *c;
    }
    let f = forward(c);
    let depth = (pivot - eye(c)).dot(f).max(distance(c) * 1e-3).max(1e-6);
    // The target moves to the pivot's depth; `Camera::with_projection` keeps the framing of the target plane.
    set(c, eye(c), eye(c) + f * depth, cam_up(c)).with_projection(projection)
}

/// View direction (eye → target) and up vector of a standard view, in the up axis's frame (e1, e2, up): the
/// front view looks along e2 (+Y for a Z-up model, −Z for a Y-up one), the right view along −e1, the top view
/// down with e2 at the top of the image, the iso view from (+e1, −e2, +up).
pub fn std_view_dirs(view: StdView, up: UpAxis) -> (Vec3, Vec3) {
    let [e1, e2, u] = up.frame().map(|v| v.as_vec3());
    match view {
        StdView::Front => (e2, u),
        StdView::Back => (-e2, u),
        StdView::Right => (-e1, u),
        StdView::Left => (e1, u),
        StdView::Top => (-u, e2),
        StdView::Bottom => (u, -e2),
        StdView::Iso => ((-e1 + e2 - u).normalize(), u),
    }
}

/// The view from the other side of the pivot (Blender's "opposite view", key 9): the eye mirrored through the
/// pivot, looking back along the reversed direction, with the same up vector, distance and projection.
pub fn opposite(c: &Camera, pivot: Vec3) -> Camera {
    set(c, 2.0 * pivot - eye(c), 2.0 * pivot - target(c), cam_up(c))
}

/// A standard view framing the box `min..max`; returns the camera and pivot. The six axis views are
/// orthographic (as in CAD tools); the iso view keeps the current projection.
pub fn std_view(c: &Camera, view: StdView, up: UpAxis, min: Vec3, max: Vec3) -> (Camera, Vec3) {
    let (dir, upv) = std_view_dirs(view, up);
    let centre = (min + max) * 0.5;
    let mut oriented = set(c, centre - dir, centre, upv);
    if view != StdView::Iso {
        oriented.projection = Projection::Orthographic;
    }
    fit(&oriented, min, max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A drag that has not moved (a press: egui reports the drag from it) leaves the camera bit for bit: a camera
    /// that differs in its last bits is a new view, which would start a frame the drag's motion waits for.
    #[test]
    fn a_drag_of_nothing_leaves_the_camera_bit_for_bit() {
        let mut c = Camera {
            eye: [102.04, -127.6, 128.04],
            target: [3.1, 2.7, -0.4],
            up: [0.0, 0.0, 1.0],
            ..Camera::default()
        };
        let (pivot, up) = (Vec3::new(1.3, -0.7, 5.9), Vec3::Z);
        let mut changed = 0;
        for k in 0..50 {
            // A camera that orbits and pans have re-derived, as the view has after any navigation.
            c = pan(&orbit(&c, pivot, up, 0.013 * k as f32, -0.007), 3.0, -1.0, 800.0);
            for (name, d) in [
                ("orbit", orbit(&c, pivot, up, 0.0, 0.0)),
                ("pan", pan(&c, 0.0, 0.0, 800.0)),
                ("look", fly_look(&c, up, 0.0, 0.0)),
            ] {
                changed += (d != c) as u32;
                assert_eq!(d, c, "{name} by nothing after {k} steps");
            }
        }
        assert_eq!(changed, 0);
    }

    #[test]
    fn opposite_views_look_back_through_the_pivot() {
        let (min, max) = (Vec3::new(-1.0, -2.0, 0.0), Vec3::new(3.0, 2.0, 1.0));
        for up in [UpAxis::Y, UpAxis::Z] {
            for (a, b) in [
                (StdView::Front, StdView::Back),
                (StdView::Right, StdView::Left),
                (StdView::Top, StdView::Bottom),
            ] {
                let (da, _) = std_view_dirs(a, up);
                let (db, _) = std_view_dirs(b, up);
                assert!(close(da, -db), "{a:?}/{b:?}");
                let (ca, pivot) = std_view(&cam(), a, up, min, max);
                let (cb, _) = std_view(&cam(), b, up, min, max);
                let o = opposite(&ca, pivot);
                assert!(close(forward(&o), forward(&cb)), "{a:?} -> {b:?}");
                assert!((distance(&o) - distance(&ca)).abs() < 1e-4);
                assert!(close(nav_pivot_dist(&o, pivot), nav_pivot_dist(&ca, pivot)));
                let back = opposite(&o, pivot);
                assert!(close(eye(&back), eye(&ca)) && close(target(&back), target(&ca)));
            }
        }
    }

    /// The pivot's distance from the eye, as a vector for `close`.
    fn nav_pivot_dist(c: &Camera, pivot: Vec3) -> Vec3 {
        Vec3::splat((pivot - eye(c)).length())
    }

    fn cam() -> Camera {
        Camera {
            eye: [0.0, -10.0, 0.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 0.0, 1.0],
            fov_y_deg: 60.0,
            width: 200,
            height: 100,
            ..Default::default()
        }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn orbit_keeps_distance_to_pivot_and_turns() {
        let c = cam();
        let pivot = Vec3::new(1.0, 0.0, 0.0);
        let d0 = (eye(&c) - pivot).length();
        let o = orbit(&c, pivot, Vec3::Z, std::f32::consts::FRAC_PI_2, 0.0);
        assert!(((eye(&o) - pivot).length() - d0).abs() < 1e-4);
        // A quarter turn around +Z moves the eye from -Y to +X of the pivot.
        assert!(close(eye(&o) - pivot, Vec3::new(10.0, -1.0, 0.0)));
        // Pitch up over the top stays valid (up is kept orthogonal) and preserves the distance.
        let p = orbit(&c, Vec3::ZERO, Vec3::Z, 0.0, std::f32::consts::FRAC_PI_2);
        assert!(p.validate().is_ok(), "{p:?}");
        assert!((distance(&p) - 10.0).abs() < 1e-4);
        assert!(forward(&p).z.abs() > 0.999, "looking straight down or up");
        // Full turn returns to the start.
        let mut r = c;
        for _ in 0..8 {
            r = orbit(&r, pivot, Vec3::Z, std::f32::consts::FRAC_PI_4, 0.0);
        }
        assert!(close(eye(&r), eye(&c)) && close(target(&r), target(&c)));
    }

    #[test]
    fn pan_moves_eye_and_target_together_by_pixel_scale() {
        let c = cam();
        let p = pan(&c, 50.0, 0.0, 100.0);
        let wpp = world_per_pixel(&c, 100.0);
        assert!(close(eye(&p) - eye(&c), target(&p) - target(&c)));
        // Dragging right moves the camera left (content follows the cursor).
        assert!(close(target(&p), Vec3::new(-50.0 * wpp, 0.0, 0.0)));
        let p = pan(&c, 0.0, 10.0, 100.0);
        assert!(target(&p).z > 0.0, "dragging down moves the camera up");
        assert!(close(forward(&p), forward(&c)));
    }

    #[test]
    fn zoom_toward_cursor_keeps_the_cursor_point_fixed() {
        let c = cam();
        // A ray to the right of centre: pixel (150, 50).
        let dir = c.ray_dir(150.0, 50.0);
        let z = zoom_to(&c, c.ray(150.0, 50.0), 0.5);
        assert!((distance(&z) - 5.0).abs() < 1e-4, "distance halves");
        assert!(close(forward(&z), forward(&c)));
        // The point under the cursor on the target plane projects to the same pixel.
        let p = eye(&c) + dir * (distance(&c) / dir.dot(forward(&c)));
        let d2 = (p - eye(&z)).normalize();
        assert!(
            close(d2, z.ray_dir(150.0, 50.0)),
            "{d2} vs {}",
            z.ray_dir(150.0, 50.0)
        );
        // Zoom at the centre moves straight along the view direction.
        let zc = zoom_to(&c, (eye(&c), forward(&c)), 2.0);
        assert!(close(target(&zc), target(&c)));
        assert!((distance(&zc) - 20.0).abs() < 1e-3);
    }

    #[test]
    fn fit_frames_the_box_and_keeps_direction() {
        let c = cam();
        let (f, pivot) = fit(&c, Vec3::new(10.0, 10.0, 10.0), Vec3::new(12.0, 12.0, 12.0));
        assert!(close(pivot, Vec3::splat(11.0)));
        assert!(close(target(&f), pivot));
        assert!(close(forward(&f), forward(&c)));
        let r = 3f32.sqrt();
        // The bounding sphere touches the vertical field of view (aspect 2: vertical is the limit).
        let half = (30f32).to_radians();
        assert!((distance(&f) - r / half.sin()).abs() < 1e-3);
        // Every box corner is in front of the camera and inside the frustum.
        for corner in [Vec3::splat(10.0), Vec3::splat(12.0), Vec3::new(10.0, 12.0, 10.0)] {
            let v = corner - eye(&f);
            let z = v.dot(forward(&f));
            assert!(z > 0.0);
            assert!((v.dot(cam_up(&f)) / z).abs() <= half.tan() + 1e-4);
        }
    }

    #[test]
    fn standard_views_look_along_axes() {
        let c = cam();
        let (min, max) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let (top, _) = std_view(&c, StdView::Top, UpAxis::Z, min, max);
        assert!(top.validate().is_ok());
        assert!(close(forward(&top), -Vec3::Z));
        let (front, _) = std_view(&c, StdView::Front, UpAxis::Z, min, max);
        assert!(close(forward(&front), Vec3::Y) && close(cam_up(&front), Vec3::Z));
        let (right_v, _) = std_view(&c, StdView::Right, UpAxis::Y, min, max);
        assert!(close(forward(&right_v), -Vec3::X) && close(cam_up(&right_v), Vec3::Y));
        let (iso, pivot) = std_view(&c, StdView::Iso, UpAxis::Y, min, max);
        assert!(close(pivot, Vec3::ZERO));
        let f = forward(&iso);
        assert!((f.x - f.y).abs() < 1e-5 && (f.y - f.z).abs() < 1e-5);
        for v in [StdView::Front, StdView::Right, StdView::Top, StdView::Iso] {
            for up in [UpAxis::Y, UpAxis::Z] {
                assert!(std_view(&c, v, up, min, max).0.validate().is_ok());
            }
        }
    }

    fn ortho() -> Camera {
        Camera {
            projection: Projection::Orthographic,
            ortho_height: 6.0,
            ..cam()
        }
    }

    /// Image coordinates in [-1, 1] (x right, y up) of world point `p`, and its depth in front of the eye.
    fn project(c: &Camera, p: Vec3) -> (f32, f32, f32) {
        let v = p - eye(c);
        let depth = v.dot(forward(c));
        let aspect = c.width as f32 / c.height as f32;
        let half = match c.projection {
            Projection::Perspective => (c.fov_y_deg.to_radians() * 0.5).tan() * depth,
            Projection::Orthographic => c.ortho_height * 0.5,
        };
        (v.dot(right(c)) / (half * aspect), v.dot(cam_up(c)) / half, depth)
    }

    #[test]
    fn fit_all_projects_the_box_inside_the_view_in_both_projections() {
        let (min, max) = (Vec3::new(10.0, 10.0, 10.0), Vec3::new(14.0, 12.0, 11.0));
        for base in [
            cam(),
            ortho(),
            Camera {
                width: 100,
                height: 200,
                ..ortho()
            },
        ] {
            let (f, pivot) = fit(&base, min, max);
            assert_eq!(f.projection, base.projection);
            assert!(close(pivot, (min + max) * 0.5));
            assert!(close(forward(&f), forward(&base)));
            let mut widest = 0.0f32;
            for corner in hrtao_scene::Aabb::new(min, max).corners() {
                let (x, y, depth) = project(&f, corner);
                assert!(depth > 0.0, "{:?}: corner behind the eye plane", f.projection);
                assert!(
                    x.abs() <= 1.0 + 1e-4 && y.abs() <= 1.0 + 1e-4,
                    "{:?}: ({x}, {y})",
                    f.projection
                );
                widest = widest.max(x.abs()).max(y.abs());
            }
            // Framed, not lost in the middle: the box reaches at least a third of the image.
            assert!(widest > 0.33, "{:?}: {widest}", f.projection);
        }
        // Orthographic: the bounding sphere spans the smaller extent (height here: aspect 2).
        let (f, _) = fit(&ortho(), min, max);
        assert!((f.ortho_height - (max - min).length()).abs() < 1e-4);
    }

    #[test]
    fn orthographic_zoom_scales_ortho_height_and_keeps_the_cursor_point() {
        let c = ortho();
        let z = zoom_to(&c, c.ray(150.0, 50.0), 0.5);
        assert!((z.ortho_height - 3.0).abs() < 1e-5, "zoom in halves the height");
        assert!(
            close(eye(&z) - target(&z), eye(&c) - target(&c)),
            "the eye plane stays"
        );
        // The point under the cursor on the target plane projects to the same pixel.
        let (o, d) = c.ray(150.0, 50.0);
        let p = o + d * (target(&c) - o).dot(d);
        let (o2, d2) = z.ray(150.0, 50.0);
        let p2 = o2 + d2 * (target(&z) - o2).dot(d2);
        assert!(close(p, p2), "{p} vs {p2}");
        let out = zoom_to(&c, c.ray(99.5, 49.5), 2.0);
        assert!((out.ortho_height - 12.0).abs() < 1e-4);
        assert!(
            close(target(&out), target(&c)),
            "zoom about the centre keeps the target"
        );
        // Pan in ortho moves by ortho_height / height per pixel.
        let p = pan(&c, 10.0, 0.0, 100.0);
        assert!(close(target(&p) - target(&c), -right(&c) * 0.6));
    }

    #[test]
    fn switching_projection_keeps_the_framing_at_the_pivot() {
        let c = cam();
        let pivot = Vec3::new(1.0, -4.0, 0.5); // depth 6 in front of the eye
        let o = set_projection(&c, pivot, Projection::Orthographic);
        let h = 2.0 * 6.0 * (30f32).to_radians().tan();
        assert!((o.ortho_height - h).abs() < 1e-4);
        assert!(close(eye(&o), eye(&c)) && close(forward(&o), forward(&c)));
        // A point on the pivot's depth plane lands on the same pixel in both projections.
        let q = pivot + right(&c) * 1.5 + cam_up(&c) * 0.7;
        let (a, b) = (project(&c, q), project(&o, q));
        assert!(
            (a.0 - b.0).abs() < 1e-4 && (a.1 - b.1).abs() < 1e-4,
            "{a:?} vs {b:?}"
        );
        // And back: the pivot's depth plane spans ortho_height again.
        let narrow = Camera {
            ortho_height: 2.0,
            ..o
        };
        let p = set_projection(&narrow, pivot, Projection::Perspective);
        assert_eq!(p.projection, Projection::Perspective);
        let (x, y, _) = project(&p, q);
        let (xo, yo, _) = project(&narrow, q);
        assert!(
            (x - xo).abs() < 1e-4 && (y - yo).abs() < 1e-4,
            "({x}, {y}) vs ({xo}, {yo})"
        );
        assert!(p.validate().is_ok());
    }

    #[test]
    fn standard_axis_views_are_orthographic() {
        let (min, max) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        for v in [StdView::Front, StdView::Right, StdView::Top] {
            let (c, _) = std_view(&cam(), v, UpAxis::Z, min, max);
            assert_eq!(c.projection, Projection::Orthographic, "{v:?}");
            assert!((c.ortho_height - 2.0 * 3f32.sqrt()).abs() < 1e-4);
        }
        assert_eq!(
            std_view(&cam(), StdView::Iso, UpAxis::Z, min, max).0.projection,
            Projection::Perspective
        );
    }

    #[test]
    fn fly_moves_and_looks() {
        let c = cam();
        let m = fly_move(&c, Vec3::new(0.0, 0.0, 2.0));
        assert!(close(eye(&m), Vec3::new(0.0, -8.0, 0.0)));
        assert!(close(forward(&m), forward(&c)));
        let l = fly_look(&c, Vec3::Z, std::f32::consts::FRAC_PI_2, 0.0);
        assert!(close(eye(&l), eye(&c)));
        assert!(close(forward(&l), -Vec3::X));
    }
}
