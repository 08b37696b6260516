//! What a file says about itself (`Scene::metadata`): glTF's asset, PLY comments and obj_info, an STL's solid
//! name or binary header; nothing for OBJ.

mod common;

use common::{base64, no_progress, temp_dir, TRI};
use hrtao_scene::load;

fn pairs(v: &[(&str, &str)]) -> Vec<(String, String)> {
    v.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

fn load_path(p: &std::path::Path) -> hrtao_scene::Scene {
    load(p.to_str().unwrap(), &mut no_progress()).unwrap()
}

#[test]
fn gltf_asset_fields() {
    let dir = temp_dir("meta-gltf");
    let mut bin = Vec::new();
    for c in TRI.iter().flatten() {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"Blender glTF exporter","copyright":"2024 Someone"}},
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
        base64(&bin)
    );
    let p = dir.join("tri.gltf");
    std::fs::write(&p, json).unwrap();
    assert_eq!(
        load_path(&p).metadata,
        pairs(&[
            ("generator", "Blender glTF exporter"),
            ("copyright", "2024 Someone"),
            ("glTF version", "2.0"),
        ])
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ply_comments_and_obj_info() {
    let dir = temp_dir("meta-ply");
    let p = dir.join("tri.ply");
    std::fs::write(
        &p,
        "ply\nformat ascii 1.0\ncomment made by a scanner\nobj_info serial 42\ncomment units mm\n\
         element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    .unwrap();
    assert_eq!(
        load_path(&p).metadata,
        pairs(&[
            ("comment", "made by a scanner"),
            ("comment", "units mm"),
            ("obj_info", "serial 42"),
        ])
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn stl_solid_name_and_binary_header() {
    let dir = temp_dir("meta-stl");
    let ascii = dir.join("ascii.stl");
    std::fs::write(
        &ascii,
        "solid bracket v2\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  \
         endloop\n endfacet\nendsolid bracket v2\n",
    )
    .unwrap();
    assert_eq!(load_path(&ascii).metadata, pairs(&[("solid name", "bracket v2")]));
    // Binary: the 80-byte header, NUL-padded; one triangle.
    let binary = |header: &[u8]| {
        let mut b = vec![0u8; 80];
        b[..header.len()].copy_from_slice(header);
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&[0u8; 12]);
        for v in TRI.iter().flatten() {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&[0u8; 2]);
        b
    };
    let bin = dir.join("binary.stl");
    std::fs::write(&bin, binary(b"Exported by CADTool 3.1")).unwrap();
    assert_eq!(
        load_path(&bin).metadata,
        pairs(&[("header", "Exported by CADTool 3.1")])
    );
    // A header of binary data (or blank) says nothing.
    std::fs::write(&bin, binary(&[1, 2, 3, 200])).unwrap();
    assert!(load_path(&bin).metadata.is_empty());
    std::fs::write(&bin, binary(b"")).unwrap();
    assert!(load_path(&bin).metadata.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn obj_has_none() {
    let dir = temp_dir("meta-obj");
    let p = dir.join("tri.obj");
    std::fs::write(&p, "# a comment\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert!(load_path(&p).metadata.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}
