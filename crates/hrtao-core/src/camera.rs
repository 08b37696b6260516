//! The camera of CAMERA.json: eye/target/up in the scene file's own coordinates, and a projection: a pinhole
//! (perspective, the default) whose vertical field of view spans the image height, or orthographic, whose
//! image spans `ortho_height` world units vertically (rays parallel to the view direction, starting on the
//! plane through the eye).
use glam::Vec3;
/// Which world direction points up (the six signed axes; `hrtao_scene::UpAxis`).
pub use hrtao_scene::UpAxis;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};

/// How the camera projects the scene onto the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// Pinhole: rays from the eye; `fov_y_deg` spans the image height.
    #[default]
    Perspective,
    /// Parallel rays along the view direction from the plane through the eye; `ortho_height` world units span
    /// the image height.
    Orthographic,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    #[serde(default = "default_fov")]
    pub fov_y_deg: f32,
    #[serde(default = "default_width")]
    pub width: u32,
    #[serde(default = "default_height")]
    pub height: u32,
    #[serde(default)]
    pub projection: Projection,
    /// World height spanned by the image in orthographic projection (unused in perspective).
    #[serde(default = "default_ortho_height")]
    pub ortho_height: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            eye: [0.0, 0.0, 1.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 45.0,
            width: 640,
            height: 360,
            projection: Projection::Perspective,
            ortho_height: 1.0,
        }
    }
}

fn default_ortho_height() -> f32 {
    1.0
}

fn default_fov() -> f32 {
    45.0
}
fn default_width() -> u32 {
    640
}
fn default_height() -> u32 {
    360
}

/// Camera basis vectors as the shaders want them (see `FrameGlobals::cam_u`).
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    pub eye: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub w: Vec3,
}

impl Camera {
    /// Loads CAMERA.json, whose eye and target are in the scene file's own coordinates, into the coordinates of
    /// a scene re-centred at `origin` (`Scene::origin`; zero for most files). The file's values are read in
    /// f64, so a camera 10^6 units from the file's origin keeps its precision.
    pub fn load_in(path: &std::path::Path, origin: [f64; 3]) -> Result<Camera> {
        #[derive(Deserialize)]
        struct FileCamera {
            eye: [f64; 3],
            target: [f64; 3],
            up: [f32; 3],
            #[serde(default = "default_fov")]
            fov_y_deg: f32,
            #[serde(default = "default_width")]
            width: u32,
            #[serde(default = "default_height")]
            height: u32,
            #[serde(default)]
            projection: Projection,
            /// Absent: the perspective framing at the target distance (see `Camera::framing_height`).
            ortho_height: Option<f32>,
        }
        let text = std::fs::read_to_string(path).map_err(|e| CoreError::Io {
            path: path.display().to_string(),
            source: e,
        })?;
        let f: FileCamera = serde_json::from_str(&text)
            .map_err(|e| CoreError::Invalid(format!("camera file {}: {e}", path.display())))?;
        let local = |p: [f64; 3]| std::array::from_fn(|i| (p[i] - origin[i]) as f32);
        let mut cam = Camera {
            eye: local(f.eye),
            target: local(f.target),
            up: f.up,
            fov_y_deg: f.fov_y_deg,
            width: f.width,
            height: f.height,
            projection: f.projection,
            ortho_height: f.ortho_height.unwrap_or(1.0),
        };
        if f.ortho_height.is_none() {
            cam.ortho_height = cam.framing_height();
        }
        cam.validate()
            .map_err(|e| CoreError::Invalid(format!("camera file {}: {e}", path.display())))?;
        Ok(cam)
    }

    /// Loads CAMERA.json for a scene in the file's own coordinates (origin zero).
    pub fn load(path: &std::path::Path) -> Result<Camera> {
        Self::load_in(path, [0.0; 3])
    }

    pub fn validate(&self) -> std::result::Result<(), String> {
        let all = self.eye.iter().chain(&self.target).chain(&self.up);
        if !all.clone().all(|v| v.is_finite())
            || !self.fov_y_deg.is_finite()
            || !self.ortho_height.is_finite()
        {
            return Err("non-finite value".into());
        }
        if self.projection == Projection::Orthographic
            && !(self.ortho_height > 0.0 && self.ortho_height < 1e30)
        {
            return Err(format!("ortho_height {} must be positive", self.ortho_height));
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(format!("fov_y_deg {} must be in (0, 180)", self.fov_y_deg));
        }
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return Err(format!(
                "image size {}x{} must be within 1..=16384",
                self.width, self.height
            ));
        }
        let fwd = Vec3::from(self.target) - Vec3::from(self.eye);
        if fwd.length() <= 0.0 {
            return Err("eye and target coincide".into());
        }
        if fwd.normalize().cross(Vec3::from(self.up)).length() < 1e-6 {
            return Err("up is parallel to the view direction".into());
        }
        Ok(())
    }

    pub fn frame(&self) -> CameraFrame {
        let eye = Vec3::from(self.eye);
        let w = (Vec3::from(self.target) - eye).normalize();
        let right = w.cross(Vec3::from(self.up)).normalize();
        let up = right.cross(w);
        // Half the image height: on the plane at unit distance (perspective) or in world units (orthographic).
        let half = match self.projection {
            Projection::Perspective => (self.fov_y_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic => self.ortho_height * 0.5,
        };
        let aspect = self.width as f32 / self.height as f32;
        CameraFrame {
            eye,
            u: right * half * aspect,
            v: up * half,
            w,
        }
    }

    pub fn is_orthographic(&self) -> bool {
        self.projection == Projection::Orthographic
    }

    /// The world-space ray (origin, unit direction) through the image point (x, y) in pixels (pixel centres at
    /// +0.5, row 0 at the top), as the shaders compute it (`camera_ray` in common.glsl).
    pub fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3) {
        let f = self.frame();
        let nx = (x + 0.5) / self.width as f32 * 2.0 - 1.0;
        let ny = (y + 0.5) / self.height as f32 * 2.0 - 1.0;
        let offset = nx * f.u - ny * f.v;
        match self.projection {
            Projection::Perspective => (f.eye, (f.w + offset).normalize()),
            Projection::Orthographic => (f.eye + offset, f.w),
        }
    }

    /// The world-space ray direction through pixel (x, y) centre (row 0 at the top), as the shaders compute it.
    pub fn ray_dir(&self, x: f32, y: f32) -> Vec3 {
        self.ray(x, y).1
    }

    /// Where orthographic rays start: the eye, moved back along the view direction until every point of
    /// `points` (the scene bounds' corners) lies in front of the plane through it. An orthographic view thus
    /// never clips the scene, wherever the eye stands (as in CAD tools); the eye fixes the view direction and the
    /// image position only.
    /// When it moves, it stops 1 % of the points' depth range short of the nearest point (a ray starting exactly
    /// on a face could miss it).
    pub fn ortho_ray_plane(&self, points: &[Vec3]) -> Vec3 {
        let f = self.frame();
        let depths = points
            .iter()
            .map(|p| (*p - f.eye).dot(f.w))
            .filter(|d| d.is_finite());
        let (near, far) = depths.fold((f32::MAX, f32::MIN), |(n, x), d| (n.min(d), x.max(d)));
        if near >= 0.0 || near > far {
            return f.eye;
        }
        let margin = 0.01 * (far - near);
        f.eye + f.w * (near - margin)
    }

    /// Distance from the eye to the target.
    pub fn distance(&self) -> f32 {
        (Vec3::from(self.target) - Vec3::from(self.eye)).length()
    }

    /// World height the perspective image spans at the target distance: the `ortho_height` that keeps the
    /// framing of the target plane when switching projections.
    pub fn framing_height(&self) -> f32 {
        2.0 * self.distance() * (self.fov_y_deg.to_radians() * 0.5).tan()
    }

    /// World height the image spans at view depth `depth` (along the view direction): grows with the depth in
    /// perspective, constant in orthographic.
    pub fn view_height_at(&self, depth: f32) -> f32 {
        match self.projection {
            Projection::Perspective => 2.0 * depth * (self.fov_y_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic => self.ortho_height,
        }
    }

    /// This camera in `projection`, keeping the framing of the target plane (orthographic height = the
    /// perspective view height at the target distance, and back: the eye moves along the view direction so
    /// the target plane spans `ortho_height`).
    pub fn with_projection(&self, projection: Projection) -> Camera {
        if projection == self.projection {
            return *self;
        }
        match projection {
            Projection::Orthographic => Camera {
                projection,
                ortho_height: self.framing_height(),
                ..*self
            },
            Projection::Perspective => {
                let target = Vec3::from(self.target);
                let back = (Vec3::from(self.eye) - target).normalize();
                let d = self.ortho_height * 0.5 / (self.fov_y_deg.to_radians() * 0.5).tan();
                Camera {
                    projection,
                    eye: (target + back * d).to_array(),
                    ..*self
                }
            }
        }
    }
}

impl Camera {
    /// A perspective camera at `eye` looking at `target`, `up` up, its vertical field of view `fov_y_deg` spanning
    /// an image of `width` x `height` pixels.
    pub fn perspective(
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
        fov_y_deg: f32,
        (width, height): (u32, u32),
    ) -> Camera {
        Camera {
            eye,
            target,
            up,
            fov_y_deg,
            width,
            height,
            ..Default::default()
        }
    }

    /// A camera that frames the box `min..max` from an isometric-like direction (front-right-above).
    /// An empty or non-finite box (a scene with nothing visible) frames the unit cube.
    pub fn fit(min: Vec3, max: Vec3, up: UpAxis, fov_y_deg: f32, width: u32, height: u32) -> Camera {
        let (min, max) = if min.is_finite() && max.is_finite() && min.cmple(max).all() {
            (min, max)
        } else {
            (Vec3::splat(-0.5), Vec3::splat(0.5))
        };
        let center = (min + max) * 0.5;
        let radius = ((max - min).length() * 0.5).max(1e-6);
        let upv = up.vector();
        // Front-right-above in the up axis's frame (e1, e2, up): for +Z the direction (1, -1.2, 0.8).
        let dir = up
            .from_frame(glam::DVec3::new(1.0, -1.2, 0.8))
            .as_vec3()
            .normalize();
        let aspect = width as f32 / height.max(1) as f32;
        let half = (fov_y_deg.to_radians() * 0.5)
            .tan()
            .min((fov_y_deg.to_radians() * 0.5).tan() * aspect);
        let dist = radius / half.atan().sin();
        let eye = center + dir * dist;
        Camera {
            ortho_height: 2.0 * radius / aspect.min(1.0),
            ..Camera::perspective(
                eye.to_array(),
                center.to_array(),
                upv.to_array(),
                fov_y_deg,
                (width, height),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_target_and_corners_span_fov() {
        let cam = Camera::perspective([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 90.0, (2, 2));
        let f = cam.frame();
        assert!((f.w - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // With 90 deg vertical fov, the top edge of the image is at 45 deg.
        let top = (f.w + f.v).normalize();
        assert!((top.angle_between(f.w).to_degrees() - 45.0).abs() < 1e-4);
        assert!(cam.ray_dir(0.0, 0.0).y > 0.0, "row 0 is the top of the image");
    }

    fn ortho() -> Camera {
        Camera {
            projection: Projection::Orthographic,
            ortho_height: 4.0,
            ..Camera::perspective([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 45.0, (200, 100))
        }
    }

    #[test]
    fn orthographic_rays_are_parallel_and_span_ortho_height() {
        let cam = ortho();
        let (o0, d0) = cam.ray(-0.5, -0.5); // the top-left image corner
        let (o1, d1) = cam.ray(199.5, 99.5); // the bottom-right corner
        assert_eq!(d0, Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(d1, d0);
        // The image spans 4 units vertically and 8 horizontally (aspect 2), on the plane through the eye.
        assert!((o0 - Vec3::new(-4.0, 2.0, 5.0)).length() < 1e-5, "{o0}");
        assert!((o1 - Vec3::new(4.0, -2.0, 5.0)).length() < 1e-5, "{o1}");
        assert_eq!(cam.view_height_at(1.0), 4.0);
        assert_eq!(cam.view_height_at(100.0), 4.0);
        // Rays start in front of every given point: behind the eye (z 5) up to z 7 and a margin of 1 % of the
        // points' depth range (9), never in front of the eye.
        let plane = cam.ortho_ray_plane(&[Vec3::new(3.0, 1.0, 7.0), Vec3::new(0.0, 0.0, -2.0)]);
        assert!((plane - Vec3::new(0.0, 0.0, 7.09)).length() < 1e-5, "{plane}");
        assert_eq!(cam.ortho_ray_plane(&[Vec3::ZERO]), Vec3::new(0.0, 0.0, 5.0));
    }

    #[test]
    fn switching_projection_keeps_the_target_plane_framing() {
        let persp = Camera {
            fov_y_deg: 90.0,
            ..ortho().with_projection(Projection::Perspective)
        };
        let o = persp.with_projection(Projection::Orthographic);
        assert!(o.is_orthographic());
        // 90 degrees at distance d spans 2 d.
        assert!((o.ortho_height - 2.0 * persp.distance()).abs() < 1e-4);
        assert!((o.view_height_at(3.0) - persp.view_height_at(persp.distance())).abs() < 1e-4);
        // Back to perspective: the eye moves so the target plane spans ortho_height again.
        let narrow = Camera {
            ortho_height: 1.0,
            ..o
        };
        let p = narrow.with_projection(Projection::Perspective);
        assert_eq!(p.projection, Projection::Perspective);
        assert!((p.framing_height() - 1.0).abs() < 1e-4, "{}", p.framing_height());
        assert_eq!(p.target, narrow.target);
    }

    #[test]
    fn camera_json_reads_the_projection() {
        let dir = std::env::temp_dir().join(format!("hrtao-cam-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let write = |name: &str, text: &str| {
            let p = dir.join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        let old = write("old.json", r#"{"eye":[0,0,5],"target":[0,0,0],"up":[0,1,0]}"#);
        let c = Camera::load(&old).unwrap();
        assert_eq!(
            c.projection,
            Projection::Perspective,
            "old files stay perspective"
        );
        let o = write(
            "ortho.json",
            r#"{"eye":[10,0,5],"target":[10,0,0],"up":[0,1,0],"projection":"orthographic","ortho_height":3}"#,
        );
        let c = Camera::load_in(&o, [10.0, 0.0, 0.0]).unwrap();
        assert_eq!(c.projection, Projection::Orthographic);
        assert_eq!(c.ortho_height, 3.0);
        assert_eq!(c.eye, [0.0, 0.0, 5.0]);
        // Without ortho_height: the perspective framing at the target distance.
        let f = write(
            "framed.json",
            r#"{"eye":[0,0,5],"target":[0,0,0],"up":[0,1,0],"fov_y_deg":90,"projection":"orthographic"}"#,
        );
        assert!((Camera::load(&f).unwrap().ortho_height - 10.0).abs() < 1e-4);
        let bad = write(
            "bad.json",
            r#"{"eye":[0,0,5],"target":[0,0,0],"up":[0,1,0],"projection":"orthographic","ortho_height":-1}"#,
        );
        let e = Camera::load(&bad).unwrap_err().to_string();
        assert!(e.contains("ortho_height"), "{e}");
        let typo = write(
            "typo.json",
            r#"{"eye":[0,0,5],"target":[0,0,0],"up":[0,1,0],"projection":"isometric"}"#,
        );
        let e = Camera::load(&typo).unwrap_err().to_string();
        assert!(e.contains("isometric"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn rejects_bad_cameras() {
        let mut cam = Camera::perspective([0.0; 3], [0.0; 3], [0.0, 1.0, 0.0], 45.0, (4, 4));
        assert!(cam.validate().is_err());
        cam.target = [0.0, 1.0, 0.0];
        assert!(cam.validate().is_err(), "up parallel to view");
        cam.target = [1.0, 0.0, 0.0];
        cam.fov_y_deg = f32::NAN;
        assert!(cam.validate().is_err());
    }
}
