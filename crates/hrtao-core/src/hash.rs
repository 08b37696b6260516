//! CPU mirror of `shaders/hash.glsl`: the HRTAO world-space hash (paper §1-2, eq. 1-6), bit for bit.
//!
//! Tested against the GPU in `tests/hash_gpu.rs`. Positions are quantised exactly (power-of-two cell sizes,
//! see the shader's header comment), so the CPU and the GPU agree on every key.
use glam::{IVec3, Vec3};

use crate::gpu::EMPTY_CELL;

/// "lowbias32" (C. Wellons): the index hash `h` of eq. (1).
pub fn h_index(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// PCG RXS-M-XS: the independent checksum hash (§1).
pub fn h_check(x: u32) -> u32 {
    let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// log2 of s_min rounded to an integer: s_min is used as the power of two nearest to it (eq. 3).
pub fn log2_s_min(s_min: f32) -> i32 {
    (s_min.max(f32::MIN_POSITIVE) as f64).log2().round() as i32
}

/// eq. (2) as we read it: s_w = d · s_p · (2 tan(f_y / 2) / R_y), the world width of s_p pixels at distance d
/// for a pinhole camera of vertical aperture f_y spanning R_y view pixels (square pixels). Returned per unit
/// of d. The paper's max(f/R_x, f R_x/R_y²) with f the vertical aperture gives cells R_x/R_y (1.8 at 16:9)
/// times too large; see docs/algorithm.md.
pub fn feature_size_per_distance(fov_y_radians: f32, view_height: u32, s_p: f32) -> f32 {
    s_p * 2.0 * (0.5 * fov_y_radians).tan() / view_height.max(1) as f32
}

/// eq. (2) as an affine function of the hit distance d: s_w = base + d · per_distance. Perspective: base = 0
/// and per_distance = `feature_size_per_distance`; orthographic: a pixel spans ortho_height / R_y world units
/// at any distance, so base = s_p · ortho_height / R_y and per_distance = 0 (docs/algorithm.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatureSize {
    pub base: f32,
    pub per_distance: f32,
}

impl FeatureSize {
    /// eq. (2) for `camera` (its projection, field of view or ortho height) spanning `view_height` view pixels.
    pub fn for_camera(camera: &crate::Camera, view_height: u32, s_p: f32) -> FeatureSize {
        match camera.projection {
            crate::camera::Projection::Perspective => FeatureSize {
                base: 0.0,
                per_distance: feature_size_per_distance(camera.fov_y_deg.to_radians(), view_height, s_p),
            },
            crate::camera::Projection::Orthographic => FeatureSize {
                base: s_p * camera.ortho_height / view_height.max(1) as f32,
                per_distance: 0.0,
            },
        }
    }

    /// s_w at hit distance d (hash_map.glsl evaluates the same expression: bit-identical, as one term is 0).
    pub fn at(&self, d: f32) -> f32 {
        self.base + d * self.per_distance
    }
}

/// eq. (3) as an integer LOD: floor(log2(s_w)), at least log2(s_min); the cell size is s_wd = 2^lod.
pub fn lod_of(s_w: f32, log2_s_min: i32) -> i32 {
    if s_w.is_nan() || s_w <= 0.0 || s_w.is_infinite() {
        return log2_s_min;
    }
    let biased = ((s_w.to_bits() >> 23) & 0xff) as i32;
    if biased == 0 {
        return log2_s_min; // subnormal: far below any s_min
    }
    (biased - 127).max(log2_s_min)
}

/// The LOD of a pixel at hit distance d (hash_map.glsl `pixel_lod`): s_w = `size.at(d)`, at most s_w_max.
pub fn pixel_lod(d: f32, size: FeatureSize, s_w_max: f32, log2_s_min: i32) -> i32 {
    lod_of(size.at(d).min(s_w_max), log2_s_min)
}

/// s_wd of eq. (3) for a LOD.
pub fn cell_size(lod: i32) -> f32 {
    2f32.powi(lod)
}

/// floor(p / s_wd), clamped to the int range.
pub fn cell_coord(p: Vec3, lod: i32) -> IVec3 {
    let scale = 2f32.powi(-lod);
    let q = (p * scale)
        .floor()
        .clamp(Vec3::splat(-2_147_483_520.0), Vec3::splat(2_147_483_520.0));
    q.as_ivec3()
}

/// eq. (5)'s normal bins: s_nd per unit of a normal component, shifted by `offset` bins (see hash.glsl).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalBins {
    pub s_nd: f32,
    pub offset: f32,
}

impl NormalBins {
    /// eq. (5) as published: floor(n s_nd).
    pub fn paper(s_nd: f32) -> NormalBins {
        NormalBins { s_nd, offset: 0.0 }
    }

    /// The components where a bin ends, in [-1, 1]: n s_nd + offset is an integer.
    pub fn edges(self) -> Vec<f32> {
        let lo = (-self.s_nd + self.offset).ceil() as i64;
        let hi = (self.s_nd + self.offset).floor() as i64;
        (lo..=hi).map(|k| (k as f32 - self.offset) / self.s_nd).collect()
    }
}

/// eq. (5)'s normal quantisation: floor(n s_nd + offset), per component (see hash.glsl).
pub fn normal_coord(n: Vec3, bins: NormalBins) -> IVec3 {
    (n.clamp(Vec3::splat(-1.0), Vec3::splat(1.0)) * bins.s_nd + Vec3::splat(bins.offset))
        .floor()
        .as_ivec3()
}

/// eq. (4)-(6) chained with one base hash `h`: h(F + H7D), H7D = h(nz + h(ny + h(nx + H4D))),
/// H4D = h(lod + h(pz + h(py + h(px)))). Ours (local edits): a non-zero region epoch E adds one step,
/// h(F + h(E + H7D)); E = 0 is the paper's key.
pub fn h8d(h: fn(u32) -> u32, c: IVec3, lod: i32, nq: IVec3, frame: u32, epoch: u32) -> u32 {
    let mut k = h(c.x as u32);
    k = h((c.y as u32).wrapping_add(k));
    k = h((c.z as u32).wrapping_add(k));
    k = h((lod as u32).wrapping_add(k)); // eq. (4): s_wd embedded
    k = h((nq.x as u32).wrapping_add(k)); // eq. (5)
    k = h((nq.y as u32).wrapping_add(k));
    k = h((nq.z as u32).wrapping_add(k));
    if epoch != 0 {
        k = h(epoch.wrapping_add(k));
    }
    h(frame.wrapping_add(k)) // eq. (6)
}

/// A cell's slot (before probing) and checksum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellKey {
    pub slot: u32,
    pub checksum: u32,
}

/// The key of integer cell `c` at LOD `lod` with quantised normal `nq`, F `frame` and region epoch `epoch`.
pub fn cell_key_at(c: IVec3, lod: i32, nq: IVec3, frame: u32, epoch: u32, capacity: u32) -> CellKey {
    let slot = h8d(h_index, c, lod, nq, frame, epoch) & (capacity - 1);
    let check = h8d(h_check, c, lod, nq, frame, epoch);
    CellKey {
        slot,
        checksum: if check == EMPTY_CELL { 1 } else { check },
    }
}

pub fn cell_key(
    p: Vec3,
    n: Vec3,
    lod: i32,
    bins: NormalBins,
    frame: u32,
    epoch: u32,
    capacity: u32,
) -> CellKey {
    cell_key_at(
        cell_coord(p, lod),
        lod,
        normal_coord(n, bins),
        frame,
        epoch,
        capacity,
    )
}

/// hash.glsl `region_entry`: the epoch table entry of region `r` of grid `grid` (regions of edge 2^(grid+1)).
pub fn region_entry(r: IVec3, grid: i32) -> u32 {
    let mut k = h_index(grid as u32);
    k = h_index((r.x as u32).wrapping_add(k));
    k = h_index((r.y as u32).wrapping_add(k));
    k = h_index((r.z as u32).wrapping_add(k));
    k & (crate::gpu::REGION_COUNT - 1)
}

/// hash.glsl `region_index`: the epoch table entry of integer cell `c` at LOD `lod`, grid max(lod, region_lod).
pub fn region_index(c: IVec3, lod: i32, region_lod: i32) -> u32 {
    let grid = lod.max(region_lod);
    region_entry(c >> (grid + 1 - lod).clamp(0, 31), grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_size_is_affine_in_distance_per_projection() {
        let persp = crate::Camera {
            fov_y_deg: 60.0,
            ..Default::default()
        };
        let p = FeatureSize::for_camera(&persp, 360, 4.0);
        assert_eq!(p.base, 0.0);
        assert_eq!(
            p.at(7.0),
            7.0 * feature_size_per_distance(60f32.to_radians(), 360, 4.0)
        );
        // Orthographic: s_p pixels of ortho_height / R_y world units, at any distance.
        let ortho = crate::Camera {
            projection: crate::camera::Projection::Orthographic,
            ortho_height: 9.0,
            ..persp
        };
        let o = FeatureSize::for_camera(&ortho, 360, 4.0);
        assert_eq!(o.per_distance, 0.0);
        assert_eq!(o.at(0.5), 0.1);
        assert_eq!(o.at(5000.0), 0.1);
        // The orthographic camera framing the perspective view at distance d gives the same cells there.
        let d = 3.0;
        let framed = crate::Camera {
            ortho_height: persp.view_height_at(d),
            ..ortho
        };
        let f = FeatureSize::for_camera(&framed, 360, 4.0);
        assert!((f.at(123.0) - p.at(d)).abs() < 1e-6);
    }

    #[test]
    fn lod_is_a_power_of_two_and_steps_when_distance_doubles() {
        let l2 = log2_s_min(1e-10);
        assert_eq!(l2, -33);
        let aperture = 40f32.to_radians();
        let mut last = None;
        for i in 0..20 {
            let d = 0.37 * 2f32.powi(i);
            let s_w = d * feature_size_per_distance(aperture, 180, 8.0);
            let lod = lod_of(s_w, l2);
            let s_wd = cell_size(lod);
            // s_wd = 2^floor(log2(s_w / s_min)) s_min, with s_min a power of two: s_wd <= s_w < 2 s_wd.
            assert!(s_wd <= s_w && s_w < 2.0 * s_wd, "d={d}: s_w={s_w}, s_wd={s_wd}");
            if let Some(prev) = last {
                assert_eq!(lod, prev + 1, "doubling the distance moves one LOD up");
            }
            last = Some(lod);
        }
        assert_eq!(lod_of(0.0, l2), l2);
        assert_eq!(lod_of(f32::NAN, l2), l2);
        assert_eq!(lod_of(1e-30, l2), l2);
    }

    #[test]
    fn a_finest_cell_spans_half_to_all_of_s_p_view_pixels() {
        // 640x360, 40° vertical aperture: one pixel at distance d is d 2 tan(20°) / 360 wide.
        let aperture = 40f32.to_radians();
        let pixel = 2.0 * (0.5 * aperture).tan() / 360.0;
        for d in [0.3f32, 1.0, 7.7, 150.0, 4000.0] {
            let s_w = d * feature_size_per_distance(aperture, 360, 3.0);
            let cell = cell_size(lod_of(s_w, -33));
            let pixels = cell / (d * pixel);
            assert!(
                (1.5..=3.0001).contains(&pixels),
                "d={d}: a cell spans {pixels} pixels"
            );
        }
        // s_w is capped (a fraction of the AO radius): far away, cells stop growing.
        assert_eq!(
            pixel_lod(
                1e6,
                FeatureSize {
                    base: 0.0,
                    per_distance: 0.01
                },
                0.25,
                -33
            ),
            lod_of(0.25, -33)
        );
    }

    /// The normal components of CAD faces: axes (0, ±1), 30°/60° chamfers and hexagon faces (±1/2, ±√3/2),
    /// 45° chamfers (±√2/2).
    const CAD_COMPONENTS: [f32; 9] = [
        0.0,
        0.5,
        -0.5,
        std::f32::consts::FRAC_1_SQRT_2,
        -std::f32::consts::FRAC_1_SQRT_2,
        0.866_025_4,
        -0.866_025_4,
        1.0,
        -1.0,
    ];

    /// At the default s_nd and offset no bin edge lies within 0.02 of a CAD face's normal component, so a face
    /// does not split between bins on rounding noise. Catches the old centred bins, floor(3n + 1/2) (edges at
    /// ±1/2), and the paper's floor(3n) (edges at 0) as a default.
    #[test]
    fn default_normal_bins_keep_cad_normals_off_their_edges() {
        let d = crate::AoSettings::default().map;
        let bins = NormalBins {
            s_nd: d.s_nd,
            offset: d.normal_offset(),
        };
        let edges = bins.edges();
        assert!(edges.len() >= 2 * d.s_nd as usize, "{edges:?}");
        for e in &edges {
            for c in CAD_COMPONENTS {
                assert!(
                    (e - c).abs() >= 0.02,
                    "bin edge {e} is {} from {c}",
                    (e - c).abs()
                );
            }
        }
        // Each edge is where the bin changes: just below and above it the bins differ.
        for e in edges.iter().filter(|e| e.abs() < 1.0) {
            let at = |x: f32| normal_coord(Vec3::new(x, 0.0, 0.0), bins).x;
            assert_eq!(at(e + 1e-4), at(e - 1e-4) + 1, "edge {e}");
        }
        // A normal a rounding error off a CAD direction stays in its bin.
        for &c in &CAD_COMPONENTS {
            let n = Vec3::new(c, (1.0 - c * c).max(0.0).sqrt(), 0.0);
            let off = (n + Vec3::new(1e-6, -1e-6, 1e-6)).normalize();
            assert_eq!(normal_coord(n, bins), normal_coord(off, bins), "{n}");
        }
    }

    /// The paper's mode keeps eq. (5) as published: floor(n s_nd).
    #[test]
    fn paper_normal_bins_are_eq_5() {
        let p = crate::AoSettings::default().paper().map;
        assert_eq!(p.normal_offset(), 0.0);
        let bins = NormalBins {
            s_nd: p.s_nd,
            offset: p.normal_offset(),
        };
        for x in [-1.0f32, -0.7, -0.34, -0.01, 0.0, 0.2, 0.34, 0.5, 0.99, 1.0] {
            let n = Vec3::new(x, 0.0, 0.0);
            assert_eq!(normal_coord(n, bins).x, (x * p.s_nd).floor() as i32, "{x}");
        }
    }

    #[test]
    fn keys_separate_position_normal_lod_and_frame() {
        let p = Vec3::new(1.25, -3.5, 7.0);
        let n = Vec3::Z;
        let base = cell_key(p, n, -2, NormalBins::paper(3.0), 0, 0, 1 << 20);
        assert_eq!(
            base,
            cell_key(
                p + Vec3::splat(0.01),
                n,
                -2,
                NormalBins::paper(3.0),
                0,
                0,
                1 << 20
            ),
            "same cell"
        );
        assert_ne!(
            base.checksum,
            cell_key(p + Vec3::X, n, -2, NormalBins::paper(3.0), 0, 0, 1 << 20).checksum,
            "next cell"
        );
        assert_ne!(
            base.checksum,
            cell_key(p, -n, -2, NormalBins::paper(3.0), 0, 0, 1 << 20).checksum,
            "other normal"
        );
        assert_ne!(
            base.checksum,
            cell_key(p, n, -1, NormalBins::paper(3.0), 0, 0, 1 << 20).checksum,
            "other LOD"
        );
        assert_ne!(
            base.checksum,
            cell_key(p, n, -2, NormalBins::paper(3.0), 1, 0, 1 << 20).checksum,
            "other F"
        );
        // A region epoch makes a new key, distinct from every F's epoch-0 key and from the next F's.
        let e1 = cell_key(p, n, -2, NormalBins::paper(3.0), 0, 1, 1 << 20);
        assert_ne!(base.checksum, e1.checksum, "other epoch");
        assert_ne!(
            e1.checksum,
            cell_key(p, n, -2, NormalBins::paper(3.0), 1, 0, 1 << 20).checksum
        );
        assert_ne!(
            e1.checksum,
            cell_key(p, n, -2, NormalBins::paper(3.0), 1, 1, 1 << 20).checksum
        );
        assert!(base.slot < 1 << 20 && base.checksum != EMPTY_CELL);
    }

    #[test]
    fn a_region_holds_whole_cells_and_negative_coordinates_floor() {
        // region_lod 1: cells of LOD <= 1 lie in regions of edge 4 (grid 1), LOD 2 in regions of edge 8.
        let r = |x: i32, lod: i32| region_index(IVec3::new(x, 0, 0), lod, 1);
        // LOD 0 cells at x = -4..-1 (world -4..0) share a region, x = 0 starts the next.
        assert_eq!(r(-4, 0), r(-1, 0));
        assert_ne!(r(-1, 0), r(0, 0));
        assert_eq!(r(0, 0), r(3, 0));
        // A LOD 1 cell at x = 1 (world 2..4) lies in the region of world 0..4, as do finer cells there.
        assert_eq!(r(1, 1), r(0, 0));
        assert_eq!(r(7, -1), r(0, 0));
        // Coarser LODs have their own grid: regions two cells across.
        assert_eq!(r(0, 2), r(1, 2));
        assert_ne!(r(1, 2), r(2, 2));
        assert_eq!(r(-2, 2), region_entry(IVec3::new(-1, 0, 0), 2));
    }
}
