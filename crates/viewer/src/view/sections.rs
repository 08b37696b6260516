//! Section planes in the viewer: up to three planes, each on/off, with an axis-preset normal and an offset
//! over the model's bounds (slider with numeric entry, a drag value, and Ctrl+Shift+drag in the 3D view). A change
//! rebuilds the TLAS for the planes and counts as a scene change (see hrtao_core::section).
use glam::{DVec3, Vec3};
use hrtao_core::gpu::MAX_SECTIONS;
use hrtao_core::{Camera, SectionPlane, Sections};
use hrtao_scene::{Aabb, Scene};

use super::command::{Command, ViewState};
use super::nav;

const PLANES: usize = MAX_SECTIONS as usize;

/// The planes as the panel edits them (all slots, enabled or not), in scene coordinates.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SectionState {
    pub planes: [SectionPlane; PLANES],
    /// The plane Ctrl+Shift+drag moves.
    pub active: usize,
    /// The scene's bounds, for the offset range.
    pub bounds: Aabb,
    /// The panel should open its section (planes came with the scene).
    pub reveal: bool,
}

impl Default for SectionState {
    fn default() -> Self {
        SectionState {
            planes: std::array::from_fn(|i| SectionPlane {
                normal: AXES[i % 3],
                ..SectionPlane::default()
            }),
            active: 0,
            bounds: Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)),
            reveal: false,
        }
    }
}

const AXES: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl SectionState {
    /// Fresh planes for a scene: disabled, one per axis through the middle, or `initial` (scene coordinates)
    /// in the first slots, enabled.
    pub fn for_scene(bounds: Aabb, initial: &Sections) -> SectionState {
        let mut s = SectionState {
            bounds,
            reveal: initial.any_enabled(),
            ..SectionState::default()
        };
        for (i, p) in s.planes.iter_mut().enumerate() {
            p.offset = Vec3::from(p.normal).dot(bounds.center());
            if let Some(given) = initial.planes.get(i) {
                *p = *given;
            }
        }
        s
    }

    pub fn sections(&self) -> Sections {
        Sections {
            planes: self.planes.iter().filter(|p| p.enabled).copied().collect(),
        }
    }
}

/// The offsets `normal · p` over the bounds `b`, widened by 5% so a plane can clear the model.
fn offset_range(b: &Aabb, normal: [f32; 3]) -> (f32, f32) {
    let n = Vec3::from(normal);
    let corners = (0..8).map(|i| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
        .dot(n)
    });
    let (lo, hi) = corners.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| {
        (lo.min(d), hi.max(d))
    });
    let margin = ((hi - lo) * 0.05).max(1e-3);
    (lo - margin, hi + margin)
}

/// How far a drag of `delta` view pixels (x right, y down) moves a plane with `normal` along it: the drag
/// projected on the normal's screen direction, in world units at the camera's focal distance; a normal pointing
/// at the viewer takes vertical drags (up: along the normal).
fn drag_amount(cam: &Camera, normal: Vec3, delta: egui::Vec2, view_h: f32) -> f32 {
    let wpp = nav::world_per_pixel(cam, view_h);
    let screen = glam::Vec2::new(normal.dot(nav::right(cam)), normal.dot(nav::cam_up(cam)));
    let drag = glam::Vec2::new(delta.x, -delta.y);
    if screen.length() > 0.2 {
        drag.dot(screen.normalize()) * wpp / screen.length()
    } else {
        drag.y * wpp
    }
}

/// A plane's offset in the file's coordinates (what `--section` takes) and back.
fn to_file(scene: &Scene, p: &SectionPlane) -> f64 {
    p.offset as f64 + DVec3::from(p.normal.map(f64::from)).dot(DVec3::from(scene.origin))
}

fn from_file(scene: &Scene, normal: [f32; 3], d: f64) -> f32 {
    (d - DVec3::from(normal.map(f64::from)).dot(DVec3::from(scene.origin))) as f32
}

impl SectionState {
    /// The "Section planes" section: a changed plane sends the enabled planes.
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let Some(scene) = state.scene else {
            ui.label("no scene");
            return Vec::new();
        };
        let mut s = self.clone();
        let bounds = s.bounds;
        for i in 0..PLANES {
            ui.push_id(i, |ui| {
                let p = &mut s.planes[i];
                ui.horizontal(|ui| {
                    ui.checkbox(&mut p.enabled, format!("Plane {}", i + 1))
                        .on_hover_text("Cut away the geometry in front of the plane (n·p > d)");
                    for (label, axis) in ["X", "Y", "Z"].iter().zip(AXES) {
                        let on = p.normal.map(f32::abs) == axis;
                        if ui
                            .selectable_label(on, *label)
                            .on_hover_text("Normal along this axis")
                            .clicked()
                        {
                            let centre = Vec3::from(axis).dot(bounds.center());
                            p.normal = axis;
                            p.offset = centre;
                        }
                    }
                    if ui.button("Flip").on_hover_text("Keep the other side").clicked() {
                        p.normal = p.normal.map(|c| -c);
                        p.offset = -p.offset;
                    }
                    ui.radio_value(&mut s.active, i, "")
                        .on_hover_text("Ctrl+Shift+drag in the view moves this plane");
                });
                let (lo, hi) = offset_range(&bounds, p.normal);
                let mut d = to_file(scene, p);
                let (flo, fhi) = (d - (p.offset - lo) as f64, d + (hi - p.offset) as f64);
                let range = flo.min(d)..=fhi.max(d);
                ui.horizontal(|ui| {
                    let slider = egui::Slider::new(&mut d, range)
                        .text("offset")
                        .clamping(egui::SliderClamping::Never);
                    ui.add(slider)
                        .on_hover_text("Plane offset d in the file's coordinates (type a value, or drag)");
                });
                p.offset = from_file(scene, p.normal, d);
            });
        }
        if let Some([kept, crossing, cut]) = state.section_sides {
            ui.label(format!(
                "instances: {kept} untouched, {crossing} crossed, {cut} cut away"
            ));
        }
        ui.label(
            egui::RichText::new("Ctrl+Shift+left drag in the view moves the selected plane (radio button).")
                .weak(),
        );
        if s == *self {
            return Vec::new();
        }
        *self = s;
        vec![Command::Sections(self.sections())]
    }

    /// Ctrl+Shift+drag: moves the active plane along its normal by the drag projected on the normal's screen
    /// direction (`view_h`: the view's height in pixels).
    pub fn drag(&mut self, cam: &Camera, delta: egui::Vec2, view_h: f32) -> Option<Command> {
        let bounds = self.bounds;
        let p = &mut self.planes[self.active];
        if delta == egui::Vec2::ZERO || !p.enabled {
            return None;
        }
        let amount = drag_amount(cam, Vec3::from(p.normal), delta, view_h);
        let (lo, hi) = offset_range(&bounds, p.normal);
        p.offset = (p.offset + amount).clamp(lo, hi);
        Some(Command::Sections(self.sections()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dragging_moves_a_plane_with_the_pointer() {
        let cam = Camera {
            eye: [0.0, -10.0, 0.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 0.0, 1.0],
            fov_y_deg: 45.0,
            width: 200,
            height: 100,
            ..Camera::default()
        };
        let wpp = nav::world_per_pixel(&cam, 100.0);
        let right = drag_amount(&cam, Vec3::X, egui::vec2(50.0, 0.0), 100.0);
        assert!(
            (right - 50.0 * wpp).abs() < 1e-4 * right.abs(),
            "{right} vs {}",
            50.0 * wpp
        );
        assert!(drag_amount(&cam, -Vec3::X, egui::vec2(50.0, 0.0), 100.0) < 0.0);
        let up = drag_amount(&cam, Vec3::Z, egui::vec2(0.0, -20.0), 100.0);
        assert!((up - 20.0 * wpp).abs() < 1e-4 * up.abs());
        // The normal points away from the viewer: vertical drags move it, horizontal ones do not.
        assert!(drag_amount(&cam, Vec3::Y, egui::vec2(0.0, -20.0), 100.0) > 0.0);
        assert_eq!(drag_amount(&cam, Vec3::Y, egui::vec2(30.0, 0.0), 100.0), 0.0);
    }

    #[test]
    fn state_for_a_scene_and_offset_ranges() {
        let b = Aabb::new(Vec3::new(0.0, -2.0, 0.0), Vec3::new(10.0, 2.0, 4.0));
        let given = Sections::new(vec![SectionPlane::new([0.0, 0.0, -1.0], -1.0).unwrap()]).unwrap();
        let s = SectionState::for_scene(b, &given);
        assert_eq!(s.planes[0], given.planes[0]);
        assert!(!s.planes[1].enabled && s.planes[1].normal == [0.0, 1.0, 0.0] && s.planes[1].offset == 0.0);
        assert_eq!(s.planes[2].offset, 2.0, "through the middle of the bounds");
        assert_eq!(s.sections(), given);
        let (lo, hi) = offset_range(&b, [1.0, 0.0, 0.0]);
        assert!((lo + 0.5).abs() < 1e-5 && (hi - 10.5).abs() < 1e-5, "{lo} {hi}");
        let (lo, hi) = offset_range(&b, [0.0, 0.0, -1.0]);
        assert!((lo + 4.2).abs() < 1e-5 && (hi - 0.2).abs() < 1e-5, "{lo} {hi}");
    }
}
