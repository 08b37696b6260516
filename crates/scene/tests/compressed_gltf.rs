//! Compressed glTF: meshopt-compressed buffer views (gltfpack) and Draco-compressed primitives (gltf-pipeline)
//! load to the geometry of the uncompressed file; corrupt compressed data is a clear error, and a Draco
//! extension that is used but not required falls back to the primitive's uncompressed accessors.
//! testdata/scenes/rod_assembly/rod.{meshopt,draco}.glb are rod.glb compressed by scripts/make-compressed-gltf.sh.
mod common;

use glam::Vec3;
use hrtao_scene::Scene;

/// A one-triangle glTF (positions in a data: URI) that uses `ext` on its mesh primitive, requiring it when
/// `required`; the extension's data is the positions' bufferView, which is not a valid compressed stream.
fn gltf_with(ext: &str, required: bool) -> String {
    // Three float32 positions: (0,0,0), (1,0,0), (0,1,0).
    let positions: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let b64 = common::base64(&positions);
    let required = if required {
        format!(r#""extensionsRequired": ["{ext}"],"#)
    } else {
        String::new()
    };
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["{ext}"],
  {required}
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

/// Every instanced triangle in world space, as (area, centroid), and the world bounds.
fn world_triangles(scene: &Scene) -> (Vec<(f32, Vec3)>, Vec3, Vec3) {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let mut out = Vec::new();
    for inst in &scene.instances {
        for p in &scene.meshes[inst.mesh as usize].primitives {
            let at = |i: u32| {
                inst.transform
                    .transform_point3(Vec3::from(p.positions[i as usize]))
            };
            for t in p.indices.chunks_exact(3) {
                let (a, b, c) = (at(t[0]), at(t[1]), at(t[2]));
                lo = lo.min(a.min(b).min(c));
                hi = hi.max(a.max(b).max(c));
                out.push(((b - a).cross(c - a).length() / 2.0, (a + b + c) / 3.0));
            }
        }
    }
    (out, lo, hi)
}

/// rod.glb compressed by gltfpack (meshopt, KHR_mesh_quantization, octahedral normals) and by gltf-pipeline
/// (Draco) loads to rod's geometry: the same instanced triangles, bounds within the quantization's step,
/// surface area within 0.5 % and area-weighted centroid within 0.1 % of the model's size, with shading
/// normals. Fails with the meshopt views not decoded (the fallback buffer is empty: an error), the OCTAHEDRAL
/// filter left out (normals not unit length), or the Draco attributes matched by position in the list instead
/// of by unique id (positions swapped with colours).
#[test]
fn compressed_rod_loads_to_rods_geometry() {
    let load = |name: &str| {
        let path = common::testdata(&format!("scenes/rod_assembly/{name}"));
        hrtao_scene::load(path.to_str().unwrap(), &mut |_| {}).unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let rod = load("rod.glb");
    let (tris, lo, hi) = world_triangles(&rod);
    let size = (hi - lo).length();
    let area = |t: &[(f32, Vec3)]| t.iter().map(|x| x.0 as f64).sum::<f64>();
    let centroid = |t: &[(f32, Vec3)]| t.iter().fold(Vec3::ZERO, |s, x| s + x.1 * x.0) / area(t) as f32;
    for name in ["rod.meshopt.glb", "rod.draco.glb"] {
        let s = load(name);
        let (t, l, h) = world_triangles(&s);
        assert_eq!(t.len(), tris.len(), "{name}: instanced triangles");
        let bounds = (l - lo).abs().max((h - hi).abs()).max_element();
        assert!(bounds < 2e-3 * size, "{name}: bounds off by {bounds} of {size}");
        let da = (area(&t) / area(&tris) - 1.0).abs();
        assert!(da < 0.005, "{name}: surface area off by {:.3} %", da * 100.0);
        let dc = (centroid(&t) - centroid(&tris)).length();
        assert!(dc < 1e-3 * size, "{name}: centroid off by {dc}");
        for m in &s.meshes {
            for p in &m.primitives {
                assert_eq!(p.normals.len(), p.positions.len(), "{name}: shading normals");
            }
        }
        let (agree, of_rod) = (normals_agree(&s), normals_agree(&rod));
        assert!(
            (agree - of_rod).abs() < 0.02,
            "{name}: {:.1} % of the triangles' vertex normals agree with their face, {:.1} % in rod.glb",
            agree * 100.0,
            of_rod * 100.0
        );
    }
}

/// The share of triangles (weighted by area) whose mean vertex normal is within 60° of their face normal.
fn normals_agree(scene: &Scene) -> f64 {
    let (mut agree, mut all) = (0.0, 0.0);
    for m in &scene.meshes {
        for p in &m.primitives {
            let v = |i: u32| Vec3::from(p.positions[i as usize]);
            let n = |i: u32| Vec3::from(p.normals[i as usize]).normalize_or_zero();
            for t in p.indices.chunks_exact(3) {
                let face = (v(t[1]) - v(t[0])).cross(v(t[2]) - v(t[0]));
                let area = face.length() as f64;
                let mean = (n(t[0]) + n(t[1]) + n(t[2])).normalize_or_zero();
                all += area;
                if mean.dot(face.normalize_or_zero()) > 0.5 {
                    agree += area;
                }
            }
        }
    }
    agree / all.max(1e-30)
}

/// Corrupt compressed data ends in an error naming what is corrupt, never a panic: bytes of the compressed
/// streams overwritten, and a meshopt view whose stride the decoder would assert on. Fails when the stride
/// check before meshoptimizer is removed (the process aborts).
#[test]
fn corrupt_compressed_data_is_a_clear_error() {
    let dir = common::temp_dir("compressed-corrupt");
    let glb_json = |bytes: &[u8]| -> (usize, serde_json::Value) {
        let n = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        (n, serde_json::from_slice(&bytes[20..20 + n]).unwrap())
    };
    for (name, needle) in [("rod.meshopt.glb", "meshopt"), ("rod.draco.glb", "Draco")] {
        let bytes = std::fs::read(common::testdata(&format!("scenes/rod_assembly/{name}"))).unwrap();
        let (n, _) = glb_json(&bytes);
        let bin = 20 + n + 8;
        // The compressed streams are the BIN chunk: overwrite a run in its middle.
        let mut bad = bytes.clone();
        let mid = bin + (bad.len() - bin) / 3;
        for b in &mut bad[mid..mid + 64] {
            *b ^= 0x5a;
        }
        let path = dir.join(format!("corrupt-{name}"));
        std::fs::write(&path, &bad).unwrap();
        match hrtao_scene::load(path.to_str().unwrap(), &mut |_| {}) {
            Err(e) => assert!(e.to_string().contains(needle), "{name}: {e}"),
            // A Draco stream can decode to other values without noticing: then the geometry is still whole.
            Ok(s) => assert!(
                needle == "Draco" && s.unique_triangle_count() > 0,
                "{name} loaded"
            ),
        }
    }
    // A meshopt view with a stride the vertex decoder does not take (a multiple of 4 up to 256).
    let bytes = std::fs::read(common::testdata("scenes/rod_assembly/rod.meshopt.glb")).unwrap();
    let (n, mut json) = glb_json(&bytes);
    json["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["byteStride"] = 6.into();
    let mut text = serde_json::to_vec(&json).unwrap();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&bytes[20 + n..]);
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    let path = dir.join("stride.glb");
    std::fs::write(&path, &out).unwrap();
    let e = hrtao_scene::load(path.to_str().unwrap(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("byteStride 6"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A Draco extension that is used but not required, whose stream does not decode, falls back to the
/// primitive's uncompressed accessors; required, it is an error naming Draco, in a .gltf and a .glb alike.
/// Fails with the fallback removed (the used-only file errs) or applied to a required extension.
#[test]
fn a_used_draco_extension_falls_back_a_required_one_does_not() {
    let dir = common::temp_dir("compressed-fallback");
    for required in [false, true] {
        let text = gltf_with("KHR_draco_mesh_compression", required);
        let as_gltf = dir.join(format!("draco-{required}.gltf"));
        std::fs::write(&as_gltf, &text).unwrap();
        let as_glb = dir.join(format!("draco-{required}.glb"));
        std::fs::write(&as_glb, glb(&text)).unwrap();
        for file in [&as_gltf, &as_glb] {
            let r = hrtao_scene::load(file.to_str().unwrap(), &mut |_| {});
            match (required, r) {
                (false, Ok(s)) => assert_eq!(s.unique_triangle_count(), 1),
                (true, Err(e)) => assert!(e.to_string().contains("Draco"), "{}: {e}", file.display()),
                (_, r) => panic!(
                    "{} (required {required}): {:?}",
                    file.display(),
                    r.map(|s| s.unique_triangle_count())
                ),
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
