//! Helpers of the viewer's integration tests: the repository's test data.
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
