//! Axis-aligned bounding boxes.

use glam::{Mat4, Vec3};

/// Axis-aligned bounding box. An empty box has `min > max` on every axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::empty()
    }
}

impl Aabb {
    /// The empty box (identity for [`Aabb::union`] and [`Aabb::extend`]).
    pub fn empty() -> Self {
        Self {
            min: Vec3::splat(f32::INFINITY),
            max: Vec3::splat(f32::NEG_INFINITY),
        }
    }

    /// Box spanning `min..max` as given.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// Smallest box containing all `points` (empty if there are none).
    pub fn from_points<I: IntoIterator<Item = Vec3>>(points: I) -> Self {
        let mut b = Self::empty();
        for p in points {
            b.extend(p);
        }
        b
    }

    /// Grows the box to contain `p`.
    pub fn extend(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Smallest box containing both boxes.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// True if the box contains no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Centre of the box (zero for an empty box).
    pub fn center(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            (self.min + self.max) * 0.5
        }
    }

    /// `max - min` (zero for an empty box).
    pub fn diagonal(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// The 8 corners of the box.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// Box containing the 8 transformed corners (empty stays empty).
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        Aabb::from_points(self.corners().iter().map(|&c| m.transform_point3(c)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_union_extend() {
        let mut b = Aabb::empty();
        assert!(b.is_empty());
        assert_eq!(b.diagonal(), Vec3::ZERO);
        b.extend(Vec3::new(1.0, 2.0, 3.0));
        assert!(!b.is_empty());
        b.extend(Vec3::new(-1.0, 0.0, 5.0));
        assert_eq!(b.min, Vec3::new(-1.0, 0.0, 3.0));
        assert_eq!(b.max, Vec3::new(1.0, 2.0, 5.0));
        assert_eq!(b.center(), Vec3::new(0.0, 1.0, 4.0));
        assert_eq!(b.diagonal(), Vec3::new(2.0, 2.0, 2.0));
        let u = Aabb::empty().union(&b);
        assert_eq!(u, b);
    }

    #[test]
    fn transformed_rotation_covers_corners() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0));
        let m = Mat4::from_translation(Vec3::new(10.0, 0.0, 0.0))
            * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let t = b.transformed(&m);
        assert!((t.min - Vec3::new(9.0, 0.0, 0.0)).length() < 1e-5, "{t:?}");
        assert!((t.max - Vec3::new(10.0, 2.0, 1.0)).length() < 1e-5, "{t:?}");
        assert!(Aabb::empty().transformed(&m).is_empty());
    }
}
