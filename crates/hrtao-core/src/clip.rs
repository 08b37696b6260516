//! Where a section plane change acts: a world box clipped by half-spaces, as a few boxes.
//!
//! A plane change makes geometry appear or disappear in a region of the model's box bounded by planes (the slab a
//! plane swept, or the wedge between its old and new cut). That region is convex; its bounding box is exact for
//! axis planes, but for a tilted plane it can be most of the model. `region_boxes` cuts the model's box into
//! columns across the planes' normals and bounds the region within each column, so a thin tilted slab becomes a
//! staircase of thin boxes.
use glam::{Mat3, Vec3};

/// A world-space box (min, max).
pub type WorldBox = (Vec3, Vec3);

/// The half-space n·p ≤ d.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfSpace {
    pub normal: Vec3,
    pub offset: f32,
}

impl HalfSpace {
    pub fn new(normal: Vec3, offset: f32) -> HalfSpace {
        HalfSpace { normal, offset }
    }

    /// True when the normal is (close to) a coordinate axis.
    pub fn axis_aligned(&self) -> bool {
        self.normal.abs().max_element() > 1.0 - 1e-6
    }
}

/// The most boxes `region_boxes` returns for one region.
pub const COLUMN_BUDGET: usize = 32;

/// The bounding box of `bounds` ∩ every half-space of `cuts`, or None when that is empty. Exact: the region is a
/// convex polytope, and its box is that of its vertices, each the meeting point of three of its bounding planes
/// (the box's six faces and the cuts) that satisfies every constraint.
pub fn clipped_box(bounds: WorldBox, cuts: &[HalfSpace]) -> Option<WorldBox> {
    let (lo, hi) = bounds;
    if !(lo.is_finite() && hi.is_finite()) || lo.cmpgt(hi).any() {
        return None;
    }
    let mut planes: Vec<HalfSpace> = Vec::with_capacity(6 + cuts.len());
    for k in 0..3 {
        let e = Vec3::AXES[k];
        planes.push(HalfSpace::new(e, hi[k]));
        planes.push(HalfSpace::new(-e, -lo[k]));
    }
    planes.extend(
        cuts.iter()
            .filter(|c| c.normal.is_finite() && c.offset.is_finite()),
    );
    // Tolerance of the feasibility test, relative to the size of the box.
    let tol = 1e-5
        * (hi - lo)
            .length()
            .max(lo.abs().max(hi.abs()).max_element())
            .max(1e-6);
    let inside = |p: Vec3| planes.iter().all(|h| h.normal.dot(p) <= h.offset + tol);
    let mut out: Option<WorldBox> = None;
    for a in 0..planes.len() {
        for b in a + 1..planes.len() {
            for c in b + 1..planes.len() {
                let m = Mat3::from_cols(planes[a].normal, planes[b].normal, planes[c].normal).transpose();
                if m.determinant().abs() < 1e-9 {
                    continue;
                }
                let p = m.inverse() * Vec3::new(planes[a].offset, planes[b].offset, planes[c].offset);
                if p.is_finite() && inside(p) {
                    // Rounding may put a vertex a hair outside the box.
                    let p = p.clamp(lo, hi);
                    out = Some(out.map_or((p, p), |(l, h)| (l.min(p), h.max(p))));
                }
            }
        }
    }
    out
}

/// Boxes covering `bounds` ∩ `cuts`: one (exact) when every cut is axis-aligned; otherwise the model's box is cut
/// into at most `COLUMN_BUDGET` columns along the two axes the cuts' normals lean along least, each column split
/// in proportion to how much its axis tilts the planes, and the region is bounded within each column.
pub fn region_boxes(bounds: WorldBox, cuts: &[HalfSpace]) -> Vec<WorldBox> {
    let tilted: Vec<Vec3> = cuts
        .iter()
        .filter(|c| !c.axis_aligned())
        .map(|c| c.normal.abs())
        .collect();
    let Some(lean) = tilted.iter().copied().reduce(Vec3::max) else {
        return clipped_box(bounds, cuts).into_iter().collect();
    };
    let (lo, hi) = bounds;
    let extent = hi - lo;
    // The column axis k is the one the normals lean along most; the spread of a plane across a column along
    // axis i grows with |n_i| / |n_k| times the column's width.
    let k = (0..3).max_by(|&a, &b| lean[a].total_cmp(&lean[b])).unwrap_or(0);
    let spread = |i: usize| {
        tilted
            .iter()
            .map(|n| n[i] / n[k].max(1e-6))
            .fold(0.0f32, f32::max)
            * extent[i]
    };
    let mut count = [1usize; 3];
    loop {
        let next = (0..3)
            .filter(|&i| i != k && spread(i) > 0.0)
            .max_by(|&a, &b| (spread(a) / count[a] as f32).total_cmp(&(spread(b) / count[b] as f32)));
        let Some(i) = next else { break };
        if count[0] * count[1] * count[2] * 2 > COLUMN_BUDGET {
            break;
        }
        count[i] *= 2;
    }
    let mut out = Vec::new();
    let step = extent / Vec3::new(count[0] as f32, count[1] as f32, count[2] as f32);
    for x in 0..count[0] {
        for y in 0..count[1] {
            for z in 0..count[2] {
                let a = lo + step * Vec3::new(x as f32, y as f32, z as f32);
                let b = Vec3::new(
                    if x + 1 == count[0] { hi.x } else { a.x + step.x },
                    if y + 1 == count[1] { hi.y } else { a.y + step.y },
                    if z + 1 == count[2] { hi.z } else { a.z + step.z },
                );
                out.extend(clipped_box((a, b), cuts));
            }
        }
    }
    out
}

/// Volume of a box, each extent at least `floor` (so that flat models still compare).
pub fn volume((lo, hi): WorldBox, floor: f32) -> f32 {
    let e = (hi - lo).max(Vec3::splat(floor));
    e.x * e.y * e.z
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> WorldBox {
        (Vec3::ZERO, Vec3::ONE)
    }

    fn close(a: WorldBox, b: WorldBox) -> bool {
        a.0.abs_diff_eq(b.0, 1e-5) && a.1.abs_diff_eq(b.1, 1e-5)
    }

    #[test]
    fn axis_cuts_give_the_exact_box() {
        let slab = [HalfSpace::new(Vec3::X, 0.75), HalfSpace::new(-Vec3::X, -0.25)];
        let got = clipped_box(unit(), &slab).unwrap();
        assert!(
            close(got, (Vec3::new(0.25, 0.0, 0.0), Vec3::new(0.75, 1.0, 1.0))),
            "{got:?}"
        );
        assert_eq!(region_boxes(unit(), &slab), vec![got]);
        // Outside the box: empty.
        assert_eq!(clipped_box(unit(), &[HalfSpace::new(Vec3::X, -0.5)]), None);
        assert_eq!(clipped_box((Vec3::ONE, Vec3::ZERO), &[]), None);
    }

    #[test]
    fn a_tilted_cut_gives_its_corner() {
        // x + y ≥ 1.5 (n·p ≤ d with n = -(1,1)/√2): the corner triangle of the unit square, extruded in z.
        let n = Vec3::new(1.0, 1.0, 0.0).normalize();
        let got = clipped_box(unit(), &[HalfSpace::new(-n, -1.5 * n.x)]).unwrap();
        assert!(close(got, (Vec3::new(0.5, 0.5, 0.0), Vec3::ONE)), "{got:?}");
    }

    #[test]
    fn a_thin_tilted_slab_becomes_thin_columns() {
        // The slab 0.5 ≤ n·p ≤ 0.52 across a 10 x 10 x 1 box, n leaning 30° from x toward y.
        let n = Vec3::new(30f32.to_radians().cos(), 30f32.to_radians().sin(), 0.0);
        let bounds = (Vec3::new(-5.0, -5.0, 0.0), Vec3::new(5.0, 5.0, 1.0));
        let slab = [HalfSpace::new(n, 0.52), HalfSpace::new(-n, -0.5)];
        let whole = clipped_box(bounds, &slab).unwrap();
        let cols = region_boxes(bounds, &slab);
        assert!(!cols.is_empty() && cols.len() <= COLUMN_BUDGET);
        let sum: f32 = cols.iter().map(|&b| volume(b, 0.0)).sum();
        assert!(
            sum < 0.15 * volume(whole, 0.0),
            "columns {sum} against one box {}",
            volume(whole, 0.0)
        );
        // The columns cover the slab: points on it lie in some column.
        for t in 0..50 {
            let y = -5.0 + 10.0 * t as f32 / 49.0;
            for d in [0.5, 0.51, 0.52] {
                let x = (d - n.y * y) / n.x;
                let p = Vec3::new(x, y, 0.5);
                if p.x.abs() > 5.0 {
                    continue;
                }
                assert!(
                    cols.iter()
                        .any(|(a, b)| p.cmpge(*a - 1e-4).all() && p.cmple(*b + 1e-4).all()),
                    "{p} is in no column"
                );
            }
        }
    }
}
