//! Which world direction is "up": the six signed axes (F3D's up option). A format may imply one (IFC and 3MF
//! are Z up by their specifications, glTF is Y up); the viewer's camera, orbit, standard views, walk mode and
//! the sky light's zenith follow it. Each up axis has one right-handed frame `(e1, e2, up)`: the horizontal
//! axes the fitted view, the sky frame and the plan coordinates are measured along.
use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

/// A signed world axis pointing up. Serialised as `X`, `Y`, `Z`, `-X`, `-Y`, `-Z` (files of older versions
/// hold `Y` or `Z`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum UpAxis {
    #[serde(rename = "X", alias = "+X")]
    X,
    #[default]
    #[serde(rename = "Y", alias = "+Y")]
    Y,
    #[serde(rename = "Z", alias = "+Z")]
    Z,
    #[serde(rename = "-X")]
    NegX,
    #[serde(rename = "-Y")]
    NegY,
    #[serde(rename = "-Z")]
    NegZ,
}

impl UpAxis {
    /// Every up axis, in the order the panel lists them.
    pub const ALL: [UpAxis; 6] = [
        UpAxis::X,
        UpAxis::Y,
        UpAxis::Z,
        UpAxis::NegX,
        UpAxis::NegY,
        UpAxis::NegZ,
    ];

    /// The unit vector pointing up.
    pub fn vector(self) -> Vec3 {
        self.dvector().as_vec3()
    }

    pub fn dvector(self) -> DVec3 {
        self.frame()[2]
    }

    /// The right-handed frame `[e1, e2, up]` (e1 × e2 = up): for +Z it is the world's own (X, Y, Z), for +Y
    /// it is (X, −Z, Y), the frame the sky light has always used for Y-up scenes.
    pub fn frame(self) -> [DVec3; 3] {
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        match self {
            UpAxis::X => [y, z, x],
            UpAxis::Y => [x, -z, y],
            UpAxis::Z => [x, y, z],
            UpAxis::NegX => [y, -z, -x],
            UpAxis::NegY => [x, z, -y],
            UpAxis::NegZ => [x, -y, -z],
        }
    }

    /// `d` in the frame's coordinates: (along e1, along e2, height).
    pub fn to_frame(self, d: DVec3) -> DVec3 {
        let [a, b, c] = self.frame();
        DVec3::new(d.dot(a), d.dot(b), d.dot(c))
    }

    /// The world direction of frame coordinates (the inverse of [`UpAxis::to_frame`]).
    pub fn from_frame(self, f: DVec3) -> DVec3 {
        let [a, b, c] = self.frame();
        a * f.x + b * f.y + c * f.z
    }

    /// The name the command line, the panel and the files use (`+Z`, `-Y`, ...).
    pub fn label(self) -> &'static str {
        match self {
            UpAxis::X => "+X",
            UpAxis::Y => "+Y",
            UpAxis::Z => "+Z",
            UpAxis::NegX => "-X",
            UpAxis::NegY => "-Y",
            UpAxis::NegZ => "-Z",
        }
    }

    /// Parses `x`, `+x`, `-x` (any case) and likewise for y and z.
    pub fn parse(s: &str) -> Result<UpAxis, String> {
        let t = s.trim().to_ascii_lowercase();
        let (neg, axis) = match t.strip_prefix('-') {
            Some(a) => (true, a),
            None => (false, t.strip_prefix('+').unwrap_or(&t)),
        };
        Ok(match (neg, axis) {
            (false, "x") => UpAxis::X,
            (false, "y") => UpAxis::Y,
            (false, "z") => UpAxis::Z,
            (true, "x") => UpAxis::NegX,
            (true, "y") => UpAxis::NegY,
            (true, "z") => UpAxis::NegZ,
            _ => return Err(format!("`{s}` is not an up axis: one of x, y, z, -x, -y, -z")),
        })
    }

    /// The axis the vector `v` leans to most, with its sign (a camera file's up vector).
    pub fn nearest(v: Vec3) -> UpAxis {
        let best = UpAxis::ALL
            .into_iter()
            .max_by(|a, b| a.vector().dot(v).total_cmp(&b.vector().dot(v)));
        best.unwrap_or_default()
    }
}

impl std::fmt::Display for UpAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

impl std::str::FromStr for UpAxis {
    type Err = String;
    fn from_str(s: &str) -> Result<UpAxis, String> {
        UpAxis::parse(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_frame_is_right_handed_and_orthonormal_with_up_last() {
        for up in UpAxis::ALL {
            let [a, b, c] = up.frame();
            assert_eq!(a.cross(b), c, "{up}");
            assert_eq!(c, up.dvector());
            assert_eq!(up.vector().length(), 1.0);
            let d = DVec3::new(0.3, -0.7, 2.5);
            assert!((up.from_frame(up.to_frame(d)) - d).length() < 1e-12, "{up}");
            assert_eq!(up.to_frame(up.dvector()), DVec3::Z, "{up}");
        }
    }

    #[test]
    fn names_parse_back_and_older_files_still_read() {
        for up in UpAxis::ALL {
            assert_eq!(UpAxis::parse(up.label()), Ok(up));
            let json = serde_json::to_string(&up).unwrap();
            assert_eq!(serde_json::from_str::<UpAxis>(&json).unwrap(), up);
        }
        assert_eq!(UpAxis::parse("z"), Ok(UpAxis::Z));
        assert_eq!(UpAxis::parse("-Y"), Ok(UpAxis::NegY));
        assert!(UpAxis::parse("w").is_err());
        assert_eq!(serde_json::from_str::<UpAxis>("\"Z\"").unwrap(), UpAxis::Z);
        assert_eq!(serde_json::to_string(&UpAxis::Y).unwrap(), "\"Y\"");
        assert_eq!(UpAxis::nearest(Vec3::new(0.1, -0.9, 0.2)), UpAxis::NegY);
    }
}
