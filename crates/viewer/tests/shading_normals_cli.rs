//! Shading normals end to end through `hrtao render` (issue #45): a 12-segment capped cylinder whose file carries
//! normals (OBJ `vn`, glTF NORMAL) shades like a 384-segment one, without facet steps; with face normals (OBJ
//! without `vn` and `--flat-normals`, glTF without NORMAL) it is at least 3x further off. The measure is the one of
//! crates/hrtao-core/tests/shading_normals.rs, on the PNG the command writes.
use std::path::{Path, PathBuf};

mod cli;
#[path = "../../scene/tests/common/mod.rs"]
mod common;

const W: usize = 640;
const H: usize = 360;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hrtao-normals-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write_obj(path: &Path, segments: u32, with_vn: bool) {
    let (p, n, ix) = common::cylinder(segments, 1.0, 1.0);
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

/// The cylinder as a .gltf with an embedded buffer, NORMAL when asked, and a 0.8 grey material (the OBJ's
/// default colour; glTF's default is white).
fn write_gltf(path: &Path, segments: u32, with_normal: bool) {
    let (p, n, ix) = common::cylinder(segments, 1.0, 1.0);
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
        data = common::base64(&bin),
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
    let args: [&[&str]; 3] = [
        &[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--camera",
            camera.to_str().unwrap(),
        ],
        &["--mode", "none", "--frames", "1", "--out", png.to_str().unwrap()],
        extra,
    ];
    cli::hrtao_ok(&args.concat());
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

/// The issue's measure on three renders: 12 segments with the file's normals, 384 with them, 12 with face
/// normals.
fn measure(
    what: &str,
    fine: &(Vec<f32>, Vec<bool>),
    smooth: &(Vec<f32>, Vec<bool>),
    flat: &(Vec<f32>, Vec<bool>),
) {
    common::facet_measure(what, fine, smooth, flat, W);
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
    let mask = common::interior(&[&fine.1, &sharp.1, &flat.1], W);
    assert!(
        common::mae(&sharp.0, &flat.0, &mask) < 1e-3,
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
    let refused = tmp("refused.png");
    let scene = c12.to_str().unwrap();
    let out = cli::hrtao(&[
        "render",
        "--scene",
        scene,
        "--smooth-angle",
        "270",
        "--out",
        refused.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--smooth-angle") && err.contains("0..=180"), "{err}");
    let out = cli::hrtao(&["render", "--smooth-angle", "30", "--flat-normals"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot be used with"));
}
