//! glTF files whose meshes need a decompressor hrtao lacks (Draco, meshopt) fail with an error that names the
//! extension, whether the extension is required by a .gltf or a .glb.
mod common;

/// A one-triangle glTF (positions in a data: URI) that requires `ext` and uses it on its mesh primitive.
fn gltf_requiring(ext: &str) -> String {
    // Three float32 positions: (0,0,0), (1,0,0), (0,1,0).
    let positions: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let b64 = common::base64(&positions);
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["{ext}"],
  "extensionsRequired": ["{ext}"],
  "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,{b64}"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}},
                               "extensions": {{"{ext}": {{"bufferView": 0, "attributes": {{"POSITION": 0}}}}}}}}]}}],
  "nodes": [{{"mesh": 0}}],
  "scenes": [{{"nodes": [0]}}],
  "scene": 0
}}"#
    )
}

/// The same JSON in a GLB container (JSON chunk only).
fn glb(json: &str) -> Vec<u8> {
    let mut chunk = json.as_bytes().to_vec();
    while !chunk.len().is_multiple_of(4) {
        chunk.push(b' ');
    }
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(12 + 8 + chunk.len() as u32).to_le_bytes());
    out.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&chunk);
    out
}

#[test]
fn compressed_meshes_give_an_error_naming_the_extension() {
    let dir = std::env::temp_dir().join(format!("hrtao-compressed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The same file without the extension loads: the error below comes from the extension alone.
    let plain = dir.join("plain.gltf");
    let json = gltf_requiring("KHR_draco_mesh_compression")
        .replace(r#""extensionsUsed": ["KHR_draco_mesh_compression"],"#, "")
        .replace(r#""extensionsRequired": ["KHR_draco_mesh_compression"],"#, "");
    std::fs::write(&plain, json).unwrap();
    let scene = hrtao_scene::load(plain.to_str().unwrap(), &mut |_| {}).expect("the uncompressed twin loads");
    assert_eq!(scene.unique_triangle_count(), 1);
    for ext in ["KHR_draco_mesh_compression", "EXT_meshopt_compression"] {
        let text = gltf_requiring(ext);
        let as_gltf = dir.join(format!("{ext}.gltf"));
        std::fs::write(&as_gltf, &text).unwrap();
        let as_glb = dir.join(format!("{ext}.glb"));
        std::fs::write(&as_glb, glb(&text)).unwrap();
        for file in [&as_gltf, &as_glb] {
            let e = hrtao_scene::load(file.to_str().unwrap(), &mut |_| {})
                .err()
                .unwrap_or_else(|| panic!("{} loaded", file.display()))
                .to_string();
            assert!(e.contains(ext), "{}: {e}", file.display());
            assert!(e.contains("cannot decode"), "{}: {e}", file.display());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
