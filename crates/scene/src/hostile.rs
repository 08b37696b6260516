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

mod formats;

#[derive(Clone, Debug)]
pub struct HostileCase {
    pub name: &'static str,
    pub path: PathBuf,
    pub expect: Expect,
    /// For a file whose reference leads somewhere bad (buffer URI, `mtllib`): the reference as written,
    /// which the error must name besides the file.
    pub reference: Option<&'static str>,
}

/// What one corpus entry is on disk.
enum Entry {
    File(Vec<u8>),
    /// A named pipe (nobody ever writes to it: reading it would block forever).
    Fifo,
    Dir,
    /// A symlink to this target.
    Link(&'static str),
}

/// Creates `path` as `entry`, replacing whatever is there (never writing into a stale FIFO).
/// Writes each (name, extension, bytes, expected outcome) into `dir` as NAME.EXT: cases with no reference.
fn write_files(
    dir: &Path,
    files: Vec<(&'static str, &'static str, Vec<u8>, Expect)>,
) -> io::Result<Vec<HostileCase>> {
    let mut out = Vec::new();
    for (name, ext, bytes, expect) in files {
        let path = dir.join(format!("{name}.{ext}"));
        make(&path, &Entry::File(bytes))?;
        out.push(HostileCase {
            name,
            path,
            expect,
            reference: None,
        });
    }
    Ok(out)
}

fn make(path: &Path, entry: &Entry) -> io::Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path)?,
        Ok(_) => std::fs::remove_file(path)?,
        Err(_) => {}
    }
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent)?;
    }
    match entry {
        Entry::File(bytes) => std::fs::write(path, bytes),
        Entry::Dir => std::fs::create_dir(path),
        Entry::Link(target) => std::os::unix::fs::symlink(target, path),
        Entry::Fifo => {
            use std::os::unix::ffi::OsStrExt;
            let c = std::ffi::CString::new(path.as_os_str().as_bytes())
                .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
            // SAFETY: `c` is a valid NUL-terminated path that outlives the call.
            if unsafe { libc::mkfifo(c.as_ptr(), 0o644) } != 0 {
                return Err(io::Error::last_os_error());
            }
            Ok(())
        }
    }
}

/// Standard base64 with padding (glTF `data:` URIs): the encoder of the crate the loader decodes them with.
fn b64(data: &[u8]) -> String {
    base64::encode(data)
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

/// A binary STL of the triangles in `v` (9 floats each) with `header` at the start of its 80-byte header.
pub fn stl_binary(v: &[f32], header: &[u8]) -> Vec<u8> {
    let mut out = header.to_vec();
    out.resize(80, 0);
    out.extend(((v.len() / 9) as u32).to_le_bytes());
    for t in v.chunks_exact(9) {
        out.extend([0u8; 12]);
        out.extend(floats(t));
        out.extend([0u8; 2]);
    }
    out
}

/// An ASCII STL of the triangles in `v` (9 floats each).
pub fn stl_ascii(v: &[f32]) -> String {
    let mut s = String::from("solid hrtao\n");
    for t in v.chunks_exact(9) {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for p in t.chunks_exact(3) {
            s.push_str(&format!("      vertex {} {} {}\n", p[0], p[1], p[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str("endsolid hrtao\n");
    s
}

fn ply_header(format: &str, vertices: u64, faces: usize) -> String {
    format!(
        "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n\
         property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

/// An ASCII PLY of the triangles in `v` (9 floats each, unshared vertices); `vertex_count` overrides the
/// vertex count the header declares.
pub fn ply_ascii(v: &[f32], vertex_count: Option<u64>) -> String {
    let n = v.len() / 3;
    let mut s = ply_header("ascii", vertex_count.unwrap_or(n as u64), n / 3);
    for p in v.chunks_exact(3) {
        s.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
    }
    for t in 0..n / 3 {
        s.push_str(&format!("3 {} {} {}\n", 3 * t, 3 * t + 1, 3 * t + 2));
    }
    s
}

/// A binary little-endian PLY of the triangles in `v`.
pub fn ply_binary(v: &[f32]) -> Vec<u8> {
    let n = v.len() / 3;
    let mut out = ply_header("binary_little_endian", n as u64, n / 3).into_bytes();
    out.extend(floats(v));
    for t in 0..n / 3 {
        out.push(3);
        out.extend(u32s(&[3 * t as u32, 3 * t as u32 + 1, 3 * t as u32 + 2]));
    }
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

    let corner_stl = stl_binary(&CORNER, b"hrtao corner");
    let mut count_lies = corner_stl.clone();
    count_lies[80..84].copy_from_slice(&4_000_000_000u32.to_le_bytes());
    files.extend([
        ("stl_binary", "stl", corner_stl, Expect::Image),
        (
            "stl_binary_header_says_solid",
            "stl",
            stl_binary(&CORNER, b"solid but binary"),
            Expect::Image,
        ),
        ("stl_ascii", "stl", stl_ascii(&CORNER).into_bytes(), Expect::Image),
        ("stl_count_far_beyond_file_size", "stl", count_lies, Expect::Error),
        (
            "stl_ascii_garbage",
            "stl",
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zz\n".to_vec(),
            Expect::Error,
        ),
        ("stl_tiny", "stl", b"abc".to_vec(), Expect::Error),
        (
            "ply_ascii",
            "ply",
            ply_ascii(&CORNER, None).into_bytes(),
            Expect::Image,
        ),
        ("ply_binary", "ply", ply_binary(&CORNER), Expect::Image),
        (
            "ply_vertex_count_far_beyond_file_size",
            "ply",
            ply_ascii(&CORNER, Some(4_000_000_000)).into_bytes(),
            Expect::Error,
        ),
        (
            "ply_face_index_out_of_range",
            "ply",
            ply_ascii(&CORNER, None)
                .replace("3 3 4 5", "3 3 4 99")
                .into_bytes(),
            Expect::Error,
        ),
        (
            "ply_garbage",
            "ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n".to_vec(),
            Expect::Error,
        ),
    ]);
    let mut cases = Vec::new();
    for (name, ext, bytes, expect) in files {
        let path = dir.join(format!("{name}.{ext}"));
        make(&path, &Entry::File(bytes))?;
        let reference = (name == "missing_bin").then_some("missing.bin");
        cases.push(HostileCase {
            name,
            path,
            expect,
            reference,
        });
    }
    cases.extend(write_reference_cases(dir, &good)?);
    cases.extend(formats::write(dir)?);
    Ok(cases)
}

/// Files whose references lead where no model data lives (devices, FIFOs, directories, outside the
/// folder, sizes that lie), the model path itself being such a thing, and valid external references.
fn write_reference_cases(dir: &Path, good: &str) -> io::Result<Vec<HostileCase>> {
    let inline = format!("data:application/octet-stream;base64,{}", b64(&floats(&CORNER)));
    // The good glTF with its buffer at `uri`, declaring `len` bytes.
    let external = |uri: &str, len: u64| {
        good.replace(&inline, uri).replace(
            r#""buffers":[{"byteLength":72,"#,
            &format!(r#""buffers":[{{"byteLength":{len},"#),
        )
    };
    let obj_body = |mtllib: &str| {
        format!("mtllib {mtllib}\nusemtl steel\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n")
    };
    const HUGE: u64 = 4_000_000_000;
    // (name, extension, the model entry, reference named in the error, files beside, expectation)
    type Case = (
        &'static str,
        &'static str,
        Entry,
        Option<&'static str>,
        Vec<(&'static str, Entry)>,
        Expect,
    );
    let text = |s: String| Entry::File(s.into_bytes());
    // A glTF whose buffer is at `uri` (declaring `len` bytes), refused naming it; `beside` its files.
    let bad_buffer = |name, uri, len, beside| -> Case {
        (
            name,
            "gltf",
            text(external(uri, len)),
            Some(uri),
            beside,
            Expect::Error,
        )
    };
    // An OBJ whose material library is `uri`, refused naming it.
    let bad_mtllib =
        |name, uri, beside| -> Case { (name, "obj", text(obj_body(uri)), Some(uri), beside, Expect::Error) };
    let cases: Vec<Case> = vec![
        bad_buffer("buffer_dev_zero", "/dev/zero", HUGE, vec![]),
        bad_buffer("buffer_file_uri_dev_zero", "file:///dev/zero", HUGE, vec![]),
        bad_buffer("buffer_dev_urandom", "/dev/urandom", HUGE, vec![]),
        bad_buffer(
            "buffer_fifo",
            "buffer_fifo.bin",
            72,
            vec![("buffer_fifo.bin", Entry::Fifo)],
        ),
        bad_buffer(
            "buffer_symlink_to_dev_zero",
            "zero_link.bin",
            HUGE,
            vec![("zero_link.bin", Entry::Link("/dev/zero"))],
        ),
        bad_buffer("buffer_etc_passwd", "../../../../../../etc/passwd", 72, vec![]),
        bad_buffer(
            "buffer_directory",
            "a_directory.bin",
            72,
            vec![("a_directory.bin", Entry::Dir)],
        ),
        bad_buffer("buffer_missing_file", "no_such_file.bin", 72, vec![]),
        bad_buffer(
            "buffer_shorter_than_byte_length",
            "short.bin",
            72,
            vec![("short.bin", Entry::File(floats(&CORNER[..9])))],
        ),
        bad_buffer("buffer_http_uri", "http://example.com/part.bin", 72, vec![]),
        (
            "buffer_external_valid",
            "gltf",
            text(external("corner.bin", 72)),
            None,
            vec![("corner.bin", Entry::File(floats(&CORNER)))],
            Expect::Image,
        ),
        (
            "buffer_external_subfolder_percent_encoded",
            "gltf",
            text(external("sub%20folder/corner%2B.bin", 72)),
            None,
            vec![("sub folder/corner+.bin", Entry::File(floats(&CORNER)))],
            Expect::Image,
        ),
        (
            "model_is_a_fifo",
            "gltf",
            Entry::Fifo,
            None,
            vec![],
            Expect::Error,
        ),
        (
            "model_is_a_directory",
            "glb",
            Entry::Dir,
            None,
            vec![],
            Expect::Error,
        ),
        (
            "model_is_dev_zero",
            "glb",
            Entry::Link("/dev/zero"),
            None,
            vec![],
            Expect::Error,
        ),
        bad_mtllib("obj_mtllib_dev_zero", "/dev/zero", vec![]),
        bad_mtllib(
            "obj_mtllib_fifo",
            "mtl_fifo.mtl",
            vec![("mtl_fifo.mtl", Entry::Fifo)],
        ),
        bad_mtllib(
            "obj_mtllib_symlink_to_dev_zero",
            "zero_link.mtl",
            vec![("zero_link.mtl", Entry::Link("/dev/zero"))],
        ),
        bad_mtllib("obj_mtllib_etc_passwd", "../../../../../../etc/passwd", vec![]),
        (
            "obj_mtllib_valid",
            "obj",
            text(obj_body("steel.mtl")),
            None,
            vec![(
                "steel.mtl",
                Entry::File(b"newmtl steel\nKd 0.2 0.4 0.8\n".to_vec()),
            )],
            Expect::Image,
        ),
    ];
    let mut out = Vec::new();
    for (name, ext, entry, reference, beside, expect) in cases {
        for (file, e) in &beside {
            make(&dir.join(file), e)?;
        }
        let path = dir.join(format!("{name}.{ext}"));
        make(&path, &entry)?;
        out.push(HostileCase {
            name,
            path,
            expect,
            reference,
        });
    }
    Ok(out)
}

pub use formats::threemf_whitespace;

/// Bombs measured against a scene memory limit of `budget` bytes (`HRTAO_MAX_SCENE_MB`), each for its time and
/// peak memory besides its outcome: a 3MF whose model part inflates to half the budget of whitespace (refused
/// before it is inflated: parsing takes up to 3x the part), one inflating to a quarter (within the budget:
/// streamed, the blanks squeezed, it opens), IFC mapped items nested 9 levels deep 10 a level (10^9 boxes from
/// 14 kB: refused by counting before tessellating) and an IFC cut in the middle of an entity (opens with a
/// warning). The IFC cases need the worker's venv.
pub fn write_budget_corpus(dir: &Path, budget: u64) -> io::Result<Vec<HostileCase>> {
    std::fs::create_dir_all(dir)?;
    let files: Vec<(&'static str, &'static str, Vec<u8>, Expect)> = vec![
        (
            "3mf_whitespace_half_budget",
            "3mf",
            threemf_whitespace(budget / 2)?,
            Expect::Error,
        ),
        (
            "3mf_whitespace_quarter_budget",
            "3mf",
            threemf_whitespace(budget / 4)?,
            Expect::Image,
        ),
        (
            "ifc_mapped_items_1e9",
            "ifc",
            ifc_mapped_bomb(9, 10).into_bytes(),
            Expect::Error,
        ),
        (
            "ifc_truncated_mid_entity",
            "ifc",
            ifc_truncated_mid_entity().into_bytes(),
            Expect::Image,
        ),
    ];
    write_files(dir, files)
}

/// Variations of the generated STEP file ([`step_boxes`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct StepOptions {
    /// Every box but the first has height 0: its side faces have no area, its top and bottom coincide.
    pub flat: bool,
    /// The length unit refers to an entity the file does not define.
    pub undefined_unit: bool,
    /// The product is used as a component of itself (a NEXT_ASSEMBLY_USAGE_OCCURRENCE from it to it).
    pub self_reference: bool,
}

/// A STEP (AP214) file of `n` 10 mm boxes as faceted B-rep solids of one part (40 entities a box), in millimetres.
pub fn step_boxes(n: usize, o: StepOptions) -> String {
    let mut s = String::from(
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('hrtao hostile corpus'),'2;1');\n\
         FILE_NAME('boxes','2026-01-01T00:00:00',(''),(''),'','','');\n\
         FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n\
         #1=APPLICATION_CONTEXT('automotive design');\n\
         #2=APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#1);\n\
         #3=PRODUCT_CONTEXT('',#1,'mechanical');\n#4=PRODUCT('boxes','boxes','',(#3));\n\
         #5=PRODUCT_DEFINITION_FORMATION('','',#4);\n#6=PRODUCT_DEFINITION_CONTEXT('part definition',#1,'design');\n\
         #7=PRODUCT_DEFINITION('design','',#5,#6);\n#8=PRODUCT_DEFINITION_SHAPE('','',#7);\n\
         #9=SHAPE_DEFINITION_REPRESENTATION(#8,#10);\n",
    );
    let first = 100;
    let per = 40;
    let breps: Vec<String> = (0..n).map(|i| format!("#{}", first + i * per + 27)).collect();
    s += &format!(
        "#10=FACETED_BREP_SHAPE_REPRESENTATION('',({}),#11);\n",
        breps.join(",")
    );
    let unit = if o.undefined_unit { 99 } else { 12 };
    s += &format!(
        "#11=(GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#15)) \
         GLOBAL_UNIT_ASSIGNED_CONTEXT((#{unit},#13,#14)) REPRESENTATION_CONTEXT('',''));\n\
         #12=(LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.));\n\
         #13=(NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.));\n\
         #14=(NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT());\n\
         #15=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#{unit},'distance_accuracy_value','');\n"
    );
    // Face normals in the order of `BOX_FACES` (-x, +x, -y, +y, -z, +z) and reference directions (+z, +x) of the
    // faces' planes.
    s += "#30=DIRECTION('',(-1.,0.,0.));\n#31=DIRECTION('',(1.,0.,0.));\n#32=DIRECTION('',(0.,-1.,0.));\n\
          #33=DIRECTION('',(0.,1.,0.));\n#34=DIRECTION('',(0.,0.,-1.));\n#35=DIRECTION('',(0.,0.,1.));\n\
          #36=DIRECTION('',(1.,0.,0.));\n#37=DIRECTION('',(0.,0.,1.));\n";
    if o.self_reference {
        s += "#20=NEXT_ASSEMBLY_USAGE_OCCURRENCE('1','self','',#7,#7,$);\n\
              #21=PRODUCT_DEFINITION_SHAPE('','',#20);\n\
              #22=CONTEXT_DEPENDENT_SHAPE_REPRESENTATION(#23,#21);\n\
              #23=(REPRESENTATION_RELATIONSHIP('','',#10,#10) REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#24) \
              SHAPE_REPRESENTATION_RELATIONSHIP());\n\
              #24=ITEM_DEFINED_TRANSFORMATION('','',#25,#26);\n\
              #25=AXIS2_PLACEMENT_3D('',#27,$,$);\n#26=AXIS2_PLACEMENT_3D('',#28,$,$);\n\
              #27=CARTESIAN_POINT('',(0.,0.,0.));\n#28=CARTESIAN_POINT('',(50.,0.,0.));\n";
    }
    let side = (n as f64).sqrt().ceil().max(1.0) as usize;
    for i in 0..n {
        let h = if o.flat && i > 0 { 0.0 } else { 10.0 };
        let b = first + i * per;
        let (x0, y0) = (20.0 * (i % side) as f32, 20.0 * (i / side) as f32);
        for (c, [x, y, z]) in crate::generate::box_corners([x0, y0, 0.0], [x0 + 10.0, y0 + 10.0, h])
            .into_iter()
            .enumerate()
        {
            s += &format!("#{}=CARTESIAN_POINT('',({x:.1},{y:.1},{z:.1}));\n", b + c);
        }
        for (f, corners) in crate::generate::BOX_FACES.iter().enumerate() {
            let pts: Vec<String> = corners.iter().map(|&c| format!("#{}", b + c as usize)).collect();
            s += &format!("#{}=POLY_LOOP('',({}));\n", b + 8 + f, pts.join(","));
            s += &format!("#{}=FACE_OUTER_BOUND('',#{},.T.);\n", b + 14 + f, b + 8 + f);
            // The plane through the loop's first corner; the x faces take +z as reference direction, the others +x.
            let reference = if f < 2 { 37 } else { 36 };
            s += &format!(
                "#{}=AXIS2_PLACEMENT_3D('',#{},#{},#{reference});\n",
                b + 28 + f,
                b + corners[0] as usize,
                30 + f
            );
            s += &format!("#{}=PLANE('',#{});\n", b + 34 + f, b + 28 + f);
            s += &format!(
                "#{}=FACE_SURFACE('',(#{}),#{},.T.);\n",
                b + 20 + f,
                b + 14 + f,
                b + 34 + f
            );
        }
        let faces: Vec<String> = (0..6).map(|f| format!("#{}", b + 20 + f)).collect();
        s += &format!("#{}=CLOSED_SHELL('',({}));\n", b + 26, faces.join(","));
        s += &format!("#{}=FACETED_BREP('',#{});\n", b + 27, b + 26);
    }
    s += "ENDSEC;\nEND-ISO-10303-21;\n";
    s
}

/// STEP and IGES files for the kernel's loader: truncated, garbage named `.step`, a header without data, an
/// assembly containing itself, faces without area, 10^4 solids, an entity count beyond the cap, an undefined
/// unit. Loading them needs the OpenCASCADE worker (`LoadOptions::cad`).
pub fn write_cad_corpus(dir: &Path) -> io::Result<Vec<HostileCase>> {
    std::fs::create_dir_all(dir)?;
    let one = step_boxes(1, StepOptions::default());
    let header_end = one.find("DATA;").unwrap_or(0);
    let mut garbage = Vec::with_capacity(4096);
    let mut x: u32 = 0x1234_5678;
    for _ in 0..4096 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        garbage.push(x as u8);
    }
    // One more entity than the cap: tiny entities, refused by counting before the kernel runs.
    let mut over_cap = String::from(&one[..header_end]);
    over_cap += "DATA;\n";
    for i in 1..=(crate::cad::MAX_CAD_ENTITIES + 1) {
        over_cap += &format!("#{i}=A();\n");
    }
    over_cap += "ENDSEC;\nEND-ISO-10303-21;\n";
    let files: Vec<(&'static str, &'static str, Vec<u8>, Expect)> = vec![
        ("step_valid_box", "step", one.clone().into_bytes(), Expect::Image),
        ("step_garbage", "step", garbage.clone(), Expect::Error),
        ("iges_garbage", "igs", garbage, Expect::Error),
        ("step_empty", "stp", Vec::new(), Expect::Error),
        (
            "step_header_only",
            "step",
            format!("{}END-ISO-10303-21;\n", &one[..header_end]).into_bytes(),
            Expect::Error,
        ),
        (
            "step_truncated",
            "step",
            one.as_bytes()[..one.len() / 2].to_vec(),
            Expect::Error,
        ),
        (
            "step_self_reference",
            "step",
            step_boxes(
                1,
                StepOptions {
                    self_reference: true,
                    ..Default::default()
                },
            )
            .into_bytes(),
            Expect::Error,
        ),
        (
            "step_no_area_faces",
            "step",
            step_boxes(
                4,
                StepOptions {
                    flat: true,
                    ..Default::default()
                },
            )
            .into_bytes(),
            Expect::Image,
        ),
        (
            "step_undefined_unit",
            "step",
            step_boxes(
                2,
                StepOptions {
                    undefined_unit: true,
                    ..Default::default()
                },
            )
            .into_bytes(),
            Expect::Image,
        ),
        (
            "step_10k_solids",
            "step",
            step_boxes(10_000, StepOptions::default()).into_bytes(),
            Expect::Image,
        ),
        (
            "step_over_entity_cap",
            "step",
            over_cap.into_bytes(),
            Expect::Error,
        ),
    ];
    write_files(dir, files)
}

/// A one-box IFC4 file written by hand: a project and an IfcBuildingElementProxy (outside any spatial structure)
/// whose body is an IfcTriangulatedFaceSet; `extra` lines go before the end of its DATA section.
pub fn ifc_box(schema: &str, extra: &str) -> String {
    format!(
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('ViewDefinition [CoordinationView]'),'2;1');\n\
         FILE_NAME('box.ifc','2026-01-01T00:00:00',(''),(''),'hrtao','hrtao','');\nFILE_SCHEMA(('{schema}'));\n\
         ENDSEC;\nDATA;\n\
         #1=IFCPROJECT('0YvctVUKr0kugbFTf53O9L',$,'Box project',$,$,$,$,(#4),#7);\n\
         #2=IFCCARTESIANPOINT((0.,0.,0.));\n#3=IFCAXIS2PLACEMENT3D(#2,$,$);\n\
         #4=IFCGEOMETRICREPRESENTATIONCONTEXT($,'Model',3,1.E-05,#3,$);\n\
         #5=IFCSIUNIT(*,.LENGTHUNIT.,$,.METRE.);\n#7=IFCUNITASSIGNMENT((#5));\n\
         #10=IFCLOCALPLACEMENT($,#3);\n\
         #11=IFCCARTESIANPOINTLIST3D(((0.,0.,0.),(1.,0.,0.),(1.,1.,0.),(0.,1.,0.),(0.,0.,1.),(1.,0.,1.),(1.,1.,1.),(0.,1.,1.)));\n\
         #12=IFCTRIANGULATEDFACESET(#11,$,.T.,((1,3,2),(1,4,3),(5,6,7),(5,7,8),(1,2,6),(1,6,5),(2,3,7),(2,7,6),(3,4,8),(3,8,7),(4,1,5),(4,5,8)),$);\n\
         #13=IFCSHAPEREPRESENTATION(#4,'Body','Tessellation',(#12));\n#14=IFCPRODUCTDEFINITIONSHAPE($,$,(#13));\n\
         #15=IFCBUILDINGELEMENTPROXY('1YvctVUKr0kugbFTf53O9L',$,'box',$,$,#10,#14,$,$);\n{extra}\
         ENDSEC;\nEND-ISO-10303-21;\n"
    )
}

/// IFC files for the IfcOpenShell worker: garbage, empty, a header only, truncated (before its geometry: an
/// error; in the middle of an entity after it: an image with a warning), a STEP schema that is not IFC, an
/// unknown IFC schema, an ifcZIP and an ifcXML named `.ifc`, a project without geometry, an aggregation cycle
/// (the project decomposed into itself), mapped items nested 9 levels deep 10 a level (10^9 boxes, refused by
/// counting), ten products sharing one mapped representation, and the valid box. Loading them needs the
/// worker's venv.
pub fn write_ifc_corpus(dir: &Path) -> io::Result<Vec<HostileCase>> {
    std::fs::create_dir_all(dir)?;
    let one = ifc_box("IFC4", "");
    let header_end = one.find("DATA;").unwrap_or(0);
    let no_geometry = one
        .lines()
        .filter(|l| !l.starts_with("#1") || l.starts_with("#1="))
        .collect::<Vec<_>>()
        .join("\n");
    let cycle = ifc_box(
        "IFC4",
        "#20=IFCRELAGGREGATES('2YvctVUKr0kugbFTf53O9L',$,$,$,#1,(#1,#15));\n\
         #21=IFCRELAGGREGATES('3YvctVUKr0kugbFTf53O9L',$,$,$,#15,(#1));\n",
    );
    let files: Vec<(&'static str, Vec<u8>, Expect)> = vec![
        ("ifc_valid_box", one.clone().into_bytes(), Expect::Image),
        ("ifc_aggregation_cycle", cycle.into_bytes(), Expect::Image),
        (
            "ifc_garbage",
            b"\x7fELF\x02\x01\x01garbage".repeat(64),
            Expect::Error,
        ),
        ("ifc_empty", Vec::new(), Expect::Error),
        (
            "ifc_header_only",
            format!("{}END-ISO-10303-21;\n", &one[..header_end]).into_bytes(),
            Expect::Error,
        ),
        (
            "ifc_truncated",
            one.as_bytes()[..one.len() / 2].to_vec(),
            Expect::Error,
        ),
        (
            "ifc_step_schema",
            one.replace("'IFC4'", "'AUTOMOTIVE_DESIGN'").into_bytes(),
            Expect::Error,
        ),
        (
            "ifc_unknown_schema",
            one.replace("'IFC4'", "'IFC9'").into_bytes(),
            Expect::Error,
        ),
        ("ifc_zip", b"PK\x03\x04\x14\x00\x00\x00".repeat(16), Expect::Error),
        (
            "ifc_xml",
            b"<?xml version=\"1.0\"?><ifcXML/>".to_vec(),
            Expect::Error,
        ),
        ("ifc_no_geometry", no_geometry.into_bytes(), Expect::Error),
        (
            "ifc_mapped_items_1e9",
            ifc_mapped_bomb(9, 10).into_bytes(),
            Expect::Error,
        ),
        (
            "ifc_truncated_mid_entity",
            ifc_truncated_mid_entity().into_bytes(),
            Expect::Image,
        ),
        (
            "ifc_shared_mapped_items",
            ifc_shared_mapped(10).into_bytes(),
            Expect::Image,
        ),
    ];
    let mut out = Vec::new();
    for (name, bytes, expect) in files {
        let path = dir.join(format!("{name}.ifc"));
        make(&path, &Entry::File(bytes))?;
        out.push(HostileCase {
            name,
            path,
            expect,
            reference: None,
        });
    }
    Ok(out)
}

/// The box's geometry as representation map 0, and `levels` representation maps each placing the one below
/// `per_level` times (IfcMappedItem, each offset along x): one IfcBuildingElementProxy whose body maps the top
/// one expands to `per_level^levels` boxes from a file of a few hundred entities (9 levels of 10: 10^9 boxes in
/// 14 kB).
pub fn ifc_mapped_bomb(levels: u32, per_level: u32) -> String {
    let mut extra = String::new();
    // Representation of level 0: the box's own (#13); each level k adds a map of level k - 1, its items and its
    // representation.
    let mut below = 13u32;
    let mut id = 100u32;
    for k in 1..=levels {
        let map = id;
        extra += &format!("#{map}=IFCREPRESENTATIONMAP(#3,#{below});\n");
        id += 1;
        let mut items = Vec::new();
        for j in 0..per_level {
            let step = 2.0 * (per_level as f64).powi(k as i32 - 1);
            extra += &format!(
                "#{}=IFCCARTESIANPOINT(({:.1},0.,0.));\n#{}=IFCCARTESIANTRANSFORMATIONOPERATOR3D($,$,#{},$,$);\n\
                 #{}=IFCMAPPEDITEM(#{map},#{});\n",
                id,
                step * j as f64,
                id + 1,
                id,
                id + 2,
                id + 1
            );
            items.push(format!("#{}", id + 2));
            id += 3;
        }
        extra += &format!(
            "#{id}=IFCSHAPEREPRESENTATION(#4,'Body','MappedRepresentation',({}));\n",
            items.join(",")
        );
        below = id;
        id += 1;
    }
    ifc_box("IFC4", &extra).replace(
        "#14=IFCPRODUCTDEFINITIONSHAPE($,$,(#13));",
        &format!("#14=IFCPRODUCTDEFINITIONSHAPE($,$,(#{below}));"),
    )
}

/// `n` products (IfcBuildingElementProxy, 2 m apart) whose bodies map one representation map of the box: the
/// legitimate sharing that must stay one mesh with `n` instances.
pub fn ifc_shared_mapped(n: u32) -> String {
    let mut extra = String::from("#100=IFCREPRESENTATIONMAP(#3,#13);\n");
    for k in 0..n {
        let b = 200 + 10 * k;
        extra += &format!(
            "#{b}=IFCCARTESIANPOINT(({:.1},0.,0.));\n#{}=IFCAXIS2PLACEMENT3D(#{b},$,$);\n\
             #{}=IFCLOCALPLACEMENT($,#{});\n#{}=IFCCARTESIANTRANSFORMATIONOPERATOR3D($,$,#2,$,$);\n\
             #{}=IFCMAPPEDITEM(#100,#{});\n#{}=IFCSHAPEREPRESENTATION(#4,'Body','MappedRepresentation',(#{}));\n\
             #{}=IFCPRODUCTDEFINITIONSHAPE($,$,(#{}));\n\
             #{}=IFCBUILDINGELEMENTPROXY('{:0>22}',$,'copy {k}',$,$,#{},#{},$,$);\n",
            2.0 * k as f64,
            b + 1,
            b + 2,
            b + 1,
            b + 3,
            b + 4,
            b + 3,
            b + 5,
            b + 4,
            b + 6,
            b + 5,
            b + 7,
            format!("P{k}"),
            b + 2,
            b + 6
        );
    }
    // The box product itself is dropped: only the mapped copies have geometry.
    ifc_box("IFC4", &extra).replace(
        "#15=IFCBUILDINGELEMENTPROXY('1YvctVUKr0kugbFTf53O9L',$,'box',$,$,#10,#14,$,$);\n",
        "",
    )
}

/// The valid box followed by a second product, cut in the middle of an entity (no `ENDSEC;`, no
/// `END-ISO-10303-21;`): what was read (the box) opens, with a warning that the file ends early.
pub fn ifc_truncated_mid_entity() -> String {
    let whole = ifc_box(
        "IFC4",
        "#16=IFCCARTESIANPOINT((5.,0.,0.));\n#17=IFCAXIS2PLACEMENT3D(#16,$,$);\n#18=IFCLOCALPLACEMENT($,#17);\n\
         #19=IFCBUILDINGELEMENTPROXY('2YvctVUKr0kugbFTf53O9L',$,'second box',$,$,#18,#14,$,$);\n",
    );
    let cut = whole.find("#19=").expect("the second product") + 30;
    whole[..cut].to_string()
}
