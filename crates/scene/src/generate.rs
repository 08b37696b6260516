//! Procedural CAD-like scenes, selected by spec strings `gen:NAME?key=value&...`.
//!
//! All generators use metres and are **Z-up** (ground at z = 0).
//!
//! | spec | parameters (default) | content |
//! |---|---|---|
//! | `gen:racks` | `rows` (25), `cols` (100), `units` (40), `detail` (2000) | server room: floor slab, rows×cols rack frames, `units` 1U servers per rack; the server mesh has exactly `detail` triangles (vent louvres). Defaults give 102,501 instances. |
//! | `gen:city` | `blocks` (8), `per_block` (3), `variants` (6), `floors` (30), `seed` (1) | blocks×blocks city blocks, per_block² instanced towers with recessed windows per block, a kerb slab per block, and a ground plane |
//! | `gen:box` | `size` (2) | closed-top box open towards −Y (inside corners for AO tests) |
//! | `gen:plane` | `size` (100) | one square quad at z = 0 |
//! | `gen:slab` | `h` (1), `size` (10), `ground` (100) | ground quad plus a `size`×`size`×0.1 slab whose underside is at z = `h` |
//!
//! Each unique mesh is built once; instances only carry transforms, so `gen:racks` with
//! `rows=100&cols=100&units=40&detail=2500` (10⁹ instanced triangles) is cheap to generate.
//! Parameters are parsed strictly: unknown or repeated keys, non-numeric, negative or
//! out-of-range values are [`SceneError::BadGeneratorParam`].

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Mat4, Vec3};

use crate::error::SceneError;
use crate::scene::{Instance, LoadProgress, Mesh, Primitive, Scene};

/// Upper bound of triangles in one generated mesh.
pub const MAX_MESH_TRIANGLES: u64 = 50_000_000;
/// Upper bound of generated instances.
pub const MAX_INSTANCES: u64 = 10_000_000;

/// The six faces of an axis-aligned box (-x, +x, -y, +y, -z, +z) as loops of its corners, each counter-clockwise
/// seen from outside; corner `i` is the one [`box_corners`] returns at `i`.
pub const BOX_FACES: [[u32; 4]; 6] = [
    [0, 4, 6, 2],
    [1, 3, 7, 5],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 2, 3, 1],
    [4, 5, 7, 6],
];

/// The eight corners of the axis-aligned box `min..max`: corner `i` takes its x from `max` where bit 0 of `i` is set
/// (else from `min`), its y where bit 1 is, its z where bit 2 is. [`BOX_FACES`] and [`box_triangles`] index them.
pub fn box_corners(min: [f32; 3], max: [f32; 3]) -> [[f32; 3]; 8] {
    std::array::from_fn(|i| std::array::from_fn(|k| if i >> k & 1 != 0 { max[k] } else { min[k] }))
}

/// The box's twelve outward triangles over [`box_corners`]: each face of [`BOX_FACES`] split along its first diagonal.
pub fn box_triangles() -> [[u32; 3]; 12] {
    std::array::from_fn(|t| {
        let f = BOX_FACES[t / 2];
        if t % 2 == 0 {
            [f[0], f[1], f[2]]
        } else {
            [f[0], f[2], f[3]]
        }
    })
}

/// Generates a scene from a `gen:...` spec (the `gen:` prefix is optional).
pub fn generate(spec: &str, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    let body = spec.strip_prefix("gen:").unwrap_or(spec);
    let (name, query) = match body.split_once('?') {
        Some((n, q)) => (n, q),
        None => (body, ""),
    };
    let mut scene = match name {
        "racks" => racks(
            Params::parse(name, query, &["rows", "cols", "units", "detail"])?,
            progress,
        )?,
        "city" => city(
            Params::parse(
                name,
                query,
                &["blocks", "per_block", "variants", "floors", "seed"],
            )?,
            progress,
        )?,
        "box" => open_box(Params::parse(name, query, &["size"])?)?,
        "plane" => plane(Params::parse(name, query, &["size"])?)?,
        "slab" => slab(Params::parse(name, query, &["h", "size", "ground"])?)?,
        _ => {
            return Err(SceneError::UnknownGenerator(format!(
                "{spec:?} (known: gen:racks, gen:city, gen:box, gen:plane, gen:slab)"
            )))
        }
    };
    scene.name = spec.to_owned();
    Ok(scene)
}

/// Strictly parsed `key=value` pairs of one generator.
struct Params {
    gen: String,
    pairs: Vec<(String, String)>,
}

impl Params {
    fn parse(gen: &str, query: &str, allowed: &[&str]) -> Result<Self, SceneError> {
        let bad = |m: String| SceneError::BadGeneratorParam(format!("gen:{gen}: {m}"));
        let mut pairs: Vec<(String, String)> = Vec::new();
        if !query.is_empty() {
            for part in query.split('&') {
                let (k, v) = part
                    .split_once('=')
                    .ok_or_else(|| bad(format!("expected key=value, got {part:?}")))?;
                if !allowed.contains(&k) {
                    return Err(bad(format!(
                        "unknown parameter {k:?} (allowed: {})",
                        allowed.join(", ")
                    )));
                }
                if pairs.iter().any(|(pk, _)| pk == k) {
                    return Err(bad(format!("parameter {k:?} given twice")));
                }
                pairs.push((k.to_owned(), v.to_owned()));
            }
        }
        Ok(Self {
            gen: gen.to_owned(),
            pairs,
        })
    }

    fn raw(&self, key: &str) -> Option<&str> {
        self.pairs.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    fn bad(&self, key: &str, v: &str, why: String) -> SceneError {
        SceneError::BadGeneratorParam(format!("gen:{}: {key}={v:?}: {why}", self.gen))
    }

    /// Integer in `min..=max`.
    fn int(&self, key: &str, default: u64, min: u64, max: u64) -> Result<u64, SceneError> {
        let Some(v) = self.raw(key) else {
            return Ok(default);
        };
        if v.is_empty() || !v.bytes().all(|b| b.is_ascii_digit()) {
            return Err(self.bad(key, v, "expected a non-negative integer".into()));
        }
        let n: u64 = v
            .parse()
            .map_err(|_| self.bad(key, v, format!("must be at most {max}")))?;
        if n < min || n > max {
            return Err(self.bad(key, v, format!("must be in {min}..={max}")));
        }
        Ok(n)
    }

    /// Finite number in `min..=max` (exclusive of `min` if `min_exclusive`).
    fn num(
        &self,
        key: &str,
        default: f32,
        min: f32,
        min_exclusive: bool,
        max: f32,
    ) -> Result<f32, SceneError> {
        let Some(v) = self.raw(key) else {
            return Ok(default);
        };
        let x: f32 = v
            .parse()
            .map_err(|_| self.bad(key, v, "expected a number".into()))?;
        let low_ok = if min_exclusive { x > min } else { x >= min };
        if !x.is_finite() || !low_ok || x > max {
            let lo = if min_exclusive { "(" } else { "[" };
            return Err(self.bad(key, v, format!("must be a finite number in {lo}{min}, {max}]")));
        }
        Ok(x)
    }
}

/// Triangle-list builder.
#[derive(Default)]
struct MeshBuilder {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

impl MeshBuilder {
    /// Planar quad `a b c d` (in order around the boundary), wound so its normal points
    /// along `facing`.
    fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3, facing: Vec3) {
        let base = self.positions.len() as u32;
        let flip = (b - a).cross(c - a).dot(facing) < 0.0;
        for p in [a, b, c, d] {
            self.positions.push(p.to_array());
        }
        if flip {
            self.indices
                .extend_from_slice(&[base, base + 2, base + 1, base, base + 3, base + 2]);
        } else {
            self.indices
                .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }

    /// Closed axis-aligned box with outward-facing triangles (8 vertices, 12 triangles).
    fn cuboid(&mut self, min: Vec3, max: Vec3) {
        let base = self.positions.len() as u32;
        self.positions.extend(box_corners(min.to_array(), max.to_array()));
        for t in box_triangles() {
            self.indices.extend(t.map(|i| base + i));
        }
    }

    fn into_mesh(self, name: &str, color: [f32; 3]) -> Mesh {
        Mesh {
            name: name.to_owned(),
            primitives: vec![Primitive::new(
                self.positions,
                self.indices,
                [color[0], color[1], color[2], 1.0],
            )],
        }
    }
}

fn instance(mesh: u32, transform: Mat4, name: String) -> Instance {
    Instance {
        mesh,
        transform,
        name,
        visible: true,
    }
}

fn check_instances(gen: &str, n: u64) -> Result<(), SceneError> {
    if n > MAX_INSTANCES {
        return Err(SceneError::BadGeneratorParam(format!(
            "gen:{gen}: parameters give {n} instances (limit {MAX_INSTANCES})"
        )));
    }
    Ok(())
}

/// Height of one rack unit (1U) in metres.
const RACK_UNIT: f32 = 0.04445;
const RACK_WIDTH: f32 = 0.6;
const RACK_DEPTH: f32 = 1.0;
const AISLE: f32 = 1.2;
const PLINTH: f32 = 0.1;

fn racks(p: Params, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    let rows = p.int("rows", 25, 1, 100_000)?;
    let cols = p.int("cols", 100, 1, 100_000)?;
    let units = p.int("units", 40, 1, 1000)?;
    let detail = p.int("detail", 2000, 24, MAX_MESH_TRIANGLES)?;
    let n_inst = rows * cols * (units + 1) + 1;
    check_instances("racks", n_inst)?;

    let mut scene = Scene::new("racks");
    let step = |done| LoadProgress {
        stage: "meshes",
        done,
        total: 3,
    };
    scene.meshes.push(server_mesh(detail));
    progress(step(1));
    scene.meshes.push(rack_mesh(units as u32));
    progress(step(2));
    let (w, d) = (cols as f32 * RACK_WIDTH, rows as f32 * (RACK_DEPTH + AISLE));
    let mut floor = MeshBuilder::default();
    floor.cuboid(
        Vec3::new(-2.0, -2.0 - AISLE, -0.1),
        Vec3::new(w + 2.0, d + 2.0, 0.0),
    );
    scene
        .meshes
        .push(floor.into_mesh("floor slab", [0.55, 0.55, 0.57]));
    progress(step(3));

    scene.instances.reserve_exact(n_inst as usize);
    scene.instances.push(instance(2, Mat4::IDENTITY, "floor".into()));
    let flip = Mat4::from_translation(Vec3::new(0.0, RACK_DEPTH * 0.5, 0.0))
        * Mat4::from_rotation_z(PI)
        * Mat4::from_translation(Vec3::new(0.0, -RACK_DEPTH * 0.5, 0.0));
    for r in 0..rows {
        for c in 0..cols {
            let pos = Vec3::new(
                (c as f32 + 0.5) * RACK_WIDTH,
                r as f32 * (RACK_DEPTH + AISLE),
                0.0,
            );
            // Odd rows face the other way (hot/cold aisles).
            let rack = if r % 2 == 1 {
                Mat4::from_translation(pos) * flip
            } else {
                Mat4::from_translation(pos)
            };
            scene.instances.push(instance(1, rack, format!("rack r{r} c{c}")));
            for u in 0..units {
                let z = PLINTH + u as f32 * RACK_UNIT;
                let m = rack * Mat4::from_translation(Vec3::new(0.0, 0.08, z));
                scene
                    .instances
                    .push(instance(0, m, format!("server r{r} c{c} u{u}")));
            }
        }
        progress(LoadProgress {
            stage: "instances",
            done: scene.instances.len() as u64,
            total: n_inst,
        });
    }
    Ok(scene)
}

/// 1U server: chassis, front bezel with ears, and a grid of vent louvres in front of the
/// bezel; exactly `detail` triangles (24 + 12 per louvre + a label fan for the remainder). Local frame: x across (centred),
/// y from the front (0) to the back, z up from 0 to 1U.
fn server_mesh(detail: u64) -> Mesh {
    let mut b = MeshBuilder::default();
    let h = RACK_UNIT;
    b.cuboid(Vec3::new(-0.22, 0.02, 0.001), Vec3::new(0.22, 0.75, h - 0.001));
    b.cuboid(
        Vec3::new(-0.2413, 0.005, 0.001),
        Vec3::new(0.2413, 0.02, h - 0.001),
    );
    let louvres = (detail.saturating_sub(24) / 12) as usize;
    if louvres > 0 {
        // Grid over the 0.40 m × (1U - 8 mm) vent area with cells roughly square.
        let (aw, ah) = (0.40f32, h - 0.008);
        let nx = ((louvres as f32 * aw / ah).sqrt().ceil() as usize).clamp(1, louvres);
        let nz = louvres.div_ceil(nx);
        let (cw, ch) = (aw / nx as f32, ah / nz as f32);
        b.positions.reserve(louvres * 8);
        b.indices.reserve(louvres * 36);
        for k in 0..louvres {
            let (i, j) = ((k % nx) as f32, (k / nx) as f32);
            let x0 = -aw * 0.5 + (i + 0.2) * cw;
            let z0 = 0.004 + (j + 0.2) * ch;
            b.cuboid(
                Vec3::new(x0, -0.001, z0),
                Vec3::new(x0 + 0.6 * cw, 0.005, z0 + 0.6 * ch),
            );
        }
    }
    // Make the count exact: a thin label plate (triangle fan) on the lid for the remainder.
    let rest = (detail.saturating_sub(24) % 12) as u32;
    if rest > 0 {
        let base = b.positions.len() as u32;
        let (cx, cy, z) = (0.0f32, 0.1f32, h - 0.0009);
        b.positions.push([cx, cy, z]);
        for k in 0..=rest {
            let a = k as f32 / rest as f32 * PI;
            b.positions.push([cx + 0.03 * a.cos(), cy + 0.03 * a.sin(), z]);
        }
        for k in 0..rest {
            b.indices.extend_from_slice(&[base, base + 1 + k, base + 2 + k]);
        }
    }
    b.into_mesh("server 1U", [0.16, 0.16, 0.18])
}

/// Rack frame for `units` rack units: plinth, roof, four posts, two side panels.
fn rack_mesh(units: u32) -> Mesh {
    let mut b = MeshBuilder::default();
    let (hw, d) = (RACK_WIDTH * 0.5, RACK_DEPTH);
    let top = PLINTH + units as f32 * RACK_UNIT + 0.02;
    let height = top + 0.08;
    b.cuboid(Vec3::new(-hw, 0.0, 0.0), Vec3::new(hw, d, PLINTH));
    b.cuboid(Vec3::new(-hw, 0.0, top), Vec3::new(hw, d, height));
    for (x, y) in [
        (-hw, 0.0),
        (hw - 0.04, 0.0),
        (-hw, d - 0.04),
        (hw - 0.04, d - 0.04),
    ] {
        b.cuboid(Vec3::new(x, y, PLINTH), Vec3::new(x + 0.04, y + 0.04, top));
    }
    b.cuboid(Vec3::new(-hw, 0.04, PLINTH), Vec3::new(-hw + 0.01, d - 0.04, top));
    b.cuboid(Vec3::new(hw - 0.01, 0.04, PLINTH), Vec3::new(hw, d - 0.04, top));
    b.into_mesh("rack frame", [0.08, 0.08, 0.09])
}

const BLOCK: f32 = 100.0;
const STREET: f32 = 20.0;
const FLOOR_HEIGHT: f32 = 3.5;

/// SplitMix64: deterministic pseudo-random numbers for the city layout.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn city(p: Params, progress: &mut dyn FnMut(LoadProgress)) -> Result<Scene, SceneError> {
    let blocks = p.int("blocks", 8, 1, 10_000)?;
    let per = p.int("per_block", 3, 1, 20)?;
    let variants = p.int("variants", 6, 1, 64)?;
    let max_floors = p.int("floors", 30, 1, 300)?;
    let seed = p.int("seed", 1, 0, u64::MAX)?;
    let n_inst = blocks * blocks * (per * per + 1) + 1;
    check_instances("city", n_inst)?;

    let lot = (BLOCK - STREET) / per as f32;
    let mut scene = Scene::new("city");
    let total_meshes = variants + 2;
    for v in 0..variants {
        let r = mix(seed ^ (v << 32));
        let fw = 0.55 + 0.35 * ((r & 0xFFFF) as f32 / 65535.0);
        let fd = 0.55 + 0.35 * (((r >> 16) & 0xFFFF) as f32 / 65535.0);
        let floors = 2 + (r >> 32) % max_floors.max(2);
        scene
            .meshes
            .push(tower_mesh(lot * fw, lot * fd, floors as u32, v as u32));
        progress(LoadProgress {
            stage: "meshes",
            done: v + 1,
            total: total_meshes,
        });
    }
    let kerb_id = variants as u32;
    let mut kerb = MeshBuilder::default();
    let half = (BLOCK - STREET) * 0.5;
    kerb.cuboid(Vec3::new(-half, -half, 0.0), Vec3::new(half, half, 0.15));
    scene.meshes.push(kerb.into_mesh("kerb", [0.5, 0.5, 0.5]));
    let extent = blocks as f32 * BLOCK;
    let mut ground = MeshBuilder::default();
    ground.quad(
        Vec3::new(-STREET, -STREET, 0.0),
        Vec3::new(extent + STREET, -STREET, 0.0),
        Vec3::new(extent + STREET, extent + STREET, 0.0),
        Vec3::new(-STREET, extent + STREET, 0.0),
        Vec3::Z,
    );
    scene.meshes.push(ground.into_mesh("ground", [0.3, 0.3, 0.32]));
    progress(LoadProgress {
        stage: "meshes",
        done: total_meshes,
        total: total_meshes,
    });

    scene.instances.reserve_exact(n_inst as usize);
    scene
        .instances
        .push(instance(kerb_id + 1, Mat4::IDENTITY, "ground".into()));
    for bx in 0..blocks {
        for by in 0..blocks {
            let centre = Vec3::new((bx as f32 + 0.5) * BLOCK, (by as f32 + 0.5) * BLOCK, 0.0);
            scene.instances.push(instance(
                kerb_id,
                Mat4::from_translation(centre),
                format!("kerb {bx},{by}"),
            ));
            for i in 0..per {
                for j in 0..per {
                    let r = mix(seed ^ mix((bx << 40) ^ (by << 20) ^ (i << 10) ^ j));
                    let v = r % variants;
                    let rot = ((r >> 20) % 4) as f32 * FRAC_PI_2;
                    let pos = centre
                        + Vec3::new(
                            -half + (i as f32 + 0.5) * lot,
                            -half + (j as f32 + 0.5) * lot,
                            0.15,
                        );
                    scene.instances.push(instance(
                        v as u32,
                        Mat4::from_translation(pos) * Mat4::from_rotation_z(rot),
                        format!("building {bx},{by} {i},{j}"),
                    ));
                }
            }
        }
        progress(LoadProgress {
            stage: "instances",
            done: scene.instances.len() as u64,
            total: n_inst,
        });
    }
    Ok(scene)
}

/// Tower with a `w`×`d` footprint centred on the origin, `floors` storeys of recessed
/// windows on all four facades, a roof and a rooftop plant box.
fn tower_mesh(w: f32, d: f32, floors: u32, variant: u32) -> Mesh {
    let mut b = MeshBuilder::default();
    let h = floors as f32 * FLOOR_HEIGHT;
    let (hw, hd) = (w * 0.5, d * 0.5);
    // (outward normal, facade width, bottom-left corner seen from outside)
    let facades = [
        (Vec3::NEG_Y, w, Vec3::new(-hw, -hd, 0.0)),
        (Vec3::X, d, Vec3::new(hw, -hd, 0.0)),
        (Vec3::Y, w, Vec3::new(hw, hd, 0.0)),
        (Vec3::NEG_X, d, Vec3::new(-hw, hd, 0.0)),
    ];
    for (n, len, origin) in facades {
        let cols = ((len / 3.0).floor() as u32).max(1);
        facade(&mut b, origin, n, len, cols, floors);
    }
    b.quad(
        Vec3::new(-hw, -hd, h),
        Vec3::new(hw, -hd, h),
        Vec3::new(hw, hd, h),
        Vec3::new(-hw, hd, h),
        Vec3::Z,
    );
    b.cuboid(
        Vec3::new(-hw * 0.4, -hd * 0.4, h),
        Vec3::new(hw * 0.2, hd * 0.3, h + 3.0),
    );
    let g = 0.55 + 0.06 * (variant % 5) as f32;
    b.into_mesh(
        &format!("tower {variant} ({floors} floors)"),
        [g, g * 0.97, g * 0.92],
    )
}

/// One facade: a grid of `cols`×`rows` cells, each a wall frame around a window recessed
/// 0.3 m (9 quads per cell). `n` is the outward normal, `origin` the bottom-left corner
/// seen from outside.
fn facade(b: &mut MeshBuilder, origin: Vec3, n: Vec3, len: f32, cols: u32, rows: u32) {
    let v = Vec3::Z;
    let u = v.cross(n); // right, seen from outside
    let depth = 0.3;
    let (cw, ch) = (len / cols as f32, FLOOR_HEIGHT);
    let (mu, mv) = (0.2 * cw, 0.25 * ch);
    let at = |uu: f32, vv: f32, dd: f32| origin + u * uu + v * vv - n * dd;
    for j in 0..rows {
        for i in 0..cols {
            let (u0, u1) = (i as f32 * cw, (i + 1) as f32 * cw);
            let (v0, v1) = (j as f32 * ch, (j + 1) as f32 * ch);
            let (wu0, wu1, wv0, wv1) = (u0 + mu, u1 - mu, v0 + mv, v1 - mv);
            // A wall rectangle facing out, `d` into the recess.
            let rect = |b: &mut MeshBuilder, (a0, a1): (f32, f32), (c0, c1): (f32, f32), d: f32| {
                b.quad(at(a0, c0, d), at(a1, c0, d), at(a1, c1, d), at(a0, c1, d), n)
            };
            rect(b, (u0, u1), (v0, wv0), 0.0);
            rect(b, (u0, u1), (wv1, v1), 0.0);
            rect(b, (u0, wu0), (wv0, wv1), 0.0);
            rect(b, (wu1, u1), (wv0, wv1), 0.0);
            // Window pane at the back of the recess.
            rect(b, (wu0, wu1), (wv0, wv1), depth);
            // Sill, lintel, jambs: from the window's edge `p`-`q` at the facade into the recess.
            for ((p, q), facing) in [
                (((wu0, wv0), (wu1, wv0)), v),
                (((wu0, wv1), (wu1, wv1)), -v),
                (((wu0, wv0), (wu0, wv1)), u),
                (((wu1, wv0), (wu1, wv1)), -u),
            ] {
                let (p0, q0) = (at(p.0, p.1, 0.0), at(q.0, q.1, 0.0));
                b.quad(p0, q0, at(q.0, q.1, depth), at(p.0, p.1, depth), facing);
            }
        }
    }
}

fn open_box(p: Params) -> Result<Scene, SceneError> {
    let s = p.num("size", 2.0, 0.0, true, 1e6)?;
    let h = s * 0.5;
    let c = |x: f32, y: f32, z: f32| Vec3::new(x * h, y * h, z * s);
    let mut b = MeshBuilder::default();
    // Faces point inwards; the −Y side is open.
    b.quad(
        c(-1., -1., 0.),
        c(1., -1., 0.),
        c(1., 1., 0.),
        c(-1., 1., 0.),
        Vec3::Z,
    );
    b.quad(
        c(-1., -1., 1.),
        c(1., -1., 1.),
        c(1., 1., 1.),
        c(-1., 1., 1.),
        Vec3::NEG_Z,
    );
    b.quad(
        c(-1., 1., 0.),
        c(1., 1., 0.),
        c(1., 1., 1.),
        c(-1., 1., 1.),
        Vec3::NEG_Y,
    );
    b.quad(
        c(-1., -1., 0.),
        c(-1., 1., 0.),
        c(-1., 1., 1.),
        c(-1., -1., 1.),
        Vec3::X,
    );
    b.quad(
        c(1., -1., 0.),
        c(1., 1., 0.),
        c(1., 1., 1.),
        c(1., -1., 1.),
        Vec3::NEG_X,
    );
    let mut scene = Scene::new("box");
    scene.meshes.push(b.into_mesh("open box", [0.8, 0.8, 0.8]));
    scene.instances.push(instance(0, Mat4::IDENTITY, "box".into()));
    Ok(scene)
}

fn ground_quad(size: f32) -> Mesh {
    let h = size * 0.5;
    let mut b = MeshBuilder::default();
    b.quad(
        Vec3::new(-h, -h, 0.0),
        Vec3::new(h, -h, 0.0),
        Vec3::new(h, h, 0.0),
        Vec3::new(-h, h, 0.0),
        Vec3::Z,
    );
    b.into_mesh("ground", [0.8, 0.8, 0.8])
}

fn plane(p: Params) -> Result<Scene, SceneError> {
    let size = p.num("size", 100.0, 0.0, true, 1e7)?;
    let mut scene = Scene::new("plane");
    scene.meshes.push(ground_quad(size));
    scene.instances.push(instance(0, Mat4::IDENTITY, "plane".into()));
    Ok(scene)
}

fn slab(p: Params) -> Result<Scene, SceneError> {
    let h = p.num("h", 1.0, 0.0, true, 1e6)?;
    let size = p.num("size", 10.0, 0.0, true, 1e6)?;
    let ground = p.num("ground", 100.0, 0.0, true, 1e7)?;
    let mut scene = Scene::new("slab");
    scene.meshes.push(ground_quad(ground));
    let mut b = MeshBuilder::default();
    let s = size * 0.5;
    b.cuboid(Vec3::new(-s, -s, 0.0), Vec3::new(s, s, 0.1));
    scene.meshes.push(b.into_mesh("slab", [0.8, 0.8, 0.8]));
    scene.instances.push(instance(0, Mat4::IDENTITY, "ground".into()));
    scene.instances.push(instance(
        1,
        Mat4::from_translation(Vec3::new(0.0, 0.0, h)),
        "slab".into(),
    ));
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri_normals(m: &Mesh) -> Vec<Vec3> {
        let p = &m.primitives[0];
        p.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(p.positions[i as usize]));
                (b - a).cross(c - a)
            })
            .collect()
    }

    #[test]
    fn cuboid_is_outward() {
        let mut b = MeshBuilder::default();
        b.cuboid(Vec3::ZERO, Vec3::ONE);
        let m = b.into_mesh("c", [1.0; 3]);
        let centre = Vec3::splat(0.5);
        let p = &m.primitives[0];
        for (t, n) in p.indices.chunks_exact(3).zip(tri_normals(&m)) {
            let a = Vec3::from(p.positions[t[0] as usize]);
            assert!(n.dot(a - centre) > 0.0);
        }
        assert_eq!(m.triangle_count(), 12);
    }

    #[test]
    fn server_detail_is_respected() {
        for d in [24u64, 25, 35, 100, 2500, 10_000, 10_007] {
            let t = server_mesh(d).triangle_count();
            assert_eq!(t, d);
        }
    }

    #[test]
    fn tower_facades_face_outwards() {
        let m = tower_mesh(20.0, 12.0, 4, 0);
        // Frame/pane quads of the +X facade have normals +X; none may point inwards
        // through a wall, i.e. every face on the x = hw plane faces +X.
        let p = &m.primitives[0];
        for (t, n) in p.indices.chunks_exact(3).zip(tri_normals(&m)) {
            let xs = [t[0], t[1], t[2]].map(|i| p.positions[i as usize][0]);
            if xs.iter().all(|&x| (x - 10.0).abs() < 1e-4) {
                assert!(n.x > 0.0);
            }
        }
        // 4 facades: (20/3 -> 6 cols, 12/3 -> 4 cols) * 4 floors * 18 tris + roof + box
        assert_eq!(m.triangle_count(), (6 + 4 + 6 + 4) * 4 * 18 + 2 + 12);
    }

    #[test]
    fn params_are_strict() {
        let p = Params::parse("x", "a=3&b=1.5", &["a", "b"]).unwrap();
        assert_eq!(p.int("a", 0, 0, 10).unwrap(), 3);
        assert!(p.int("b", 0, 0, 10).is_err());
        assert_eq!(p.num("b", 0.0, 0.0, false, 10.0).unwrap(), 1.5);
        assert!(Params::parse("x", "c=1", &["a"]).is_err());
        assert!(Params::parse("x", "a=1&a=2", &["a"]).is_err());
        assert!(Params::parse("x", "a", &["a"]).is_err());
        let p = Params::parse("x", "a=-1&b=nan", &["a", "b"]).unwrap();
        assert!(p.int("a", 0, 0, 10).is_err());
        assert!(p.num("b", 0.0, 0.0, false, 10.0).is_err());
        let p = Params::parse("x", "a=99999999999999999999999", &["a"]).unwrap();
        assert!(p.int("a", 0, 0, 10).is_err());
    }
}
