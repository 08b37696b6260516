//! Helpers shared by the integration tests (temp dirs, tiny glTF writer).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A file of the repository's test data (`testdata/` at the repository root).
pub fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(rel)
}

/// A real test scene by its key in `testdata/refs/index.json`: "rod" (the rod assembly) or "cycloidal" (the
/// cycloidal gearbox, which is the bundled scene `assets/default.glb`). Both MIT, see testdata/README.md.
pub fn test_scene(key: &str) -> PathBuf {
    match key {
        "rod" => testdata("scenes/rod_assembly/rod.glb"),
        "cycloidal" => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/default.glb"),
        _ => panic!("no test scene {key:?}: the repository's test data holds \"rod\" and \"cycloidal\""),
    }
}

/// Rewrites a .glb as `dir/STEM.gltf` with its binary chunk in an external `dir/STEM.bin` (the buffer gets a
/// relative `uri`), the layout of glTF files exported with separate buffers. Returns the .gltf path.
pub fn split_glb(glb: &Path, dir: &Path, stem: &str) -> PathBuf {
    let bytes = std::fs::read(glb).unwrap();
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[..4], b"glTF", "{}: not a GLB", glb.display());
    let json_len = u32_at(12);
    assert_eq!(&bytes[16..20], b"JSON");
    let json = std::str::from_utf8(&bytes[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bin_at);
    assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
    let bin = &bytes[bin_at + 8..bin_at + 8 + bin_len];
    // The single buffer of a GLB has no uri: give it one.
    let key = "\"buffers\":[{";
    assert_eq!(json.matches(key).count(), 1, "one buffers array");
    let json = json.replacen(key, &format!("{key}\"uri\":\"{stem}.bin\","), 1);
    std::fs::write(dir.join(format!("{stem}.bin")), bin).unwrap();
    let path = dir.join(format!("{stem}.gltf"));
    std::fs::write(&path, json.trim_end()).unwrap();
    path
}

/// The folder a fetch script of the repository (`scripts/SCRIPT`: Debian packages unpacked into target/) prints;
/// `needs` says what it needs when it fails.
pub fn fetched_data(script: &str, needs: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scripts")
        .join(script);
    let out = std::process::Command::new("bash").arg(path).output().unwrap();
    assert!(
        out.status.success(),
        "scripts/{script} failed (it needs {needs}):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
}

/// A fresh, unique temporary directory for one test.
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-scene-test-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn no_progress() -> impl FnMut(hrtao_scene::LoadProgress) {
    |_| {}
}

pub fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Writes a one-mesh .gltf with an embedded buffer: `positions` (f32 VEC3) and optional
/// u32 `indices`. `nodes_json` is the JSON of the "nodes" array; `extra` is spliced into
/// the root object (e.g. `"scenes":[...],`).
pub fn write_gltf(
    dir: &Path,
    name: &str,
    positions: &[[f32; 3]],
    indices: Option<&[u32]>,
    nodes_json: &str,
    extra: &str,
) -> PathBuf {
    let mut bin = Vec::new();
    for p in positions {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    if let Some(ix) = indices {
        for i in ix {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let (idx_views, idx_acc, idx_ref) = match indices {
        Some(ix) => (
            format!(
                r#",{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}"#,
                ix.len() * 4
            ),
            format!(
                r#",{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}"#,
                ix.len()
            ),
            r#","indices":1"#.to_string(),
        ),
        None => (String::new(), String::new(), String::new()),
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},{extra}
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}}{idx_views}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3"}}{idx_acc}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}{idx_ref}}}]}}],
"nodes":{nodes_json}}}"#,
        bin.len(),
        base64(&bin),
        positions.len()
    );
    let path = dir.join(name);
    std::fs::write(&path, json).unwrap();
    path
}

pub const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A capped cylinder along z (z from -1 to 1) whose side is the curve (a cos θ, b sin θ) over `segments` steps,
/// wound counter-clockwise seen from outside: its positions, the exact normal of each vertex (the curve's on the
/// side, ±z on the caps, which have their own rim vertices) and its triangles.
#[allow(clippy::type_complexity)]
pub fn cylinder(segments: u32, a: f32, b: f32) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let (mut p, mut n, mut ix) = (Vec::new(), Vec::new(), Vec::new());
    let ring = |k: u32| {
        let t = std::f32::consts::TAU * k as f32 / segments as f32;
        let (nx, ny) = (t.cos() / a, t.sin() / b);
        let l = nx.hypot(ny);
        (a * t.cos(), b * t.sin(), [nx / l, ny / l, 0.0])
    };
    // Side: two vertices per step.
    for k in 0..segments {
        let (x, y, normal) = ring(k);
        p.extend([[x, y, -1.0], [x, y, 1.0]]);
        n.extend([normal, normal]);
    }
    for k in 0..segments {
        let (i, j) = (2 * k, 2 * ((k + 1) % segments));
        ix.extend([i, j, j + 1, i, j + 1, i + 1]);
    }
    // Caps: a centre and a ring each.
    for z in [-1.0f32, 1.0] {
        let centre = p.len() as u32;
        p.push([0.0, 0.0, z]);
        n.push([0.0, 0.0, z]);
        for k in 0..segments {
            let (x, y, _) = ring(k);
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

/// Pixels of a `w`-wide image at least 3 pixels from every silhouette of all the masks given (covered in all).
pub fn interior(masks: &[&[bool]], w: usize) -> Vec<bool> {
    let (w, h) = (w as i32, (masks[0].len() / w) as i32);
    let covered =
        |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h && masks.iter().all(|m| m[(y * w + x) as usize]);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| (-3..=3).all(|dy| (-3..=3).all(|dx| covered(x + dx, y + dy))))
        .collect()
}

/// The mean absolute difference of `a` and `b` inside `mask` (over 10,000 pixels).
pub fn mae(a: &[f32], b: &[f32], mask: &[bool]) -> f32 {
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

/// The 99th percentile of the luminance step between horizontal neighbours inside `mask` (rows `w` wide).
pub fn step_p99(lum: &[f32], mask: &[bool], w: usize) -> f32 {
    let mut steps: Vec<f32> = (0..lum.len() - 1)
        .filter(|&i| (i + 1) % w != 0 && mask[i] && mask[i + 1])
        .map(|i| (lum[i + 1] - lum[i]).abs())
        .collect();
    steps.sort_by(f32::total_cmp);
    steps[steps.len() * 99 / 100]
}

/// The facet measure of issue #45 on three shadings (luminance, coverage) of `w`-wide images of the cylinder: 384
/// segments, 12 with normals, 12 with face normals. The 12 segments with normals shade within MAE 0.01 of the
/// 384 and have no facet steps (p99 of the horizontal step ≤ 0.015); with face normals they are ≥ 3x further
/// off. Returns the p99 step of the face normals.
pub fn facet_measure(
    what: &str,
    fine: &(Vec<f32>, Vec<bool>),
    smooth: &(Vec<f32>, Vec<bool>),
    flat: &(Vec<f32>, Vec<bool>),
    w: usize,
) -> f32 {
    let mask = interior(&[&fine.1, &smooth.1, &flat.1], w);
    let (e_smooth, e_flat) = (mae(&smooth.0, &fine.0, &mask), mae(&flat.0, &fine.0, &mask));
    let (p_smooth, p_fine, p_flat) = (
        step_p99(&smooth.0, &mask, w),
        step_p99(&fine.0, &mask, w),
        step_p99(&flat.0, &mask, w),
    );
    eprintln!(
        "{what}: MAE to 384 segments: normals {e_smooth:.4}, face normals {e_flat:.4}; p99 step: normals \
         {p_smooth:.4}, 384 segments {p_fine:.4}, face normals {p_flat:.4}"
    );
    assert!(e_smooth <= 0.01, "{what}: {e_smooth}");
    assert!(e_flat >= 3.0 * e_smooth, "{what}: {e_flat} vs {e_smooth}");
    assert!(p_smooth <= 0.015, "{what}: facet steps {p_smooth}");
    p_flat
}
