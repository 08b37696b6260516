//! Shading normals end to end through `hrtao render` (issue #45): a 12-segment capped cylinder whose file carries
//! normals (OBJ `vn`, glTF NORMAL) shades like a 384-segment one, without facet steps; with face normals (OBJ
//! without `vn` and `--flat-normals`, glTF without NORMAL) it is at least 3x further off. The measure is the one of
//! crates/hrtao-core/tests/shading_normals.rs, on the PNG the command writes.
use std::f32::consts::TAU;
use std::path::{Path, PathBuf};
use std::process::Command;

const W: usize = 640;
const H: usize = 360;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hrtao-normals-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A capped cylinder of radius 1 along z (-1..1), wound counter-clockwise seen from outside: positions, the
/// exact normal of each vertex (radial on the side, ±z on the caps, which have their own rim vertices), triangles.
#[allow(clippy::type_complexity)]
fn cylinder(segments: u32) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let (mut p, mut n, mut ix) = (Vec::new(), Vec::new(), Vec::new());
    let ring = |k: u32| {
        let t = TAU * k as f32 / segments as f32;
        (t.cos(), t.sin())
    };
    for k in 0..segments {
        let (x, y) = ring(k);
        p.extend([[x, y, -1.0], [x, y, 1.0]]);
        n.extend([[x, y, 0.0], [x, y, 0.0]]);
    }
    for k in 0..segments {
        let (i, j) = (2 * k, 2 * ((k + 1) % segments));
        ix.extend([i, j, j + 1, i, j + 1, i + 1]);
    }
    for z in [-1.0f32, 1.0] {
        let centre = p.len() as u32;
        p.push([0.0, 0.0, z]);
        n.push([0.0, 0.0, z]);
        for k in 0..segments {
            let (x, y) = ring(k);
            p.push([x, y, z]);
            n.push([0.0, 0.0, z]);
        }
        for k in 0..segments {
            let (i, j) = (centre + 1 + k, centre + 1 + (k + 1) % segments);
            ix.extend(if z > 0.0 { [centre, i, j] } else { [centre, j, i] });
        }
    }
    (p, n, ix)
}

fn write_obj(path: &Path, segments: u32, with_vn: bool) {
    let (p, n, ix) = cylinder(segments);
    let mut s = String::new();
    for v in &p {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    if with_vn {
        for v in &n {
            s += &format!("vn {} {} {}\n", v[0], v[1], v[2]);
        }
    }
    for t in ix.chunks(3) {
        let c = |i: u32| {
            if with_vn {
                format!("{0}//{0}", i + 1)
            } else {
                format!("{}", i + 1)
            }
        };
        s += &format!("f {} {} {}\n", c(t[0]), c(t[1]), c(t[2]));
    }
    std::fs::write(path, s).unwrap();
}

fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            out.push(if k <= c.len() {
                T[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// The cylinder as a .gltf with an embedded buffer, NORMAL when asked, and a 0.8 grey material (the OBJ's
/// default colour; glTF's default is white).
fn write_gltf(path: &Path, segments: u32, with_normal: bool) {
    let (p, n, ix) = cylinder(segments);
    let f32s = |v: &[[f32; 3]]| -> Vec<u8> { v.iter().flatten().flat_map(|c| c.to_le_bytes()).collect() };
    let mut bin = f32s(&p);
    let pos_len = bin.len();
    bin.extend(f32s(&n));
    let idx_off = bin.len();
    bin.extend(ix.iter().flat_map(|i| i.to_le_bytes()));
    let normal = if with_normal { r#","NORMAL":1"# } else { "" };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},
"buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{data}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},
  {{"buffer":0,"byteOffset":{pos_len},"byteLength":{pos_len}}},
  {{"buffer":0,"byteOffset":{idx_off},"byteLength":{idx_len}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[-1,-1,-1],"max":[1,1,1]}},
  {{"bufferView":1,"componentType":5126,"count":{count},"type":"VEC3"}},
  {{"bufferView":2,"componentType":5125,"count":{icount},"type":"SCALAR"}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.8,0.8,1.0]}}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0{normal}}},"indices":2,"material":0}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
        len = bin.len(),
        data = base64(&bin),
        idx_len = ix.len() * 4,
        count = p.len(),
        icount = ix.len(),
    );
    std::fs::write(path, json).unwrap();
}

/// From the side and a little above, so the top cap shows too (the core test's camera). One file per scene:
/// the tests run in parallel, and a file rewritten while another test's render reads it is a race.
fn camera(scene: &Path) -> PathBuf {
    let path = PathBuf::from(format!("{}.camera.json", scene.display()));
    std::fs::write(
        &path,
        format!(
            r#"{{"eye":[0.5,-6.0,2.5],"target":[0,0,0],"up":[0,0,1],"fov_y_deg":40,"width":{W},"height":{H}}}"#
        ),
    )
    .unwrap();
    path
}

/// `hrtao render --mode none` (no AO; feature edges are off unless `--edges`) of `scene` at 640x360: the sRGB
/// luminance of each pixel in 0..1 and whether it shows the model (it differs from the background, a vertical
/// gradient read from the image's left column, by more than 3/255 in some channel).
fn render(scene: &Path, extra: &[&str]) -> (Vec<f32>, Vec<bool>) {
    // Named after the whole file name: c12.obj and c12.gltf render in parallel tests.
    let png = PathBuf::from(format!("{}{}.png", scene.display(), extra.join("")));
    let camera = camera(scene);
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(["render", "--scene", scene.to_str().unwrap()])
        .args([
            "--camera",
            camera.to_str().unwrap(),
            "--mode",
            "none",
            "--frames",
            "1",
        ])
        .args(["--out", png.to_str().unwrap()])
        .args(extra)
        .env("HRTAO_VALIDATION", "1")
        .output()
        .expect("run hrtao");
    assert!(
        out.status.success(),
        "{}: {}",
        scene.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (W as u32, H as u32));
    let px = |x: usize, y: usize| img.get_pixel(x as u32, y as u32).0;
    let mut lum = Vec::with_capacity(W * H);
    let mut hit = Vec::with_capacity(W * H);
    for y in 0..H {
        let bg = px(0, y);
        for x in 0..W {
            let c = px(x, y);
            lum.push((0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32) / 255.0);
            hit.push((0..3).any(|k| (c[k] as i32 - bg[k] as i32).abs() > 3));
        }
    }
    (lum, hit)
}

/// Pixels at least 3 pixels from every silhouette of all the masks given (covered in all of them).
fn interior(masks: &[&[bool]]) -> Vec<bool> {
    let (w, h) = (W as i32, H as i32);
    let covered =
        |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h && masks.iter().all(|m| m[(y * w + x) as usize]);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| (-3..=3).all(|dy| (-3..=3).all(|dx| covered(x + dx, y + dy))))
        .collect()
}

fn mae(a: &[f32], b: &[f32], mask: &[bool]) -> f32 {
    let (sum, n) = a
        .iter()
        .zip(b)
        .zip(mask)
        .filter(|(_, &m)| m)
        .fold((0.0f64, 0usize), |(s, n), ((x, y), _)| {
            (s + (x - y).abs() as f64, n + 1)
        });
    assert!(n > 10_000, "only {n} pixels to compare");
    (sum / n as f64) as f32
}

/// The 99th percentile of the luminance step between horizontal neighbours inside `mask`.
fn step_p99(lum: &[f32], mask: &[bool]) -> f32 {
    let mut steps: Vec<f32> = (0..lum.len() - 1)
        .filter(|&i| (i + 1) % W != 0 && mask[i] && mask[i + 1])
        .map(|i| (lum[i + 1] - lum[i]).abs())
        .collect();
    steps.sort_by(f32::total_cmp);
    steps[steps.len() * 99 / 100]
}

/// The issue's measure on three renders: 12 segments with the file's normals, 384 with them, 12 with face
/// normals. Returns (MAE smooth, MAE face normals, p99 step smooth).
fn measure(
    what: &str,
    fine: &(Vec<f32>, Vec<bool>),
    smooth: &(Vec<f32>, Vec<bool>),
    flat: &(Vec<f32>, Vec<bool>),
) {
    let mask = interior(&[&fine.1, &smooth.1, &flat.1]);
    let (e_smooth, e_flat) = (mae(&smooth.0, &fine.0, &mask), mae(&flat.0, &fine.0, &mask));
    let (p_smooth, p_fine, p_flat) = (
        step_p99(&smooth.0, &mask),
        step_p99(&fine.0, &mask),
        step_p99(&flat.0, &mask),
    );
    eprintln!(
        "{what}: MAE to 384 segments: normals {e_smooth:.4}, face normals {e_flat:.4}; p99 step: normals \
         {p_smooth:.4}, 384 segments {p_fine:.4}, face normals {p_flat:.4}"
    );
    assert!(e_smooth <= 0.01, "{what}: {e_smooth}");
    assert!(e_flat >= 3.0 * e_smooth, "{what}: {e_flat} vs {e_smooth}");
    assert!(p_smooth <= 0.015, "{what}: facet steps {p_smooth}");
}

/// OBJ with `vn`: the 12-segment cylinder shades like the 384-segment one; without `vn` and with
/// `--flat-normals` it shows its facets. Without `vn` and the default smoothing (40°) it reads as round too.
#[test]
fn obj_normals_shade_a_coarse_cylinder_like_a_fine_one() {
    let (c12, c384, c12_bare) = (tmp("c12.obj"), tmp("c384.obj"), tmp("c12_bare.obj"));
    write_obj(&c12, 12, true);
    write_obj(&c384, 384, true);
    write_obj(&c12_bare, 12, false);
    let fine = render(&c384, &[]);
    let smooth = render(&c12, &[]);
    let flat = render(&c12_bare, &["--flat-normals"]);
    measure("OBJ vn", &fine, &smooth, &flat);
    // The same file smoothed by the loader (no `vn`, default crease angle): the side is round, the rim sharp.
    let smoothed = render(&c12_bare, &[]);
    measure("OBJ smoothed", &fine, &smoothed, &flat);
    // `--smooth-angle 20` (less than the 30° between side faces) leaves the facets.
    let sharp = render(&c12_bare, &["--smooth-angle", "20"]);
    let mask = interior(&[&fine.1, &sharp.1, &flat.1]);
    assert!(
        mae(&sharp.0, &flat.0, &mask) < 1e-3,
        "at 20° the 30° edges stay sharp"
    );
}

/// glTF with NORMAL: the same; without NORMAL the primitive is flat (the glTF spec), whatever the smoothing.
#[test]
fn gltf_normals_shade_a_coarse_cylinder_like_a_fine_one() {
    let (c12, c384, c12_bare) = (tmp("c12.gltf"), tmp("c384.gltf"), tmp("c12_bare.gltf"));
    write_gltf(&c12, 12, true);
    write_gltf(&c384, 384, true);
    write_gltf(&c12_bare, 12, false);
    let fine = render(&c384, &[]);
    let smooth = render(&c12, &[]);
    let flat = render(&c12_bare, &[]);
    measure("glTF NORMAL", &fine, &smooth, &flat);
}

/// A bad angle is a clear error before anything is loaded.
#[test]
fn a_bad_smoothing_angle_is_refused() {
    let c12 = tmp("c12_refused.obj");
    write_obj(&c12, 12, false);
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args([
            "render",
            "--scene",
            c12.to_str().unwrap(),
            "--smooth-angle",
            "270",
        ])
        .args(["--out", tmp("refused.png").to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--smooth-angle") && err.contains("0..=180"), "{err}");
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(["render", "--smooth-angle", "30", "--flat-normals"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot be used with"));
}
