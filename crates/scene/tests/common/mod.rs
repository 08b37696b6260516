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
