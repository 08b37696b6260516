//! A corpus of malformed and extreme input files, generated on demand for robustness tests
//! (`hrtao render` and the loaders must give a clear error or a correct image for each, never panic or hang).
//! Enabled by the `hostile-corpus` feature; not part of the normal API.
use std::io;
use std::path::{Path, PathBuf};

/// What a correct program does with the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expect {
    /// A clear error naming the file.
    Error,
    /// Loads and renders (a finite image).
    Image,
}

#[derive(Clone, Debug)]
pub struct HostileCase {
    pub name: &'static str,
    pub path: PathBuf,
    pub expect: Expect,
}

fn b64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for chunk in data.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            s.push(if i <= chunk.len() {
                T[((n >> (18 - 6 * i)) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    s
}

fn floats(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

fn u32s(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// A glTF with one mesh of `positions` (+ optional u32 `indices`), nodes given as JSON, buffer inline.
fn gltf(positions: &[f32], indices: Option<&[u32]>, nodes: &str, scenes: &str) -> String {
    let mut bin = floats(positions);
    let pos_len = bin.len();
    let mut views = format!(r#"{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}}"#);
    let mut accessors = format!(
        r#"{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3"}}"#,
        positions.len() / 3
    );
    let mut prim = r#""attributes":{"POSITION":0}"#.to_string();
    if let Some(ix) = indices {
        let data = u32s(ix);
        views.push_str(&format!(
            r#",{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}"#,
            data.len()
        ));
        accessors.push_str(&format!(
            r#",{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}"#,
            ix.len()
        ));
        prim.push_str(r#","indices":1"#);
        bin.extend(data);
    }
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":{scenes},"nodes":{nodes},
"meshes":[{{"primitives":[{{{prim}}}]}}],"accessors":[{accessors}],"bufferViews":[{views}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}]}}"#,
        bin.len(),
        b64(&bin)
    )
}

const TRI: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
/// Two triangles: a 1 x 1 floor and a wall, so AO varies.
const CORNER: [f32; 18] = [
    0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0,
];

fn scaled(v: &[f32], s: f32, offset: f32) -> Vec<f32> {
    v.iter().map(|x| x * s + offset).collect()
}

fn glb(json: &str, bin: Option<&[u8]>) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut chunks = Vec::new();
    chunks.extend((j.len() as u32).to_le_bytes());
    chunks.extend(b"JSON");
    chunks.extend(&j);
    if let Some(b) = bin {
        let mut b = b.to_vec();
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
        chunks.extend((b.len() as u32).to_le_bytes());
        chunks.extend(b"BIN\0");
        chunks.extend(b);
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + chunks.len()) as u32).to_le_bytes());
    out.extend(chunks);
    out
}

/// Writes the corpus into `dir` (created if needed) and returns its cases (at least 30).
pub fn write_corpus(dir: &Path) -> io::Result<Vec<HostileCase>> {
    std::fs::create_dir_all(dir)?;
    let one_node = r#"[{"mesh":0}]"#;
    let one_scene = r#"[{"nodes":[0]}]"#;
    let good = gltf(&CORNER, None, one_node, one_scene);
    let minimal_glb_json = r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}],"bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]}"#;
    let good_glb = glb(minimal_glb_json, Some(&floats(&TRI)));

    let mut files: Vec<(&'static str, &'static str, Vec<u8>, Expect)> = vec![
        ("empty_file", "glb", Vec::new(), Expect::Error),
        ("header_only", "glb", good_glb[..12].to_vec(), Expect::Error),
        (
            "truncated_glb",
            "glb",
            good_glb[..good_glb.len() - 20].to_vec(),
            Expect::Error,
        ),
        (
            "wrong_magic",
            "glb",
            [b"gLTF".as_slice(), &good_glb[4..]].concat(),
            Expect::Error,
        ),
        (
            "wrong_version",
            "glb",
            [&good_glb[..4], &1u32.to_le_bytes(), &good_glb[8..]].concat(),
            Expect::Error,
        ),
        (
            "length_lies",
            "glb",
            [&good_glb[..8], &(1u32 << 31).to_le_bytes(), &good_glb[12..]].concat(),
            Expect::Error,
        ),
        (
            "json_chunk_length_lies",
            "glb",
            [&good_glb[..12], &100_000u32.to_le_bytes(), &good_glb[16..]].concat(),
            Expect::Error,
        ),
        (
            "json_garbage",
            "gltf",
            b"{\"asset\": [[[ this is not json".to_vec(),
            Expect::Error,
        ),
        ("json_not_gltf", "gltf", b"{}".to_vec(), Expect::Error),
        (
            "binary_garbage",
            "gltf",
            (0..4096u32)
                .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
                .collect(),
            Expect::Error,
        ),
        (
            "valid_reference",
            "gltf",
            good.clone().into_bytes(),
            Expect::Image,
        ),
        ("valid_glb", "glb", good_glb.clone(), Expect::Image),
    ];
    let mut text = |name: &'static str, body: String, expect: Expect| {
        files.push((name, "gltf", body.into_bytes(), expect))
    };
    text(
        "buffer_view_out_of_range",
        good.replace(
            r#""byteOffset":0,"byteLength":72"#,
            r#""byteOffset":64,"byteLength":72"#,
        ),
        Expect::Error,
    );
    text(
        "accessor_out_of_range",
        good.replace(r#""count":6,"#, r#""count":600,"#),
        Expect::Error,
    );
    text(
        "accessor_count_huge",
        good.replace(r#""count":6,"#, r#""count":1000000000,"#),
        Expect::Error,
    );
    text(
        "index_past_vertex_count",
        gltf(&TRI, Some(&[0, 1, 7]), one_node, one_scene),
        Expect::Error,
    );
    text(
        "index_u32_max",
        gltf(&TRI, Some(&[0, 1, u32::MAX]), one_node, one_scene),
        Expect::Error,
    );
    text(
        "nan_position",
        gltf(
            &[f32::NAN, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            None,
            one_node,
            one_scene,
        ),
        Expect::Error,
    );
    text(
        "inf_position",
        gltf(
            &[f32::INFINITY, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            None,
            one_node,
            one_scene,
        ),
        Expect::Error,
    );
    // JSON has no NaN literal: a matrix overflowing f32 becomes infinite.
    text(
        "inf_matrix",
        gltf(
            &CORNER,
            None,
            r#"[{"mesh":0,"matrix":[1e39,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}]"#,
            one_scene,
        ),
        Expect::Error,
    );
    text(
        "inf_translation",
        gltf(
            &CORNER,
            None,
            r#"[{"mesh":0,"translation":[1e39,0,0]}]"#,
            one_scene,
        ),
        Expect::Error,
    );
    text(
        "zero_scale_only_node",
        gltf(&CORNER, None, r#"[{"mesh":0,"scale":[0,0,0]}]"#, one_scene),
        // The singular node is skipped with a warning, which leaves nothing to show.
        Expect::Error,
    );
    text(
        "degenerate_triangles_beside_good_ones",
        gltf(
            &[
                CORNER.as_slice(),
                &[0.5, 0.5, 0.0, 0.5, 0.5, 0.0, 0.5, 0.5, 0.0],
                &[0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 2.0, 2.0, 0.0],
            ]
            .concat(),
            None,
            one_node,
            one_scene,
        ),
        Expect::Image,
    );
    text(
        "only_degenerate_triangles",
        gltf(&[0.5; 9], None, one_node, one_scene),
        Expect::Image,
    );
    text(
        "empty_scene",
        gltf(&TRI, None, one_node, r#"[{"nodes":[]}]"#),
        Expect::Error,
    );
    text(
        "nodes_without_meshes",
        gltf(&TRI, None, r#"[{"children":[1]},{}]"#, one_scene),
        Expect::Error,
    );
    let chain: Vec<String> = (0..2000)
        .map(|i| {
            if i < 1999 {
                format!(r#"{{"children":[{}]}}"#, i + 1)
            } else {
                r#"{"mesh":0}"#.into()
            }
        })
        .collect();
    text(
        "deep_node_chain",
        gltf(&TRI, None, &format!("[{}]", chain.join(",")), one_scene),
        Expect::Error,
    );
    text(
        "cyclic_nodes",
        gltf(
            &TRI,
            None,
            r#"[{"mesh":0,"children":[1]},{"children":[0]}]"#,
            one_scene,
        ),
        Expect::Error,
    );
    text(
        "self_parent",
        gltf(&TRI, None, r#"[{"mesh":0,"children":[0]}]"#, one_scene),
        Expect::Error,
    );
    text(
        "missing_bin",
        good.replace(
            &format!("data:application/octet-stream;base64,{}", b64(&floats(&CORNER))),
            "missing.bin",
        ),
        Expect::Error,
    );
    text(
        "missing_texture_is_ignored",
        good.replace(r#""asset":{"version":"2.0"},"#, r#""asset":{"version":"2.0"},"images":[{"uri":"no_such_texture.png"}],"textures":[{"source":0}],"#),
        Expect::Image,
    );
    text(
        "buffer_claims_gigabytes",
        good.replace(
            r#""buffers":[{"byteLength":72,"#,
            r#""buffers":[{"byteLength":4000000000,"#,
        ),
        Expect::Error,
    );
    text(
        "float_indices",
        gltf(&TRI, Some(&[0, 1, 2]), one_node, one_scene)
            .replace(r#""componentType":5125"#, r#""componentType":5126"#),
        Expect::Error,
    );
    text(
        "points_only",
        good.replace(
            r#""attributes":{"POSITION":0}"#,
            r#""attributes":{"POSITION":0},"mode":0"#,
        ),
        Expect::Error,
    );
    text(
        "coordinates_1e7",
        gltf(&scaled(&CORNER, 1e6, 1e7), None, one_node, one_scene),
        Expect::Image,
    );
    text(
        "coordinates_1e-6",
        gltf(&scaled(&CORNER, 1e-6, 0.0), None, one_node, one_scene),
        Expect::Image,
    );
    text(
        "mesh_index_out_of_range",
        gltf(&TRI, None, r#"[{"mesh":5}]"#, one_scene),
        Expect::Error,
    );

    let mut obj = |name: &'static str, body: &str, expect: Expect| {
        files.push((name, "obj", body.as_bytes().to_vec(), expect))
    };
    obj(
        "obj_bad_index",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n",
        Expect::Error,
    );
    obj(
        "obj_zero_index",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        Expect::Error,
    );
    obj("obj_empty", "", Expect::Error);
    obj("obj_no_faces", "v 0 0 0\nv 1 0 0\n", Expect::Error);
    obj("obj_nan", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", Expect::Error);
    obj(
        "obj_missing_mtl",
        "mtllib nowhere.mtl\nusemtl steel\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n",
        Expect::Image,
    );
    obj(
        "obj_garbage",
        "\u{0}\u{1}\u{2}garbage f f f v v v\n\u{7f}",
        Expect::Error,
    );
    obj(
        "obj_1e7",
        "v 10000000 0 0\nv 10000001 0 0\nv 10000000 1 0\nv 10000000 0 1\nf 1 2 3\nf 1 3 4\n",
        Expect::Image,
    );

    let mut cases = Vec::new();
    for (name, ext, bytes, expect) in files {
        let path = dir.join(format!("{name}.{ext}"));
        std::fs::write(&path, bytes)?;
        cases.push(HostileCase { name, path, expect });
    }
    Ok(cases)
}
