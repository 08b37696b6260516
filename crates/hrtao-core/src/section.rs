//! Section planes: up to `MAX_SECTIONS` planes n·p = d; geometry where n·p > d is cut away, for primary rays
//! and AO rays alike (docs/algorithm.md, "Section planes").
//!
//! On the CPU the planes classify every instance by its world bounds (`Side`): instances entirely on the cut
//! side of a plane leave the TLAS and the raster draws. On the GPU every ray (primary and AO) is clipped to the
//! kept region, which is convex (an intersection of half-spaces), so one ray interval holds exactly the kept
//! hits and the rays stay opaque (section.glsl); the rasterised primary clips with clip distances. (Making the
//! instances a plane crosses non-opaque and testing each candidate hit costs about twice as much per AO ray on
//! lavapipe: see docs/algorithm.md.)
use glam::{Mat4, Vec3};
use hrtao_scene::Aabb;
use serde::{Deserialize, Serialize};

use crate::clip::{self, HalfSpace};
use crate::gpu::MAX_SECTIONS;

/// One section plane: geometry where `normal · p > offset` is cut away.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SectionPlane {
    /// Unit normal, pointing into the cut-away half-space.
    pub normal: [f32; 3],
    pub offset: f32,
    pub enabled: bool,
}

impl Default for SectionPlane {
    fn default() -> Self {
        SectionPlane {
            normal: [1.0, 0.0, 0.0],
            offset: 0.0,
            enabled: false,
        }
    }
}

impl SectionPlane {
    /// An enabled plane; the normal is normalised (the offset is taken in the units of the unit normal).
    pub fn new(normal: [f32; 3], offset: f32) -> Result<SectionPlane, String> {
        let n = Vec3::from(normal);
        let len = n.length();
        if !(len.is_finite() && len > 0.0 && offset.is_finite()) {
            return Err(format!(
                "a section plane needs a finite, non-zero normal and a finite offset, got {normal:?}, {offset}"
            ));
        }
        Ok(SectionPlane {
            normal: (n / len).into(),
            offset: offset / len,
            enabled: true,
        })
    }

    /// Signed distance of `p` to the plane: positive on the cut side.
    pub fn distance(&self, p: Vec3) -> f32 {
        Vec3::from(self.normal).dot(p) - self.offset
    }

    /// True when `p` is cut away.
    pub fn cuts(&self, p: Vec3) -> bool {
        self.enabled && self.distance(p) > 0.0
    }

    /// The kept half-space n·p ≤ d.
    fn kept(&self) -> HalfSpace {
        HalfSpace::new(Vec3::from(self.normal), self.offset)
    }

    /// The cut half-space n·p ≥ d.
    fn cut(&self) -> HalfSpace {
        HalfSpace::new(-Vec3::from(self.normal), -self.offset)
    }

    /// The plane as the shaders take it: xyz the normal, w the offset.
    pub fn gpu(&self) -> [f32; 4] {
        [self.normal[0], self.normal[1], self.normal[2], self.offset]
    }
}

impl std::str::FromStr for SectionPlane {
    type Err = String;
    /// `nx,ny,nz,d` (the command line's `--section`).
    fn from_str(s: &str) -> Result<Self, String> {
        let v: Vec<f32> = s
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("section `{s}`: {e} (expected nx,ny,nz,d)"))?;
        let [nx, ny, nz, d] = v[..] else {
            return Err(format!("section `{s}`: expected four numbers nx,ny,nz,d"));
        };
        SectionPlane::new([nx, ny, nz], d).map_err(|e| format!("section `{s}`: {e}"))
    }
}

/// Where an instance's world bounds lie against the enabled planes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// No plane touches it.
    Kept,
    /// A plane crosses it: the rays' clipping to the kept region hides its cut part.
    Crossing,
    /// Entirely on the cut side of a plane: left out of the TLAS and of the raster draws.
    Cut,
}

/// The section planes of a view (at most `MAX_SECTIONS`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Sections {
    pub planes: Vec<SectionPlane>,
}

/// A tilted plane change is not located when its boxes add up to more than this fraction of the model's box
/// (then most of the model may change: the global F is as good).
pub const MAX_TILTED_SHARE: f32 = 0.5;

impl Sections {
    /// Where geometry of `bounds` (world min, max) appears or disappears when the planes change from `self` to
    /// `next`: for each changed plane, the slab between its old and new positions, or the region one of them cut
    /// away and the other did not (the cut region when a plane is switched on or off), clipped to `bounds`
    /// (`clip::region_boxes`: one exact box for axis planes, columns for tilted ones). None when the boxes of
    /// tilted planes cover more than `MAX_TILTED_SHARE` of `bounds`. Empty regions are dropped.
    pub fn changed_boxes(&self, next: &Sections, bounds: (Vec3, Vec3)) -> Option<Vec<(Vec3, Vec3)>> {
        let off = SectionPlane::default();
        let floor = 1e-3 * (bounds.1 - bounds.0).max_element();
        let (mut out, mut tilted) = (Vec::new(), 0.0f32);
        for i in 0..self.planes.len().max(next.planes.len()) {
            let a = self.planes.get(i).filter(|p| p.enabled).unwrap_or(&off);
            let b = next.planes.get(i).filter(|p| p.enabled).unwrap_or(&off);
            if a == b || (!a.enabled && !b.enabled) {
                continue;
            }
            // Each region: the points one position cuts away and the other keeps.
            let regions = match (a.enabled, b.enabled) {
                (true, true) => vec![vec![a.cut(), b.kept()], vec![b.cut(), a.kept()]],
                (true, false) => vec![vec![a.cut()]],
                _ => vec![vec![b.cut()]],
            };
            let axis = [a, b].iter().all(|p| !p.enabled || p.kept().axis_aligned());
            for cuts in regions {
                let boxes = clip::region_boxes(bounds, &cuts);
                if !axis {
                    tilted += boxes.iter().map(|&b| clip::volume(b, floor)).sum::<f32>();
                }
                out.extend(boxes);
            }
        }
        if tilted > MAX_TILTED_SHARE * clip::volume(bounds, floor) {
            return None;
        }
        Some(out)
    }

    /// Planes from the command line (each enabled), at most `MAX_SECTIONS`.
    pub fn new(planes: Vec<SectionPlane>) -> Result<Sections, String> {
        let s = Sections { planes };
        s.validate()?;
        Ok(s)
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.planes.len() > MAX_SECTIONS as usize {
            return Err(format!(
                "{} section planes given: at most {MAX_SECTIONS} are supported",
                self.planes.len()
            ));
        }
        for p in &self.planes {
            if p.enabled {
                SectionPlane::new(p.normal, p.offset)?;
            }
        }
        Ok(())
    }

    pub fn enabled(&self) -> impl Iterator<Item = &SectionPlane> {
        self.planes.iter().filter(|p| p.enabled)
    }

    pub fn any_enabled(&self) -> bool {
        self.enabled().next().is_some()
    }

    /// True when `p` is cut away by an enabled plane.
    pub fn cuts(&self, p: Vec3) -> bool {
        self.enabled().any(|pl| pl.cuts(p))
    }

    /// The enabled planes packed for `FrameGlobals` (unused slots zero) and their count.
    pub fn gpu(&self) -> ([[f32; 4]; MAX_SECTIONS as usize], u32) {
        let mut out = [[0.0; 4]; MAX_SECTIONS as usize];
        let mut n = 0;
        for (slot, p) in out.iter_mut().zip(self.enabled()) {
            *slot = p.gpu();
            n += 1;
        }
        (out, n)
    }

    /// Classifies the object-space box `local` under `transform` by its eight world corners.
    pub fn side(&self, local: &Aabb, transform: &Mat4) -> Side {
        if local.is_empty() || !self.any_enabled() {
            return Side::Kept;
        }
        let corners: [Vec3; 8] = std::array::from_fn(|i| {
            let pick = |bit: usize, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            transform.transform_point3(Vec3::new(
                pick(1, local.min.x, local.max.x),
                pick(2, local.min.y, local.max.y),
                pick(4, local.min.z, local.max.z),
            ))
        });
        let mut side = Side::Kept;
        for plane in self.enabled() {
            let cut = corners.iter().filter(|&&c| plane.distance(c) > 0.0).count();
            if cut == corners.len() {
                return Side::Cut;
            }
            if cut > 0 {
                side = Side::Crossing;
            }
        }
        side
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_normalises() {
        let p: SectionPlane = "2, 0, 0, 1".parse().unwrap();
        assert_eq!(p.normal, [1.0, 0.0, 0.0]);
        assert_eq!(p.offset, 0.5);
        assert!(p.enabled);
        assert!(p.cuts(Vec3::new(0.6, 0.0, 0.0)));
        assert!(!p.cuts(Vec3::new(0.4, 5.0, 0.0)));
        for bad in ["1,0,0", "0,0,0,1", "1,0,0,x", "1,0,0,inf", "1,0,0,1,2"] {
            assert!(bad.parse::<SectionPlane>().is_err(), "{bad}");
        }
    }

    #[test]
    fn classifies_boxes() {
        let s = Sections::new(vec![SectionPlane::new([1.0, 0.0, 0.0], 0.0).unwrap()]).unwrap();
        let unit = Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5));
        let at = |x: f32| Mat4::from_translation(Vec3::new(x, 0.0, 0.0));
        assert_eq!(s.side(&unit, &at(0.0)), Side::Crossing);
        assert_eq!(s.side(&unit, &at(2.0)), Side::Cut);
        assert_eq!(s.side(&unit, &at(-2.0)), Side::Kept);
        assert_eq!(Sections::default().side(&unit, &at(2.0)), Side::Kept);
        let four = vec![SectionPlane::default(); 4];
        assert!(Sections::new(four).is_err());
        let (packed, n) = s.gpu();
        assert_eq!(n, 1);
        assert_eq!(packed[0], [1.0, 0.0, 0.0, 0.0]);
    }
}
