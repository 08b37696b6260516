//! Shading normals from every mesh loader: glTF NORMAL (float, quantized, sparse; flat without it), OBJ `vn`,
//! PLY nx/ny/nz, and smooth normals by a crease angle for STL and OBJ/PLY without normals of their own.
mod common;

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use common::{base64, no_progress, temp_dir};
use hrtao_scene::glam::Vec3;
use hrtao_scene::{load_with, LoadOptions, Primitive, SceneError};

/// Warnings logged by the loaders, kept to check that bad normals are reported (once).
static WARNINGS: Mutex<Vec<String>> = Mutex::new(Vec::new());

struct Capture;

impl log::Log for Capture {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Warn
    }
    fn log(&self, r: &log::Record) {
        if self.enabled(r.metadata()) {
            WARNINGS.lock().unwrap().push(r.args().to_string());
        }
    }
    fn flush(&self) {}
}

fn capture_warnings() {
    static LOGGER: Capture = Capture;
    let _ = log::set_logger(&LOGGER);
    log::set_max_level(log::LevelFilter::Warn);
}

fn warnings_about(needle: &str) -> Vec<String> {
    WARNINGS
        .lock()
        .unwrap()
        .iter()
        .filter(|w| w.contains(needle))
        .cloned()
        .collect()
}

fn load(path: &Path, crease_deg: Option<f32>) -> Result<Primitive, SceneError> {
    let opts = LoadOptions {
        crease_deg,
        ..Default::default()
    };
    let scene = load_with(path.to_str().unwrap(), &opts, &mut no_progress())?;
    assert_eq!(scene.meshes.len(), 1);
    assert_eq!(scene.meshes[0].primitives.len(), 1);
    Ok(scene.meshes[0].primitives[0].clone())
}

fn near(a: [f32; 3], b: [f32; 3], eps: f32) -> bool {
    Vec3::from(a).abs_diff_eq(Vec3::from(b), eps)
}

/// The face normal of triangle `t`.
fn face_normal(p: &Primitive, t: usize) -> Vec3 {
    let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(p.positions[p.indices[3 * t + k] as usize]));
    (b - a).cross(c - a).normalize()
}

/// A capped cylinder of radius 1 along z (-1..1) as triangles (counter-clockwise seen from outside), and for
/// each vertex of its side and caps the exact normal.
fn cylinder(segments: u32) -> (Vec<[f32; 3]>, Vec<u32>, Vec<[f32; 3]>) {
    let (p, n, ix) = common::cylinder(segments, 1.0, 1.0);
    (p, ix, n)
}

/// The 12-segment cylinder as a .gltf at `path` with `normals` as its NORMAL.
fn cylinder_gltf(path: &Path, normals: &[[f32; 3]]) -> PathBuf {
    let (p, ix, _) = cylinder(12);
    let attributes = [("POSITION", f32_acc(&p)), ("NORMAL", f32_acc(normals))];
    write_gltf(path, &attributes, &ix, 4, None, "")
}

fn write_stl(path: &Path, p: &[[f32; 3]], ix: &[u32]) {
    let mut b = vec![0u8; 80];
    b.extend((ix.len() as u32 / 3).to_le_bytes());
    for t in ix.chunks(3) {
        // A zero facet normal, as many exporters write: the loader does not read it.
        b.extend([0u8; 12]);
        for &i in t {
            for c in p[i as usize] {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    std::fs::write(path, b).unwrap();
}

/// An OBJ of the mesh, with `vn` (and `f v//vn`) when `normals` are given.
fn write_obj(path: &Path, p: &[[f32; 3]], ix: &[u32], normals: Option<&[[f32; 3]]>) {
    let mut s = String::new();
    for v in p {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for v in normals.unwrap_or_default() {
        s += &format!("vn {} {} {}\n", v[0], v[1], v[2]);
    }
    for t in ix.chunks(3) {
        let c = |i: u32| match normals {
            Some(_) => format!("{0}//{0}", i + 1),
            None => format!("{}", i + 1),
        };
        s += &format!("f {} {} {}\n", c(t[0]), c(t[1]), c(t[2]));
    }
    std::fs::write(path, s).unwrap();
}

/// The 12-segment cylinder as an STL: the side's normals are radial (within 1e-3), the caps' ±z, and the rim is
/// split (each rim position has a side and a cap vertex); the stored zero facet normals are not used.
#[test]
fn stl_cylinder_is_smoothed_by_the_crease_angle() {
    let dir = temp_dir("normals-stl");
    let (p, ix, _) = cylinder(12);
    let path = dir.join("cylinder.stl");
    write_stl(&path, &p, &ix);
    let prim = load(&path, Some(40.0)).unwrap();
    assert_eq!(prim.normals.len(), prim.positions.len());
    assert_eq!(prim.indices.len(), ix.len());
    // Welded: 24 side vertices, 2 x (centre + 12 rim) cap vertices.
    assert_eq!(
        prim.positions.len(),
        24 + 26,
        "the rim is split between side and caps"
    );
    for t in 0..prim.indices.len() / 3 {
        let f = face_normal(&prim, t);
        for k in 0..3 {
            let v = prim.indices[3 * t + k] as usize;
            let (pos, n) = (prim.positions[v], prim.normals[v]);
            let want = if f.z.abs() > 0.9 {
                [0.0, 0.0, f.z.signum()]
            } else {
                Vec3::new(pos[0], pos[1], 0.0).normalize().to_array()
            };
            assert!(
                near(n, want, 1e-3),
                "triangle {t} corner {k} at {pos:?}: {n:?}, want {want:?}"
            );
        }
    }
    // Smoothing off: face normals (none kept), the file's geometry as it is.
    let flat = load(&path, None).unwrap();
    assert!(flat.normals.is_empty());
    assert_eq!(flat.positions.len(), ix.len());
    // A bad angle is a clear error.
    let e = load(&path, Some(200.0)).unwrap_err().to_string();
    assert!(e.contains("0..=180") && e.contains("cylinder.stl"), "{e}");
}

/// A cube's edges are 90° creases: smoothed at 40° every corner keeps its face's normal (24 vertices).
#[test]
fn a_cube_keeps_face_normals() {
    let dir = temp_dir("normals-cube");
    let c = |i: u32| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32];
    let p: Vec<[f32; 3]> = (0..8).map(c).collect();
    #[rustfmt::skip]
    let ix = vec![
        0, 2, 1, 1, 2, 3, // z = 0
        4, 5, 6, 5, 7, 6, // z = 1
        0, 1, 4, 1, 5, 4, // y = 0
        2, 6, 3, 3, 6, 7, // y = 1
        0, 4, 2, 2, 4, 6, // x = 0
        1, 3, 5, 3, 7, 5, // x = 1
    ];
    let path = dir.join("cube.stl");
    write_stl(&path, &p, &ix);
    let prim = load(&path, Some(40.0)).unwrap();
    assert_eq!(prim.positions.len(), 24);
    for t in 0..12 {
        let f = face_normal(&prim, t).to_array();
        for k in 0..3 {
            let n = prim.normals[prim.indices[3 * t + k] as usize];
            assert!(near(n, f, 1e-6), "triangle {t}: {n:?} vs face {f:?}");
        }
    }
}

/// OBJ: `vn` are kept as given (one per vertex); without them the mesh is smoothed, or flat with smoothing off.
#[test]
fn obj_normals_are_read_or_smoothed() {
    let dir = temp_dir("normals-obj");
    let (p, ix, n) = cylinder(12);
    // Deliberately not the smoothing's answer on the caps' rim: the file's own normals win.
    let tilted: Vec<[f32; 3]> = n
        .iter()
        .map(|v| Vec3::new(v[0], v[1], v[2] + 0.5).normalize().to_array())
        .collect();
    let with = dir.join("with_vn.obj");
    write_obj(&with, &p, &ix, Some(&tilted));
    let prim = load(&with, Some(40.0)).unwrap();
    assert_eq!(prim.normals.len(), prim.positions.len());
    assert_eq!(prim.positions.len(), p.len());
    for (pos, nrm) in prim.positions.iter().zip(&prim.normals) {
        assert!(
            (0..p.len()).any(|k| near(p[k], *pos, 1e-6) && near(tilted[k], *nrm, 1e-6)),
            "{pos:?}: {nrm:?} is not the file's"
        );
    }
    let without = dir.join("without_vn.obj");
    write_obj(&without, &p, &ix, None);
    let prim = load(&without, Some(40.0)).unwrap();
    assert_eq!(prim.positions.len(), 50, "side and caps split at the rim");
    for (pos, nrm) in prim.positions.iter().zip(&prim.normals) {
        let radial = Vec3::new(pos[0], pos[1], 0.0).normalize().to_array();
        assert!(
            near(*nrm, radial, 1e-3) || near(*nrm, [0.0, 0.0, pos[2]], 1e-6),
            "{pos:?}: {nrm:?}"
        );
    }
    assert!(load(&without, None).unwrap().normals.is_empty());
}

/// PLY: nx/ny/nz (float, or double) are kept; without them the mesh is smoothed.
#[test]
fn ply_normals_are_read_or_smoothed() {
    let dir = temp_dir("normals-ply");
    let (p, ix, n) = cylinder(12);
    for ty in ["float", "double"] {
        let mut s = format!(
            "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             property {ty} nx\nproperty {ty} ny\nproperty {ty} nz\nelement face {}\n\
             property list uchar int vertex_indices\nend_header\n",
            p.len(),
            ix.len() / 3
        );
        for (v, m) in p.iter().zip(&n) {
            s += &format!("{} {} {} {} {} {}\n", v[0], v[1], v[2], m[0], m[1], m[2]);
        }
        for t in ix.chunks(3) {
            s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
        }
        let path = dir.join(format!("normals_{ty}.ply"));
        std::fs::write(&path, s).unwrap();
        let prim = load(&path, Some(40.0)).unwrap();
        assert_eq!(prim.positions, p, "{ty}: the file's vertices as they are");
        for (k, (got, want)) in prim.normals.iter().zip(&n).enumerate() {
            assert!(near(*got, *want, 1e-6), "{ty}: vertex {k}: {got:?} vs {want:?}");
        }
        assert_eq!(prim.normals.len(), p.len());
    }
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        p.len(),
        ix.len() / 3
    );
    for v in &p {
        s += &format!("{} {} {}\n", v[0], v[1], v[2]);
    }
    for t in ix.chunks(3) {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    let path = dir.join("plain.ply");
    std::fs::write(&path, s).unwrap();
    let prim = load(&path, Some(40.0)).unwrap();
    assert_eq!(prim.positions.len(), 50);
    assert_eq!(prim.normals.len(), 50);
    assert!(load(&path, None).unwrap().normals.is_empty());
}

/// One glTF accessor's data for [`write_gltf`]: bytes, componentType, type, count, normalized, sparse JSON.
struct Acc {
    bytes: Vec<u8>,
    component: u32,
    ty: &'static str,
    count: usize,
    normalized: bool,
}

fn f32_acc(v: &[[f32; 3]]) -> Acc {
    Acc {
        bytes: v.iter().flatten().flat_map(|c| c.to_le_bytes()).collect(),
        component: 5126,
        ty: "VEC3",
        count: v.len(),
        normalized: false,
    }
}

/// A .gltf with one primitive of `mode` whose attributes are `attrs` (name, accessor) plus u32 `indices`;
/// `sparse` (accessor, JSON) adds a sparse block to an accessor. Extra root JSON in `extra`.
fn write_gltf(
    path: &Path,
    attrs: &[(&str, Acc)],
    indices: &[u32],
    mode: u32,
    sparse: Option<(usize, String)>,
    extra: &str,
) -> PathBuf {
    let mut bin = Vec::new();
    let (mut views, mut accs, mut names) = (Vec::new(), Vec::new(), Vec::new());
    let idx = Acc {
        bytes: indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
        component: 5125,
        ty: "SCALAR",
        count: indices.len(),
        normalized: false,
    };
    for (k, (name, a)) in attrs.iter().chain([&("indices", idx)]).enumerate() {
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            bin.len(),
            a.bytes.len()
        ));
        bin.extend(&a.bytes);
        let sp = match &sparse {
            Some((s, json)) if *s == k => format!(r#","sparse":{json}"#),
            _ => String::new(),
        };
        accs.push(format!(
            r#"{{"bufferView":{k},"componentType":{},"count":{},"type":"{}","normalized":{}{sp}}}"#,
            a.component, a.count, a.ty, a.normalized
        ));
        names.push(name.to_string());
    }
    // Sparse data after everything: its own views.
    let n = names.len() - 1;
    let attributes: Vec<String> = names[..n]
        .iter()
        .enumerate()
        .map(|(k, a)| format!(r#""{a}":{k}"#))
        .collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},{extra}
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{}],
"accessors":[{}],
"meshes":[{{"primitives":[{{"attributes":{{{}}},"indices":{n},"mode":{mode}}}]}}],
"nodes":[{{"mesh":0}}]}}"#,
        bin.len(),
        base64(&bin),
        views.join(","),
        accs.join(","),
        attributes.join(",")
    );
    std::fs::write(path, json).unwrap();
    path.to_path_buf()
}

/// glTF: NORMAL is read (float, and KHR_mesh_quantization's normalized bytes); without it the primitive stays
/// flat whatever the crease option (the spec's flat normals).
#[test]
fn gltf_normal_is_read_and_its_absence_is_flat() {
    let dir = temp_dir("normals-gltf");
    let (p, ix, n) = cylinder(12);
    let path = cylinder_gltf(&dir.join("with.gltf"), &n);
    let prim = load(&path, Some(40.0)).unwrap();
    assert_eq!(prim.normals.len(), n.len());
    for (got, want) in prim.normals.iter().zip(&n) {
        assert!(near(*got, *want, 1e-6), "{got:?} vs {want:?}");
    }

    let path = write_gltf(
        &dir.join("without.gltf"),
        &[("POSITION", f32_acc(&p))],
        &ix,
        4,
        None,
        "",
    );
    let prim = load(&path, Some(40.0)).unwrap();
    assert!(prim.normals.is_empty(), "no NORMAL: flat, not smoothed");
    assert_eq!(prim.positions, p);

    // Quantized: normalized signed bytes (VEC3 padded to 4 bytes per element, as the extension requires).
    let bytes: Vec<u8> = n
        .iter()
        .flat_map(|v| {
            let q = v.map(|c| (c * 127.0).round() as i8 as u8);
            [q[0], q[1], q[2], 0]
        })
        .collect();
    let quantized = Acc {
        bytes,
        component: 5120,
        ty: "VEC3",
        count: n.len(),
        normalized: true,
    };
    let path = write_gltf(
        &dir.join("quantized.gltf"),
        &[("POSITION", f32_acc(&p)), ("NORMAL", quantized)],
        &ix,
        4,
        None,
        r#""extensionsUsed":["KHR_mesh_quantization"],"extensionsRequired":["KHR_mesh_quantization"],"#,
    );
    // The byte stride of 4: set on the view by hand.
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replacen(
        &format!(r#""byteLength":{}}}"#, n.len() * 4),
        &format!(r#""byteLength":{},"byteStride":4}}"#, n.len() * 4),
        1,
    );
    std::fs::write(&path, text).unwrap();
    let prim = load(&path, Some(40.0)).unwrap();
    assert_eq!(prim.normals.len(), n.len());
    for (got, want) in prim.normals.iter().zip(&n) {
        assert!(near(*got, *want, 0.01), "{got:?} vs {want:?}");
    }
}

/// A sparse NORMAL accessor: its substituted normals are the ones kept.
#[test]
fn gltf_sparse_normals() {
    let dir = temp_dir("normals-gltf-sparse");
    let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let base = vec![[0.0, 0.0, 1.0]; 3];
    // The sparse block's indices and values follow as views 3 and 4 (after POSITION, NORMAL, indices).
    let path = write_gltf(
        &dir.join("sparse.gltf"),
        &[("POSITION", f32_acc(&p)), ("NORMAL", f32_acc(&base))],
        &[0, 1, 2],
        4,
        Some((
            1,
            r#"{"count":1,"indices":{"bufferView":3,"componentType":5125},"values":{"bufferView":4}}"#.into(),
        )),
        "",
    );
    // Append the sparse views: index 2, value (1, 0, 0).
    let text = std::fs::read_to_string(&path).unwrap();
    let start = text.find("base64,").unwrap() + 7;
    let end = start + text[start..].find('"').unwrap();
    let mut bin = decode_b64(&text[start..end]);
    let off = bin.len();
    bin.extend(2u32.to_le_bytes());
    bin.extend([1.0f32, 0.0, 0.0].iter().flat_map(|c| c.to_le_bytes()));
    let old_len = format!(r#""byteLength":{off},"#);
    let text = format!("{}{}{}", &text[..start], base64(&bin), &text[end..])
        .replacen(&old_len, &format!(r#""byteLength":{},"#, bin.len()), 1)
        .replacen(
            r#"}],
"accessors""#,
            &format!(
                r#"}},{{"buffer":0,"byteOffset":{off},"byteLength":4}},{{"buffer":0,"byteOffset":{},"byteLength":12}}],
"accessors""#,
                off + 4
            ),
            1,
        );
    std::fs::write(&path, text).unwrap();
    let prim = load(&path, None).unwrap();
    assert_eq!(
        prim.normals,
        vec![[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    );
}

fn decode_b64(s: &str) -> Vec<u8> {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let vals: Vec<u32> = s
        .bytes()
        .filter(|&b| b != b'=')
        .map(|b| T.iter().position(|&t| t == b).unwrap() as u32)
        .collect();
    let mut out = Vec::new();
    for c in vals.chunks(4) {
        let n = c.iter().enumerate().fold(0u32, |n, (k, v)| n | v << (18 - 6 * k));
        out.extend(&n.to_be_bytes()[1..c.len()]);
    }
    out
}

/// Triangle strips and fans become lists by their indices: the normals stay one per vertex, unchanged.
#[test]
fn gltf_strips_and_fans_keep_one_normal_per_vertex() {
    let dir = temp_dir("normals-gltf-strip");
    let p: Vec<[f32; 3]> = (0..6).map(|k| [(k / 2) as f32, (k % 2) as f32, 0.0]).collect();
    let n: Vec<[f32; 3]> = (0..6)
        .map(|k| Vec3::new(0.1 * k as f32, 0.0, 1.0).normalize().to_array())
        .collect();
    for (mode, name) in [(5, "strip"), (6, "fan")] {
        let path = write_gltf(
            &dir.join(format!("{name}.gltf")),
            &[("POSITION", f32_acc(&p)), ("NORMAL", f32_acc(&n))],
            &[0, 1, 2, 3, 4, 5],
            mode,
            None,
            "",
        );
        let prim = load(&path, Some(40.0)).unwrap();
        assert_eq!(prim.indices.len(), 12, "{name}: 4 triangles");
        assert_eq!(prim.normals.len(), prim.positions.len(), "{name}");
        for (got, want) in prim.normals.iter().zip(&n) {
            assert!(near(*got, *want, 1e-6), "{name}: {got:?} vs {want:?}");
        }
    }
}

/// NaN normals in a file: the primitive shades flat with one warning, the load succeeds.
#[test]
fn nan_normals_shade_flat_with_a_warning() {
    capture_warnings();
    let dir = temp_dir("normals-nan");
    let (p, ix, mut n) = cylinder(12);
    n[5] = [f32::NAN, 0.0, 1.0];
    let path = cylinder_gltf(&dir.join("nan_normals.gltf"), &n);
    let prim = load(&path, Some(40.0)).unwrap();
    assert!(prim.normals.is_empty());
    let w = warnings_about("nan_normals.gltf");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("normal 5"), "{w:?}");
    // An OBJ with a NaN `vn`: the same.
    let obj = dir.join("nan_vn.obj");
    write_obj(&obj, &p, &ix, Some(&n));
    let prim = load(&obj, Some(40.0)).unwrap();
    assert!(prim.normals.is_empty());
    assert_eq!(warnings_about("nan_vn.obj").len(), 1);
}

/// Speed of smoothing an STL-sized mesh: 10M triangles of a wavy height field, every corner stored apart as in
/// an STL. `cargo test --release -p hrtao-scene --test shading_normals -- --ignored --nocapture`.
#[test]
#[ignore = "a timing, 1.5 GB of memory"]
fn smoothing_ten_million_triangles() {
    let side = 2237u32;
    let h = |x: u32, y: u32| ((x as f32 * 0.05).sin() + (y as f32 * 0.03).cos()) * 3.0;
    let mut p = Vec::with_capacity((side * side * 6) as usize);
    for y in 0..side {
        for x in 0..side {
            let c = |dx: u32, dy: u32| [(x + dx) as f32, (y + dy) as f32, h(x + dx, y + dy)];
            p.extend([c(0, 0), c(1, 0), c(1, 1), c(0, 0), c(1, 1), c(0, 1)]);
        }
    }
    let ix: Vec<u32> = (0..p.len() as u32).collect();
    let t = std::time::Instant::now();
    let (pos, idx, n) = hrtao_scene::normals::smooth(&p, &ix, 40.0);
    let s = t.elapsed().as_secs_f64();
    eprintln!(
        "smoothed {} triangles ({} corners -> {} vertices) in {s:.2} s",
        idx.len() / 3,
        p.len(),
        pos.len()
    );
    assert_eq!(
        pos.len(),
        ((side + 1) * (side + 1)) as usize,
        "a smooth field welds to its grid"
    );
    assert_eq!(n.len(), pos.len());
}

/// An OBJ model whose faces mix corners with and without `vn`: tobj cannot line the given normals up with the
/// positions, so the whole model is smoothed (with a warning) instead of shading with misplaced normals.
#[test]
fn obj_with_some_vn_is_smoothed_whole() {
    capture_warnings();
    let dir = temp_dir("normals-obj-mixed");
    let (p, ix, n) = cylinder(12);
    let mut s = String::new();
    for v in &p {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for v in &n {
        s += &format!("vn {} {} {}\n", v[0], v[1], v[2]);
    }
    for (t, c) in ix.chunks(3).enumerate() {
        // The side with `vn`, the caps without.
        if t < 24 {
            s += &format!("f {0}//{0} {1}//{1} {2}//{2}\n", c[0] + 1, c[1] + 1, c[2] + 1);
        } else {
            s += &format!("f {} {} {}\n", c[0] + 1, c[1] + 1, c[2] + 1);
        }
    }
    let path = dir.join("mixed_vn.obj");
    std::fs::write(&path, s).unwrap();
    let prim = load(&path, Some(40.0)).unwrap();
    assert_eq!(
        prim.positions.len(),
        50,
        "smoothed: side and caps split at the rim"
    );
    for (pos, nrm) in prim.positions.iter().zip(&prim.normals) {
        let radial = Vec3::new(pos[0], pos[1], 0.0).normalize().to_array();
        assert!(
            near(*nrm, radial, 1e-3) || near(*nrm, [0.0, 0.0, pos[2]], 1e-6),
            "{pos:?}: {nrm:?}"
        );
    }
    let w = warnings_about("mixed_vn.obj");
    assert!(
        w.len() == 1 && w[0].contains("smoothing the whole model"),
        "{w:?}"
    );
}
