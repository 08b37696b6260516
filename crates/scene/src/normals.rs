//! Smooth shading normals for meshes that carry none (STL, and OBJ/PLY without `vn` / nx,ny,nz), by a crease
//! angle: faces meeting at a vertex within the angle share one normal there (the surface reads as curved), and an
//! edge between faces more than the angle apart stays sharp (the vertex is split, each side keeps its own normal).
//!
//! The default angle is the renderer's feature-edge crease (`DisplaySettings::crease_deg`, 40°), so a surface
//! smoothed here gets no crease lines and a crease sharper than 40° stays sharp and gets one.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};
use std::sync::RwLock;

use glam::Vec3;

use crate::error::SceneError;
use crate::scene::Primitive;

/// The crease angle of loads with default options: the renderer's feature-edge crease (40°).
pub const DEFAULT_CREASE_DEG: f32 = 40.0;

/// Bytes smoothing takes per input triangle, at most: the welded vertex map, face normals and corner angles,
/// the vertex-to-face lists and up to three output vertices with their normals. Loaders reserve it in the load's
/// memory budget before smoothing.
pub const SMOOTH_BYTES_PER_TRIANGLE: u64 = 3 * (12 + 12 + 4) + 12 + 12 + 3 * 4 + 3 * 24 + 12;

/// Face normals compared at one vertex, at most: a vertex shared by more distinct face normals (the apex of a
/// cone of thousands of segments) gives each of its corners its own face's normal instead of spending
/// quadratic time there.
const MAX_FAN: usize = 1024;

static DEFAULT: RwLock<Option<Option<f32>>> = RwLock::new(None);

/// Sets the crease angle of loads made from now on with default [`crate::LoadOptions`] (the command line's
/// `--smooth-angle` / `--flat-normals`): `None` keeps face normals. The value must pass [`check_crease`].
pub fn set_default_crease_deg(crease_deg: Option<f32>) {
    *DEFAULT.write().unwrap_or_else(|e| e.into_inner()) = Some(crease_deg);
}

/// The crease angle [`set_default_crease_deg`] set, if it was called.
pub fn command_line_crease_deg() -> Option<Option<f32>> {
    *DEFAULT.read().unwrap_or_else(|e| e.into_inner())
}

/// The crease angle of default load options: the command line's, else [`DEFAULT_CREASE_DEG`].
pub(crate) fn default_crease_deg() -> Option<f32> {
    command_line_crease_deg().unwrap_or(Some(DEFAULT_CREASE_DEG))
}

/// Checks a crease angle: a finite number of degrees within 0..=180.
pub fn check_crease(crease_deg: f32) -> Result<f32, String> {
    if crease_deg.is_finite() && (0.0..=180.0).contains(&crease_deg) {
        Ok(crease_deg)
    } else {
        Err(format!(
            "the smoothing crease angle must be within 0..=180 degrees, got {crease_deg}"
        ))
    }
}

/// Gives `prim` smooth normals by `crease_deg` if it has none (a primitive with its own normals is left as it
/// is); `None` keeps face normals. A bad angle is [`SceneError::Invalid`] naming `source`.
pub(crate) fn smooth_primitive(
    prim: &mut Primitive,
    crease_deg: Option<f32>,
    source: &std::path::Path,
) -> Result<(), SceneError> {
    let Some(deg) = crease_deg else {
        return Ok(());
    };
    let deg = check_crease(deg).map_err(|e| SceneError::Invalid(format!("{}: {e}", source.display())))?;
    if !prim.normals.is_empty() || prim.indices.is_empty() {
        return Ok(());
    }
    let (positions, indices, normals) = smooth(
        &std::mem::take(&mut prim.positions),
        &std::mem::take(&mut prim.indices),
        deg,
    );
    (prim.positions, prim.indices, prim.normals) = (positions, indices, normals);
    Ok(())
}

/// A position's bits (-0.0 and 0.0 the same point), hashed as two words.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Key([u32; 3]);

impl Key {
    fn of(p: [f32; 3]) -> Key {
        Key(p.map(|c| if c == 0.0 { 0 } else { c.to_bits() }))
    }
}

impl Hash for Key {
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64(self.0[0] as u64 | (self.0[1] as u64) << 32);
        state.write_u64(self.0[2] as u64);
    }
}

/// A multiply-rotate hash of the key's two words with a final avalanche (murmur3's fmix64): several times
/// faster than SipHash on the weld map's tens of millions of lookups. The keys come from a file, not from an
/// adversary who could gain more than a slower load from collisions.
#[derive(Default)]
struct Mix(u64);

impl Hasher for Mix {
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(26) ^ v).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

/// Smooth normals by a crease angle: returns new positions, indices and one normal per position.
///
/// - Corners are welded by exact position (STL stores every triangle's corners apart; OBJ/PLY may repeat a
///   position under several indices).
/// - Each face's normal is weighted by its corner angle at the vertex (so the result does not depend on how a
///   surface is split into triangles).
/// - A corner takes the normals of the faces around its vertex within `crease_deg` of its own face; corners
///   of a vertex that end with different normals get separate output vertices (the crease stays sharp).
/// - Degenerate triangles (zero area, non-finite corners) add nothing; they are kept, their corners get a
///   normal of a neighbour (or +z), so the count stays one per position.
///
/// Expected O(n) time (a hash map for the weld, vertex-to-face lists; each vertex compares the distinct face
/// normals around it, at most `MAX_FAN`).
pub fn smooth(
    positions: &[[f32; 3]],
    indices: &[u32],
    crease_deg: f32,
) -> (Vec<[f32; 3]>, Vec<u32>, Vec<[f32; 3]>) {
    let cos_crease = crease_deg.clamp(0.0, 180.0).to_radians().cos() - 1e-6;
    let tris = indices.len() / 3;
    let corner_pos = |c: usize| -> [f32; 3] {
        positions
            .get(indices[c] as usize)
            .copied()
            .unwrap_or([f32::NAN; 3])
    };

    // 1. Weld corners by exact position: `weld[c]` is corner c's welded vertex.
    // An STL's corners weld to about a sixth as many vertices; indexed meshes (OBJ, PLY) have about as many
    // positions as vertices.
    let mut map: HashMap<Key, u32, BuildHasherDefault<Mix>> = HashMap::default();
    map.reserve(positions.len().min(tris * 3 / 4));
    let mut welded: Vec<[f32; 3]> = Vec::new();
    let weld: Vec<u32> = (0..tris * 3)
        .map(|c| {
            let p = corner_pos(c);
            *map.entry(Key::of(p)).or_insert_with(|| {
                welded.push(p);
                welded.len() as u32 - 1
            })
        })
        .collect();
    drop(map);
    let nv = welded.len();

    // 2. Face normals (unit; None for degenerate triangles) and corner angles.
    let mut face: Vec<Option<Vec3>> = Vec::with_capacity(tris);
    let mut angle: Vec<f32> = Vec::with_capacity(tris * 3);
    for t in 0..tris {
        let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(welded[weld[3 * t + k] as usize]));
        let n = (b - a).cross(c - a);
        let len = n.length();
        let ok = len.is_finite() && len > 0.0 && a.is_finite() && b.is_finite() && c.is_finite();
        face.push(ok.then(|| n / len));
        let corner = |p: Vec3, q: Vec3, r: Vec3| -> f32 {
            let (u, v) = (q - p, r - p);
            let a = u.angle_between(v);
            if a.is_finite() {
                a
            } else {
                0.0
            }
        };
        angle.extend([corner(a, b, c), corner(b, c, a), corner(c, a, b)]);
    }

    // 3. Vertex-to-corner lists (CSR): corners of non-degenerate faces around each welded vertex.
    let mut start = vec![0u32; nv + 1];
    for c in 0..tris * 3 {
        if face[c / 3].is_some() {
            start[weld[c] as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; start[nv] as usize];
    for c in 0..tris * 3 {
        if face[c / 3].is_some() {
            let v = weld[c] as usize;
            around[fill[v] as usize] = c as u32;
            fill[v] += 1;
        }
    }
    drop(fill);

    // 4. Per vertex: the distinct face normals around it (with summed corner angles), then each corner's normal
    //    from those within the crease of its own face; corners with equal normals share an output vertex.
    let mut out_pos: Vec<[f32; 3]> = Vec::with_capacity(nv + nv / 4);
    let mut out_nrm: Vec<[f32; 3]> = Vec::with_capacity(nv + nv / 4);
    let mut out_idx = vec![u32::MAX; tris * 3];
    let mut groups: Vec<(Vec3, f32)> = Vec::new();
    let mut group_of: Vec<usize> = Vec::new();
    let mut vertex_of: Vec<u32> = Vec::new();
    for v in 0..nv {
        let corners = &around[start[v] as usize..start[v + 1] as usize];
        if corners.is_empty() {
            continue;
        }
        groups.clear();
        group_of.clear();
        for &c in corners {
            let n = face[c as usize / 3].unwrap_or(Vec3::Z);
            let w = angle[c as usize];
            let found = if groups.len() <= MAX_FAN {
                groups.iter().position(|(m, _)| *m == n)
            } else {
                None
            };
            let g = match found {
                Some(g) => {
                    groups[g].1 += w;
                    g
                }
                None => {
                    groups.push((n, w));
                    groups.len() - 1
                }
            };
            group_of.push(g);
        }
        vertex_of.clear();
        let first = out_pos.len();
        for &(own, _) in &groups {
            let n = if groups.len() > MAX_FAN {
                own
            } else {
                let sum: Vec3 = groups
                    .iter()
                    .filter(|(m, _)| m.dot(own) >= cos_crease)
                    .map(|(m, w)| *m * *w)
                    .sum();
                match sum.normalize_or_zero() {
                    Vec3::ZERO => own,
                    n => n,
                }
            }
            .to_array();
            // Groups within the crease of each other often end with the same normal: they share a vertex.
            let shared = if groups.len() <= MAX_FAN {
                (first..out_nrm.len()).find(|&o| out_nrm[o] == n)
            } else {
                None
            };
            vertex_of.push(match shared {
                Some(o) => o as u32,
                None => {
                    out_pos.push(welded[v]);
                    out_nrm.push(n);
                    out_pos.len() as u32 - 1
                }
            });
        }
        for (k, &c) in corners.iter().enumerate() {
            out_idx[c as usize] = vertex_of[group_of[k]];
        }
    }

    // 5. Corners of degenerate triangles: a vertex already made at the same position, else a new one (+z).
    if face.iter().all(Option::is_some) {
        return (out_pos, out_idx, out_nrm);
    }
    let first_at: Vec<u32> = {
        let mut f = vec![u32::MAX; nv];
        for c in 0..tris * 3 {
            if out_idx[c] != u32::MAX && f[weld[c] as usize] == u32::MAX {
                f[weld[c] as usize] = out_idx[c];
            }
        }
        f
    };
    let mut first_at = first_at;
    for c in 0..tris * 3 {
        if out_idx[c] == u32::MAX {
            let v = weld[c] as usize;
            if first_at[v] == u32::MAX {
                out_pos.push(welded[v]);
                out_nrm.push([0.0, 0.0, 1.0]);
                first_at[v] = out_pos.len() as u32 - 1;
            }
            out_idx[c] = first_at[v];
        }
    }
    (out_pos, out_idx, out_nrm)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of a square folded by `fold_deg` along the x axis.
    fn folded(fold_deg: f32) -> (Vec<[f32; 3]>, Vec<u32>) {
        let (s, c) = fold_deg.to_radians().sin_cos();
        // First triangle in the z=0 plane (normal +z), the second turned about x by fold_deg.
        let p = vec![
            [0.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, c, s],
        ];
        (p, vec![0, 1, 2, 3, 4, 5])
    }

    #[test]
    fn shallow_folds_share_a_normal_and_sharp_ones_split() {
        let (p, i) = folded(30.0);
        let (pos, idx, n) = smooth(&p, &i, 40.0);
        assert_eq!(pos.len(), 4, "the shared edge is welded: {pos:?}");
        assert_eq!(idx.len(), 6);
        // The shared corners point halfway (15° from +z about x).
        let mid = Vec3::from(n[idx[0] as usize]);
        let want = Vec3::new(0.0, -(15f32.to_radians().sin()), 15f32.to_radians().cos());
        assert!(mid.abs_diff_eq(want, 1e-5), "{mid} vs {want}");
        let (pos, idx, n) = smooth(&folded(50.0).0, &i, 40.0);
        assert_eq!(pos.len(), 6, "a 50° fold stays sharp at 40°");
        assert!(idx[..3]
            .iter()
            .all(|&v| Vec3::from(n[v as usize]).abs_diff_eq(Vec3::Z, 1e-6)));
    }

    #[test]
    fn degenerate_triangles_add_nothing_and_keep_a_normal() {
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0]];
        // A real triangle, a zero-area one on its edge, one with an index past the positions.
        let i = vec![0, 1, 2, 0, 1, 3, 0, 1, 9];
        let (pos, idx, n) = smooth(&p, &i, 40.0);
        assert_eq!(n.len(), pos.len());
        assert!(n.iter().all(|v| Vec3::from(*v).is_normalized()));
        assert_eq!(n[idx[0] as usize], [0.0, 0.0, 1.0]);
        assert_eq!(idx.len(), 9);
    }

    #[test]
    fn bad_angles_are_refused() {
        assert!(check_crease(40.0).is_ok() && check_crease(0.0).is_ok() && check_crease(180.0).is_ok());
        for bad in [-1.0, 180.5, f32::NAN, f32::INFINITY] {
            assert!(check_crease(bad).unwrap_err().contains("0..=180"), "{bad}");
        }
    }
}
