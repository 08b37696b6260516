//! Malformed input must give a clear `Err` naming the problem, never a panic.

mod common;

use common::{no_progress, temp_dir, test_scene, write_gltf, TRI};
use hrtao_scene::{load, SceneError};

fn load_err(path: &std::path::Path) -> SceneError {
    match load(path.to_str().unwrap(), &mut no_progress()) {
        Ok(s) => panic!("{} loaded unexpectedly: {s:?}", path.display()),
        Err(e) => e,
    }
}

const ONE_NODE: &str = r#"[{"mesh":0}]"#;

#[test]
fn missing_file_is_io_error() {
    for name in [
        "/nonexistent/hrtao/x.glb",
        "/nonexistent/hrtao/x.gltf",
        "/nonexistent/hrtao/x.obj",
    ] {
        let e = load(name, &mut no_progress()).unwrap_err();
        assert!(matches!(e, SceneError::Io { .. }), "{name}: {e:?}");
        assert!(e.to_string().contains(name), "{e}");
    }
}

#[test]
fn unsupported_extension() {
    let e = load("model.fbx", &mut no_progress()).unwrap_err();
    assert!(matches!(e, SceneError::UnsupportedFormat(_)), "{e:?}");
    assert!(e.to_string().contains("model.fbx"));
}

#[test]
fn truncated_glb() {
    let dir = temp_dir("truncated");
    let full = std::fs::read(test_scene("rod")).unwrap();
    for (k, len) in [0, 3, 11, 19, 100, full.len() / 2, full.len() - 1]
        .into_iter()
        .enumerate()
    {
        let p = dir.join(format!("rod_trunc{k}.glb"));
        std::fs::write(&p, &full[..len]).unwrap();
        let e = load_err(&p);
        assert!(matches!(e, SceneError::Gltf { .. }), "len {len}: {e:?}");
        assert!(e.to_string().contains("rod_trunc"), "{e}");
    }
    let p = dir.join("rod_half.glb");
    std::fs::write(&p, &full[..full.len() / 2]).unwrap();
    assert!(load_err(&p).to_string().contains("truncated"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn huge_declared_glb_length_is_rejected_without_allocating() {
    let dir = temp_dir("hugelen");
    let mut bytes = std::fs::read(test_scene("rod")).unwrap();
    bytes[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    let p = dir.join("huge.glb");
    std::fs::write(&p, &bytes).unwrap();
    let e = load_err(&p).to_string();
    assert!(
        e.contains("truncated") && e.contains(&u32::MAX.to_string()),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn wrong_magic() {
    let dir = temp_dir("magic");
    let mut bytes = std::fs::read(test_scene("rod")).unwrap();
    bytes[..4].copy_from_slice(b"gLTX");
    let p = dir.join("magic.glb");
    std::fs::write(&p, &bytes).unwrap();
    let e = load_err(&p);
    assert!(matches!(e, SceneError::Gltf { .. }), "{e:?}");
    assert!(e.to_string().contains("magic"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn json_garbage() {
    let dir = temp_dir("garbage");
    let p = dir.join("garbage.gltf");
    std::fs::write(&p, "{ this is not json ]]").unwrap();
    let e = load_err(&p);
    assert!(matches!(e, SceneError::Gltf { .. }), "{e:?}");
    assert!(e.to_string().contains("garbage.gltf"), "{e}");
    // Valid JSON but not glTF.
    std::fs::write(&p, r#"{"hello": [1, 2, 3]}"#).unwrap();
    assert!(matches!(load_err(&p), SceneError::Gltf { .. }));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn tiny_valid_gltf_loads() {
    let dir = temp_dir("tiny");
    let p = write_gltf(&dir, "tri.gltf", &TRI, Some(&[0, 1, 2]), ONE_NODE, "");
    let s = load(p.to_str().unwrap(), &mut no_progress()).unwrap();
    assert_eq!(s.unique_triangle_count(), 1);
    assert_eq!(s.instances.len(), 1);
    assert_eq!(
        s.meshes[0].primitives[0].base_color,
        hrtao_scene::DEFAULT_BASE_COLOR
    );
    // Non-indexed: sequential indices.
    let p = write_gltf(&dir, "tri_noidx.gltf", &TRI, None, ONE_NODE, "");
    let s = load(p.to_str().unwrap(), &mut no_progress()).unwrap();
    assert_eq!(s.meshes[0].primitives[0].indices, vec![0, 1, 2]);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn nan_vertex_position() {
    let dir = temp_dir("nan");
    let pos = [[0.0, 0.0, 0.0], [1.0, f32::NAN, 0.0], [0.0, 1.0, 0.0]];
    let p = write_gltf(&dir, "nan.gltf", &pos, Some(&[0, 1, 2]), ONE_NODE, "");
    let e = load_err(&p);
    assert!(matches!(e, SceneError::Invalid(_)), "{e:?}");
    let m = e.to_string();
    assert!(
        m.contains("nan.gltf") && m.contains("mesh 0") && m.contains("vertex 1"),
        "{m}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn index_past_vertex_count() {
    let dir = temp_dir("index");
    let p = write_gltf(&dir, "idx.gltf", &TRI, Some(&[0, 1, 7]), ONE_NODE, "");
    let e = load_err(&p);
    assert!(matches!(e, SceneError::Invalid(_)), "{e:?}");
    let m = e.to_string();
    assert!(
        m.contains("primitive 0") && m.contains("7") && m.contains("3 vertices"),
        "{m}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn accessor_past_end_of_buffer() {
    let dir = temp_dir("accessor");
    let p = write_gltf(&dir, "acc.gltf", &TRI, None, ONE_NODE, "");
    let text = std::fs::read_to_string(&p).unwrap();
    // Claim 1000 vertices in a 36-byte view.
    std::fs::write(&p, text.replace(r#""count":3"#, r#""count":1000"#)).unwrap();
    let e = load_err(&p);
    let m = e.to_string();
    assert!(
        matches!(e, SceneError::Gltf { .. }) && m.contains("mesh 0 primitive 0"),
        "{m}"
    );
    // Zero count: no panic, no triangles.
    std::fs::write(&p, text.replace(r#""count":3"#, r#""count":0"#)).unwrap();
    assert!(matches!(load_err(&p), SceneError::Empty(_)));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn buffer_byte_length_larger_than_data() {
    let dir = temp_dir("bytelength");
    let p = write_gltf(&dir, "len.gltf", &TRI, None, ONE_NODE, "");
    let text = std::fs::read_to_string(&p).unwrap();
    std::fs::write(
        &p,
        text.replace(r#""byteLength":36,"uri""#, r#""byteLength":900000000000,"uri""#),
    )
    .unwrap();
    let e = load_err(&p);
    assert!(matches!(e, SceneError::Gltf { .. }), "{e:?}");
    assert!(e.to_string().contains("buffer"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn missing_external_bin() {
    let dir = temp_dir("missingbin");
    let p = write_gltf(&dir, "ext.gltf", &TRI, None, ONE_NODE, "");
    let text = std::fs::read_to_string(&p).unwrap();
    let start = text.find("data:").unwrap();
    let end = start + text[start..].find('"').unwrap();
    std::fs::write(&p, format!("{}missing.bin{}", &text[..start], &text[end..])).unwrap();
    let e = load_err(&p);
    assert!(
        matches!(&e, SceneError::Reference { uri, .. } if uri == "missing.bin"),
        "{e:?}"
    );
    assert!(e.to_string().contains("does not exist"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn cyclic_node_graph() {
    let dir = temp_dir("cycle");
    let nodes = r#"[{"mesh":0,"children":[1]},{"children":[2]},{"mesh":0,"children":[0]}]"#;
    let p = write_gltf(
        &dir,
        "cycle.gltf",
        &TRI,
        None,
        nodes,
        r#""scenes":[{"nodes":[0]}],"scene":0,"#,
    );
    let e = load_err(&p);
    assert!(e.to_string().contains("cycl"), "{e}");
    // Self-loop, no scenes at all.
    let p = write_gltf(
        &dir,
        "self.gltf",
        &TRI,
        None,
        r#"[{"mesh":0,"children":[0]}]"#,
        "",
    );
    let e = load_err(&p);
    assert!(
        matches!(e, SceneError::Gltf { .. }) && e.to_string().contains("cycl"),
        "{e:?}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn deep_node_chain_is_an_error_not_a_stack_overflow() {
    let dir = temp_dir("deep");
    let n = 5000;
    let nodes: Vec<String> = (0..n)
        .map(|i| {
            if i + 1 < n {
                format!(r#"{{"mesh":0,"children":[{}]}}"#, i + 1)
            } else {
                r#"{"mesh":0}"#.to_string()
            }
        })
        .collect();
    let nodes = format!("[{}]", nodes.join(","));
    let p = write_gltf(
        &dir,
        "deep.gltf",
        &TRI,
        None,
        &nodes,
        r#""scenes":[{"nodes":[0]}],"#,
    );
    let e = load_err(&p);
    assert!(e.to_string().contains("deeper"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn hierarchy_and_strips_and_points() {
    let dir = temp_dir("hier");
    // Parent translates by (10,0,0), child scales by 2: child world = parent * local.
    let nodes = r#"[{"translation":[10,0,0],"children":[1]},{"mesh":0,"scale":[2,2,2]}]"#;
    let p = write_gltf(&dir, "h.gltf", &TRI, None, nodes, r#""scenes":[{"nodes":[0]}],"#);
    let s = load(p.to_str().unwrap(), &mut no_progress()).unwrap();
    let b = s.bounds();
    assert_eq!(b.min.to_array(), [10.0, 0.0, 0.0]);
    assert_eq!(b.max.to_array(), [12.0, 2.0, 0.0]);

    // Triangle strip of 4 vertices -> 2 triangles.
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let p = write_gltf(&dir, "strip.gltf", &quad, None, ONE_NODE, "");
    let text = std::fs::read_to_string(&p).unwrap();
    std::fs::write(&p, text.replace(r#""POSITION":0}"#, r#""POSITION":0},"mode":5"#)).unwrap();
    let s = load(p.to_str().unwrap(), &mut no_progress()).unwrap();
    assert_eq!(s.unique_triangle_count(), 2);

    // Points only -> skipped -> empty scene error.
    std::fs::write(&p, text.replace(r#""POSITION":0}"#, r#""POSITION":0},"mode":0"#)).unwrap();
    let e = load_err(&p);
    assert!(matches!(e, SceneError::Empty(_)), "{e:?}");
    assert!(e.to_string().contains("no triangles"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn obj_with_bad_index() {
    let dir = temp_dir("objbad");
    let p = dir.join("bad.obj");
    std::fs::write(&p, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    let e = load_err(&p);
    assert!(matches!(e, SceneError::Obj { .. }), "{e:?}");
    assert!(e.to_string().contains("bad.obj"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn empty_obj() {
    let dir = temp_dir("objempty");
    for (name, text) in [
        ("empty.obj", ""),
        ("verts.obj", "# only vertices\nv 0 0 0\nv 1 0 0\n"),
    ] {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        let e = load_err(&p);
        assert!(matches!(e, SceneError::Empty(_)), "{name}: {e:?}");
        assert!(e.to_string().contains(name), "{e}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn unknown_generator_and_bad_params() {
    let e = load("gen:teapot", &mut no_progress()).unwrap_err();
    assert!(matches!(e, SceneError::UnknownGenerator(_)), "{e:?}");
    assert!(e.to_string().contains("teapot"));
    for spec in [
        "gen:racks?rows=abc",
        "gen:racks?rows=-3",
        "gen:racks?rows=0",
        "gen:racks?rows=1.5",
        "gen:racks?colour=red",
        "gen:racks?rows=2&rows=3",
        "gen:racks?rows",
        "gen:racks?detail=100000000",
        "gen:racks?rows=10000&cols=10000&units=40",
        "gen:city?blocks=999999999999999999999999",
        "gen:city?blocks=10000",
        "gen:slab?h=-1",
        "gen:slab?h=nan",
        "gen:slab?h=inf",
        "gen:plane?size=0",
        "gen:box?size=1e30",
    ] {
        let e = load(spec, &mut no_progress()).unwrap_err();
        assert!(matches!(e, SceneError::BadGeneratorParam(_)), "{spec}: {e:?}");
    }
}
