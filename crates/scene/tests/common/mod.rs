//! Helpers shared by the integration tests (temp dirs, tiny glTF writer).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Shared test scenes (repo at /work/main, shared/ beside it).
pub fn shared_scenes() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes"))
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
