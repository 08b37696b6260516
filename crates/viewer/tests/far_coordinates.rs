//! A model far from its file's origin (BIM/GIS coordinates, 10^5-10^7 units away) renders the same image as
//! the same model at the origin, through `hrtao render` with cameras in the file's own coordinates: glTF with
//! a root translation, and OBJ with far vertex coordinates.
use std::path::{Path, PathBuf};

mod cli;

/// UTM-like offset of the issue: (690 000, 0, 5 340 000).
const FAR: [f64; 3] = [690_000.0, 0.0, 5_340_000.0];

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-far-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 20 x 20 floor with two boxes on it (y up): contact shadows and creases at a 1-unit scale.
fn geometry() -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut p: Vec<[f32; 3]> = Vec::new();
    let mut idx = Vec::new();
    let mut quad = |p: &mut Vec<[f32; 3]>, c: [[f32; 3]; 4]| {
        let b = p.len() as u32;
        p.extend_from_slice(&c);
        idx.extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
    };
    quad(
        &mut p,
        [
            [-10.0, 0.0, -10.0],
            [-10.0, 0.0, 10.0],
            [10.0, 0.0, 10.0],
            [10.0, 0.0, -10.0],
        ],
    );
    for (cx, cz, h) in [(-2.0f32, 0.0f32, 2.0f32), (2.5, 1.0, 1.0)] {
        let (x0, x1, z0, z1) = (cx - 1.0, cx + 1.0, cz - 1.0, cz + 1.0);
        quad(&mut p, [[x0, h, z0], [x0, h, z1], [x1, h, z1], [x1, h, z0]]);
        quad(&mut p, [[x0, 0.0, z0], [x0, h, z0], [x1, h, z0], [x1, 0.0, z0]]);
        quad(&mut p, [[x0, 0.0, z1], [x1, 0.0, z1], [x1, h, z1], [x0, h, z1]]);
        quad(&mut p, [[x0, 0.0, z0], [x0, 0.0, z1], [x0, h, z1], [x0, h, z0]]);
        quad(&mut p, [[x1, 0.0, z0], [x1, h, z0], [x1, h, z1], [x1, 0.0, z1]]);
    }
    (p, idx)
}

/// The model as glTF (external .bin), its root node translated by `offset`.
fn write_gltf(path: &Path, offset: [f64; 3]) {
    let (p, idx) = geometry();
    let mut bin: Vec<u8> = Vec::new();
    for v in &p {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for i in &idx {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let bin_name = format!("{}.bin", path.file_stem().unwrap().to_str().unwrap());
    std::fs::write(path.with_file_name(&bin_name), &bin).unwrap();
    let (lo, hi) = p.iter().fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), v| {
        (
            std::array::from_fn(|i| lo[i].min(v[i])),
            std::array::from_fn(|i| hi[i].max(v[i])),
        )
    });
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"translation": offset, "children": [1]}, {"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": p.len(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": bin.len() - pos_len}
        ],
        "buffers": [{"uri": bin_name, "byteLength": bin.len()}]
    });
    std::fs::write(path, serde_json::to_string(&json).unwrap()).unwrap();
}

/// The model as OBJ with its vertices moved by `offset` (written with full f64 precision).
fn write_obj(path: &Path, offset: [f64; 3]) {
    let (p, idx) = geometry();
    let mut s = String::new();
    for v in &p {
        s += &format!(
            "v {} {} {}\n",
            v[0] as f64 + offset[0],
            v[1] as f64 + offset[1],
            v[2] as f64 + offset[2]
        );
    }
    for t in idx.chunks(3) {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, s).unwrap();
}

fn write_camera(path: &Path, offset: [f64; 3]) {
    let eye = [7.0 + offset[0], 6.0 + offset[1], 9.0 + offset[2]];
    let target = [0.0 + offset[0], 0.5 + offset[1], 0.0 + offset[2]];
    let cam = serde_json::json!({"eye": eye, "target": target, "up": [0, 1, 0], "fov_y_deg": 40,
        "width": 160, "height": 90});
    std::fs::write(path, cam.to_string()).unwrap();
}

/// Renders per-pixel RTAO (deterministic sequences) and HRTAO and returns both AO images.
fn render(scene: &Path, camera: &Path, tag: &str) -> Vec<Vec<f32>> {
    ["rtao", "hrtao"]
        .iter()
        .map(|mode| {
            let pfm = dir().join(format!("{tag}-{mode}.pfm"));
            let (scene, camera) = (scene.to_str().unwrap(), camera.to_str().unwrap());
            let args: [&[&str]; 3] = [
                &["render", "--scene", scene, "--camera", camera],
                &["--radius", "2", "--rays", "8", "--frames", "8", "--mode", mode],
                &["--ao-out", pfm.to_str().unwrap()],
            ];
            cli::hrtao_ok(&args.concat());
            hrtao_core::imageio::read_pfm(&pfm).unwrap().2
        })
        .collect()
}

fn compare(near: &[Vec<f32>], far: &[Vec<f32>], what: &str) {
    for (mode, (a, b)) in ["rtao", "hrtao"].iter().zip(near.iter().zip(far)) {
        let e = hrtao_core::metrics::ao_error(b, a);
        let dark = a.iter().filter(|&&v| v < 0.9).count();
        println!(
            "{what} {mode}: MAE {:.4} over {} pixels ({dark} occluded)",
            e.mae, e.pixels
        );
        assert!(dark > 500, "{what}: the view shows occlusion");
        assert!(e.mae <= 0.01, "{what} {mode}: far image differs, MAE {}", e.mae);
    }
}

/// The model `write` writes, at the origin and at `FAR` (`ext` files, each with its camera), renders the same
/// images (`compare`).
fn near_and_far_agree(ext: &str, write: fn(&Path, [f64; 3]), what: &str) {
    let d = dir();
    let [near, far] = [("near", [0.0; 3]), ("far", FAR)].map(|(tag, offset)| {
        let scene = d.join(format!("{tag}.{ext}"));
        let camera = d.join(format!("{tag}-{ext}.camera.json"));
        write(&scene, offset);
        write_camera(&camera, offset);
        render(&scene, &camera, &format!("{ext}-{tag}"))
    });
    compare(&near, &far, what);
}

#[test]
fn gltf_far_from_the_origin_renders_the_same_image() {
    near_and_far_agree("gltf", write_gltf, "glTF");
}

#[test]
fn obj_far_from_the_origin_renders_the_same_image() {
    near_and_far_agree("obj", write_obj, "OBJ");
}
