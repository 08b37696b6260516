//! The pinhole camera of CAMERA.json: eye/target/up in the scene file's own coordinates, a vertical field of
//! view spanning the image height.
use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};

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
        }
    }
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
        }
        let text = std::fs::read_to_string(path).map_err(|e| CoreError::Io {
            path: path.display().to_string(),
            source: e,
        })?;
        let f: FileCamera = serde_json::from_str(&text)
            .map_err(|e| CoreError::Invalid(format!("camera file {}: {e}", path.display())))?;
        let local = |p: [f64; 3]| std::array::from_fn(|i| (p[i] - origin[i]) as f32);
        let cam = Camera {
            eye: local(f.eye),
            target: local(f.target),
            up: f.up,
            fov_y_deg: f.fov_y_deg,
            width: f.width,
            height: f.height,
        };
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
        if !all.clone().all(|v| v.is_finite()) || !self.fov_y_deg.is_finite() {
            return Err("non-finite value".into());
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
        let tan_half = (self.fov_y_deg.to_radians() * 0.5).tan();
        let aspect = self.width as f32 / self.height as f32;
        CameraFrame {
            eye,
            u: right * tan_half * aspect,
            v: up * tan_half,
            w,
        }
    }

    /// The world-space ray direction through pixel (x, y) centre (row 0 at the top), as the shaders compute it.
    pub fn ray_dir(&self, x: f32, y: f32) -> Vec3 {
        let f = self.frame();
        let nx = (x + 0.5) / self.width as f32 * 2.0 - 1.0;
        let ny = (y + 0.5) / self.height as f32 * 2.0 - 1.0;
        (f.w + nx * f.u - ny * f.v).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_target_and_corners_span_fov() {
        let cam = Camera {
            eye: [0.0, 0.0, 5.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 90.0,
            width: 2,
            height: 2,
        };
        let f = cam.frame();
        assert!((f.w - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // With 90 deg vertical fov, the top edge of the image is at 45 deg.
        let top = (f.w + f.v).normalize();
        assert!((top.angle_between(f.w).to_degrees() - 45.0).abs() < 1e-4);
        assert!(cam.ray_dir(0.0, 0.0).y > 0.0, "row 0 is the top of the image");
    }

    #[test]
    fn rejects_bad_cameras() {
        let mut cam = Camera {
            eye: [0.0; 3],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 45.0,
            width: 4,
            height: 4,
        };
        assert!(cam.validate().is_err());
        cam.target = [0.0, 1.0, 0.0];
        assert!(cam.validate().is_err(), "up parallel to view");
        cam.target = [1.0, 0.0, 0.0];
        cam.fov_y_deg = f32::NAN;
        assert!(cam.validate().is_err());
    }
}

/// Which world axis points up for automatic cameras.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum UpAxis {
    #[default]
    Y,
    Z,
}

impl UpAxis {
    pub fn vector(self) -> Vec3 {
        match self {
            UpAxis::Y => Vec3::Y,
            UpAxis::Z => Vec3::Z,
        }
    }
}

impl Camera {
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
        let dir = match up {
            UpAxis::Y => Vec3::new(1.0, 0.8, 1.2),
            UpAxis::Z => Vec3::new(1.0, -1.2, 0.8),
        }
        .normalize();
        let aspect = width as f32 / height.max(1) as f32;
        let half = (fov_y_deg.to_radians() * 0.5)
            .tan()
            .min((fov_y_deg.to_radians() * 0.5).tan() * aspect);
        let dist = radius / half.atan().sin();
        let eye = center + dir * dist;
        Camera {
            eye: eye.to_array(),
            target: center.to_array(),
            up: upv.to_array(),
            fov_y_deg,
            width,
            height,
        }
    }
}
