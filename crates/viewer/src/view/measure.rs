//! Measure mode: two picked surface points, their distance and x/y/z components drawn over the 3D view, in
//! the unit the user picks. Files carry no unit (glTF says metres; STL, PLY and OBJ say nothing, and many
//! CAD exports are in millimetres), so the user also says what one file unit is. Points are reported in the
//! file's own coordinates (`Scene::origin` added back).
use glam::{DVec3, Vec3};
use hrtao_core::Camera;
use hrtao_scene::Scene;

/// A length unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    M,
    Cm,
    Mm,
    In,
    Ft,
}

impl Unit {
    pub const ALL: [Unit; 5] = [Unit::M, Unit::Cm, Unit::Mm, Unit::In, Unit::Ft];

    /// The unit's length in metres.
    pub fn metres(self) -> f64 {
        match self {
            Unit::M => 1.0,
            Unit::Cm => 0.01,
            Unit::Mm => 0.001,
            Unit::In => 0.0254,
            Unit::Ft => 0.3048,
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Unit::M => "m",
            Unit::Cm => "cm",
            Unit::Mm => "mm",
            Unit::In => "in",
            Unit::Ft => "ft",
        }
    }

    /// The unit of this many metres, if it is one of ours (a STEP/IGES file's declared unit).
    pub fn from_metres(m: f64) -> Option<Unit> {
        Unit::ALL
            .into_iter()
            .find(|u| (u.metres() / m - 1.0).abs() < 1e-6)
    }

    /// What one file unit is, by the file's format: glTF and generated scenes are in metres; STL, PLY and
    /// OBJ carry no unit, and CAD tools mostly export them in millimetres.
    pub fn of_file(spec: &str) -> Unit {
        let ext = std::path::Path::new(spec)
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "stl" | "ply" | "obj" => Unit::Mm,
            _ => Unit::M,
        }
    }
}

/// Converts a length of `v` file units into the display unit.
pub fn convert(v: f64, file: Unit, show: Unit) -> f64 {
    v * file.metres() / show.metres()
}

/// A length with its unit, with as many decimals as a 4-5 significant digit reading needs.
pub fn format_len(v: f64, unit: Unit) -> String {
    let decimals = match v.abs() {
        a if a >= 1000.0 => 1,
        a if a >= 10.0 => 2,
        a if a >= 0.1 => 3,
        _ => 5,
    };
    format!("{v:.decimals$} {}", unit.label())
}

/// A picked point: in scene (GPU) coordinates for drawing, in the file's coordinates for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub scene: Vec3,
    pub file: DVec3,
}

/// The distance between two points and its components, in the display unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    pub distance: f64,
    /// b - a per axis.
    pub delta: DVec3,
}

impl Measurement {
    pub fn between(a: DVec3, b: DVec3, file: Unit, show: Unit) -> Self {
        let d = b - a;
        Self {
            distance: convert(d.length(), file, show),
            delta: DVec3::new(
                convert(d.x, file, show),
                convert(d.y, file, show),
                convert(d.z, file, show),
            ),
        }
    }
}

/// The measure tool's state.
pub struct Measure {
    pub active: bool,
    pub points: Vec<Point>,
    /// What one unit of the file is.
    pub file_unit: Unit,
    /// The unit lengths are shown in.
    pub show_unit: Unit,
    /// Model dimensions (bounding box size, file units), per scene version (F, instance count).
    dims: Option<((u32, usize), Vec3)>,
}

impl Measure {
    pub fn for_spec(spec: &str) -> Self {
        let unit = Unit::of_file(spec);
        Self {
            active: false,
            points: Vec::new(),
            file_unit: unit,
            show_unit: unit,
            dims: None,
        }
    }

    /// Adds a picked point; a third pick starts a new measurement.
    pub fn add(&mut self, p: Point) {
        if self.points.len() >= 2 {
            self.points.clear();
        }
        self.points.push(p);
    }

    pub fn result(&self) -> Option<Measurement> {
        match self.points.as_slice() {
            [a, b] => Some(Measurement::between(
                a.file,
                b.file,
                self.file_unit,
                self.show_unit,
            )),
            _ => None,
        }
    }
}

/// Where a scene point appears in the view, as fractions of its width and height (0..1 inside, row 0 at the
/// top); None behind the camera. The inverse of `Camera::ray` in both projections (an orthographic view shows
/// what lies behind its eye too).
pub fn project(cam: &Camera, p: Vec3) -> Option<[f32; 2]> {
    let f = cam.frame();
    let d = p - f.eye;
    let z = match cam.projection {
        hrtao_core::camera::Projection::Perspective => d.dot(f.w),
        hrtao_core::camera::Projection::Orthographic => 1.0,
    };
    if z <= 1e-12 {
        return None;
    }
    let nx = d.dot(f.u) / (f.u.length_squared() * z);
    let ny = d.dot(f.v) / (f.v.length_squared() * z);
    Some([(nx + 1.0) * 0.5, (1.0 - ny) * 0.5])
}

const POINT_COLOR: egui::Color32 = egui::Color32::from_rgb(255, 200, 40);

impl Measure {
    /// Adds a picked scene point to the measurement.
    pub fn pick(&mut self, scene: &Scene, p: [f32; 3]) {
        let scene_p = Vec3::from(p);
        self.add(Point {
            scene: scene_p,
            file: scene.to_file(scene_p),
        });
        log::info!("measure point {} picked", self.points.len());
        if let Some(m) = self.result() {
            log::info!(
                "measured distance {:.6} {} (dx {:.6}, dy {:.6}, dz {:.6})",
                m.distance,
                self.show_unit.label(),
                m.delta.x,
                m.delta.y,
                m.delta.z
            );
        }
    }

    /// The model's bounding box size in file units (cached per scene version).
    fn model_size(&mut self, scene: &Scene) -> Vec3 {
        let key = (scene.f(), scene.instances.len());
        match self.dims {
            Some((k, size)) if k == key => size,
            _ => {
                let b = scene.bounds();
                let size = if b.is_empty() { Vec3::ZERO } else { b.max - b.min };
                self.dims = Some((key, size));
                size
            }
        }
    }

    /// "Dimensions: x × y × z" of the visible model in the display unit.
    pub fn dimensions_row(&mut self, ui: &mut egui::Ui, scene: &Scene) {
        let size = self.model_size(scene);
        let (file, show) = (self.file_unit, self.show_unit);
        let c = |v: f32| format_len(convert(v as f64, file, show), show);
        ui.label(format!(
            "Dimensions: {} × {} × {}",
            c(size.x),
            c(size.y),
            c(size.z)
        ))
        .on_hover_text("Bounding box of the visible instances (x × y × z), in the unit chosen under Measure");
    }

    /// The "Measure" section: the mode, the units and the measured distance.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.toggle_value(&mut self.active, "Measure (M)")
                .on_hover_text("Click two surface points in the view");
            if ui.button("Clear").clicked() {
                self.points.clear();
            }
        });
        let unit_combo = |ui: &mut egui::Ui, id: &str, unit: &mut Unit| {
            egui::ComboBox::from_id_salt(id)
                .selected_text(unit.label())
                .width(60.0)
                .show_ui(ui, |ui| {
                    for u in Unit::ALL {
                        ui.selectable_value(unit, u, u.label());
                    }
                });
        };
        ui.horizontal(|ui| {
            ui.label("1 file unit =").on_hover_text(
                "glTF is in metres; STL, PLY and OBJ carry no unit (CAD exports are often mm)",
            );
            unit_combo(ui, "file-unit", &mut self.file_unit);
            ui.label("show in");
            unit_combo(ui, "show-unit", &mut self.show_unit);
        });
        let show = self.show_unit;
        for (k, p) in self.points.iter().enumerate() {
            ui.label(format!(
                "{} ({:.4}, {:.4}, {:.4}) file units",
                ["A", "B"][k.min(1)],
                p.file.x,
                p.file.y,
                p.file.z
            ));
        }
        match self.result() {
            Some(m) => {
                ui.strong(format!("distance {}", format_len(m.distance, show)));
                ui.label(format!(
                    "dx {}  dy {}  dz {}",
                    format_len(m.delta.x, show),
                    format_len(m.delta.y, show),
                    format_len(m.delta.z, show)
                ));
            }
            None if self.active => {
                ui.weak(format!("click point {}", ["A", "B"][self.points.len().min(1)]));
            }
            None => {}
        }
    }

    /// Draws the picked points, the line between them and the distance over the 3D view.
    /// `cam`: the camera at the 3D view's size.
    pub fn overlay(&self, painter: &egui::Painter, rect: egui::Rect, cam: &Camera) {
        if self.points.is_empty() {
            return;
        }
        let screen: Vec<Option<egui::Pos2>> = self
            .points
            .iter()
            .map(|p| {
                project(cam, p.scene)
                    .map(|[fx, fy]| rect.min + egui::vec2(fx * rect.width(), fy * rect.height()))
            })
            .collect();
        for s in screen.iter().flatten() {
            painter.circle_filled(*s, 4.0, POINT_COLOR);
            painter.circle_stroke(*s, 4.0, egui::Stroke::new(1.0, egui::Color32::BLACK));
        }
        let (Some(m), [Some(a), Some(b)]) = (self.result(), screen.as_slice()) else {
            return;
        };
        painter.line_segment([*a, *b], egui::Stroke::new(2.0, POINT_COLOR));
        let show = self.show_unit;
        let text = format!(
            "{}\ndx {}  dy {}  dz {}",
            format_len(m.distance, show),
            format_len(m.delta.x, show),
            format_len(m.delta.y, show),
            format_len(m.delta.z, show)
        );
        let galley = painter.layout_no_wrap(text, egui::FontId::proportional(14.0), egui::Color32::WHITE);
        let at = egui::pos2((a.x + b.x) * 0.5 + 8.0, (a.y + b.y) * 0.5 + 8.0);
        let bg = egui::Rect::from_min_size(at, galley.size()).expand(4.0);
        painter.rect_filled(bg, 3.0, egui::Color32::from_black_alpha(180));
        painter.galley(at, galley, egui::Color32::WHITE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_convert_and_format() {
        let m = Measurement::between(DVec3::ZERO, DVec3::new(30.0, 40.0, 0.0), Unit::Mm, Unit::Cm);
        assert!((m.distance - 5.0).abs() < 1e-12);
        assert!((m.delta.y - 4.0).abs() < 1e-12);
        assert!((convert(1.0, Unit::Ft, Unit::In) - 12.0).abs() < 1e-12);
        assert!((convert(1.0, Unit::M, Unit::Mm) - 1000.0).abs() < 1e-9);
        assert_eq!(format_len(12.3456, Unit::Mm), "12.35 mm");
        assert_eq!(Unit::of_file("part.STL"), Unit::Mm);
        assert_eq!(Unit::of_file("a.glb"), Unit::M);
        assert_eq!(Unit::of_file("gen:box"), Unit::M);
        assert_eq!(Unit::from_metres(0.0254), Some(Unit::In));
        assert_eq!(Unit::from_metres(1e-3), Some(Unit::Mm));
        assert_eq!(Unit::from_metres(1609.344), None);
    }

    #[test]
    fn third_pick_starts_over_and_projection_inverts_rays() {
        let mut m = Measure::for_spec("x.ply");
        let p = |x: f64| Point {
            scene: Vec3::ZERO,
            file: DVec3::new(x, 0.0, 0.0),
        };
        m.add(p(1.0));
        assert!(m.result().is_none());
        m.add(p(4.0));
        assert!((m.result().unwrap().distance - 3.0).abs() < 1e-12);
        m.add(p(9.0));
        assert_eq!(m.points.len(), 1);
        let cam = Camera {
            eye: [1.0, 2.0, 10.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 50.0,
            width: 200,
            height: 100,
            ..Camera::default()
        };
        let (x, y) = (37.0, 81.0);
        let dir = cam.ray_dir(x, y);
        let [fx, fy] = project(&cam, Vec3::from(cam.eye) + dir * 7.0).unwrap();
        assert!((fx * 200.0 - (x + 0.5)).abs() < 1e-3, "{fx}");
        assert!((fy * 100.0 - (y + 0.5)).abs() < 1e-3, "{fy}");
        assert!(
            project(&cam, Vec3::new(1.0, 2.0, 20.0)).is_none(),
            "behind the camera"
        );
        // Orthographic: the inverse of the parallel ray through the pixel, at any depth.
        let ortho = cam.with_projection(hrtao_core::camera::Projection::Orthographic);
        let (o, d) = ortho.ray(x, y);
        for t in [0.5, 7.0, 40.0] {
            let [fx, fy] = project(&ortho, o + d * t).unwrap();
            assert!((fx * 200.0 - (x + 0.5)).abs() < 1e-3 && (fy * 100.0 - (y + 0.5)).abs() < 1e-3);
        }
    }
}

#[cfg(test)]
mod gpu_tests {
    use super::*;
    use hrtao_core::{AoSettings, ContextOptions, Gpu, Renderer, SceneGpu};
    use hrtao_scene::{Instance, Mesh, Primitive, Scene, DEFAULT_BASE_COLOR};

    /// A closed box from `min` to `max`.
    fn box_scene(min: Vec3, max: Vec3, origin: [f64; 3]) -> Scene {
        let c = |i: usize| {
            [
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            ]
        };
        let positions: Vec<[f32; 3]> = (0..8).map(c).collect();
        #[rustfmt::skip]
        let indices = vec![
            0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
            2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5,
        ];
        let mut s = Scene::new("box");
        s.meshes.push(Mesh {
            name: "box".into(),
            primitives: vec![Primitive::new(positions, indices, DEFAULT_BASE_COLOR)],
        });
        s.instances.push(Instance {
            mesh: 0,
            transform: glam::Mat4::IDENTITY,
            name: "box".into(),
            visible: true,
        });
        s.origin = origin;
        s
    }

    /// Two picks through the renderer's G-buffer at the pixels where two known points of a 4 × 2 × 1 box's top
    /// face appear give their distance (in mm for a box in metres), and file coordinates include the origin.
    #[test]
    fn two_picks_on_a_known_box_give_the_known_distance() {
        let gpu = Gpu::new(&ContextOptions::from_env()).expect("Vulkan device (lavapipe)");
        let origin = [1.0e6, 0.0, 0.0];
        let scene = box_scene(Vec3::ZERO, Vec3::new(4.0, 2.0, 1.0), origin);
        let sg = SceneGpu::new(&gpu, &scene).unwrap();
        let cam = Camera {
            eye: [2.0, -3.0, 6.0],
            target: [2.0, 1.0, 1.0],
            up: [0.0, 0.0, 1.0],
            fov_y_deg: 45.0,
            width: 256,
            height: 192,
            ..Camera::default()
        };
        let settings = {
            let mut s = AoSettings::default();
            s.map.ao_radius = 0.5;
            s.map.hash_capacity = 1 << 12;
            s
        };
        let mut r = Renderer::new(&gpu).unwrap();
        r.render(&hrtao_core::FrameDesc::new(&sg, scene.f(), cam, &settings))
            .unwrap();
        let mut measure = Measure::for_spec("box.glb");
        measure.show_unit = Unit::Mm;
        let (a, b) = (Vec3::new(0.5, 0.5, 1.0), Vec3::new(3.5, 1.5, 1.0));
        for p in [a, b] {
            let [fx, fy] = project(&cam, p).unwrap();
            let (x, y) = ((fx * cam.width as f32) as u32, (fy * cam.height as f32) as u32);
            let px = r.pick(x, y).unwrap().expect("the box is under the pixel");
            assert_eq!(px.instance, 0);
            let hit = Vec3::from(px.position);
            assert!((hit - p).length() < 0.05, "picked {hit} for {p}");
            measure.add(Point {
                scene: hit,
                file: scene.to_file(hit),
            });
        }
        let m = measure.result().unwrap();
        let expected = (b - a).length() as f64 * 1000.0;
        assert!(
            (m.distance - expected).abs() < 0.02 * expected,
            "{} mm vs {expected} mm",
            m.distance
        );
        assert!(
            (m.delta.x - 3000.0).abs() < 60.0 && (m.delta.z).abs() < 1.0,
            "{:?}",
            m.delta
        );
        assert!(
            (measure.points[0].file.x - 1.0e6 - 0.5).abs() < 0.05,
            "file coordinates"
        );
        drop(r);
        drop(sg);
        assert_eq!(gpu.validation_messages(), 0);
    }
}
