//! Hostile 3MF and compressed-glTF files of the corpus: archives that are not zips, hold no model, declare
//! gigabytes, nest components in a cycle or name missing vertices and objects; Draco and meshopt data that is
//! garbage or claims a billion elements; a required extension nobody implements. Each ends in a clear error
//! naming the file; the valid twins render.
use std::io::{self, Cursor, Write};
use std::path::Path;

use super::{b64, floats, write_files, Expect, HostileCase, CORNER};

const CONTENT_TYPES: &[u8] = br#"<?xml version="1.0" encoding="UTF-8"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>"#;
const RELS: &[u8] = br#"<?xml version="1.0" encoding="UTF-8"?><Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>"#;

/// A zip of `parts` (stored, uncompressed).
fn zip(parts: &[(&str, &[u8])]) -> io::Result<Vec<u8>> {
    let mut z = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, bytes) in parts {
        z.start_file(*name, opts).map_err(io::Error::other)?;
        z.write_all(bytes)?;
    }
    Ok(z.finish().map_err(io::Error::other)?.into_inner())
}

/// A 3MF model part: the corner's two triangles as object 1 (with `extra` inside its element, e.g.
/// components), and `build` as the build.
fn model_xml(triangles: &str, objects: &str, build: &str) -> String {
    let vertices: String = CORNER
        .chunks(3)
        .map(|v| format!(r#"<vertex x="{}" y="{}" z="{}"/>"#, v[0], v[1], v[2]))
        .collect();
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?><model unit="millimeter" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources><object id="1" type="model"><mesh><vertices>{vertices}</vertices><triangles>{triangles}</triangles></mesh></object>{objects}</resources><build>{build}</build></model>"#
    )
}

fn threemf(model: &str) -> io::Result<Vec<u8>> {
    zip(&[
        ("[Content_Types].xml", CONTENT_TYPES),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", model.as_bytes()),
    ])
}

const CORNER_TRIANGLES: &str = r#"<triangle v1="0" v2="1" v3="2"/><triangle v1="3" v2="4" v3="5"/>"#;

/// A glTF whose one primitive's POSITION comes from `view` (bufferView 0, over `data` inline) through
/// `prim_ext` (a primitive extension) or `view_ext` (a buffer view extension), with `used`/`required`
/// extensions.
fn compressed_gltf(data: &[u8], prim_ext: &str, view_ext: &str, count: u64, required: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":[{required}],"extensionsRequired":[{required}],
"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}{prim_ext}}}]}}],
"accessors":[{{"componentType":5126,"count":{count},"type":"VEC3"{accessor_view}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{len}{view_ext}}}],
"buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{b}"}}]}}"#,
        // A Draco primitive's accessor has no buffer view of its own; a meshopt view is the accessor's.
        accessor_view = if prim_ext.is_empty() {
            r#","bufferView":0"#
        } else {
            ""
        },
        len = data.len(),
        b = b64(data)
    )
}

/// A valid 3MF (the corner, one build item) whose model part holds `blanks` bytes of whitespace between its
/// resources and its build, deflated: a few kB on disk per MB inflated (1.5 GB of blanks is about 1.5 MB).
pub fn threemf_whitespace(blanks: u64) -> io::Result<Vec<u8>> {
    let model = model_xml(CORNER_TRIANGLES, "", r#"<item objectid="1"/>"#);
    let at = model.find("<build>").expect("a build element");
    let mut z = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let stored = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, bytes) in [("[Content_Types].xml", CONTENT_TYPES), ("_rels/.rels", RELS)] {
        z.start_file(name, stored).map_err(io::Error::other)?;
        z.write_all(bytes)?;
    }
    let deflated = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .large_file(blanks > u32::MAX as u64 / 2);
    z.start_file("3D/3dmodel.model", deflated)
        .map_err(io::Error::other)?;
    z.write_all(&model.as_bytes()[..at])?;
    let chunk = vec![b' '; 1 << 20];
    let mut left = blanks;
    while left > 0 {
        let n = left.min(chunk.len() as u64) as usize;
        z.write_all(&chunk[..n])?;
        left -= n as u64;
    }
    z.write_all(&model.as_bytes()[at..])?;
    Ok(z.finish().map_err(io::Error::other)?.into_inner())
}

pub(super) fn write(dir: &Path) -> io::Result<Vec<HostileCase>> {
    let garbage: Vec<u8> = (0..512u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 11) as u8)
        .collect();
    let item = r#"<item objectid="1"/>"#;
    let draco_ext =
        r#","extensions":{"KHR_draco_mesh_compression":{"bufferView":0,"attributes":{"POSITION":0}}}"#;
    let meshopt = |count: u64| {
        format!(
            r#","extensions":{{"EXT_meshopt_compression":{{"buffer":0,"byteOffset":0,"byteLength":{},"byteStride":12,"count":{count},"mode":"ATTRIBUTES"}}}}"#,
            garbage.len()
        )
    };
    let files: Vec<(&'static str, &'static str, Vec<u8>, Expect)> = vec![
        (
            "3mf_valid",
            "3mf",
            threemf(&model_xml(CORNER_TRIANGLES, "", item))?,
            Expect::Image,
        ),
        ("3mf_not_a_zip", "3mf", garbage.clone(), Expect::Error),
        (
            "3mf_no_model_part",
            "3mf",
            zip(&[("[Content_Types].xml", CONTENT_TYPES), ("_rels/.rels", RELS)])?,
            Expect::Error,
        ),
        (
            "3mf_truncated",
            "3mf",
            {
                let whole = threemf(&model_xml(CORNER_TRIANGLES, "", item))?;
                whole[..whole.len() * 2 / 3].to_vec()
            },
            Expect::Error,
        ),
        (
            "3mf_xml_garbage",
            "3mf",
            threemf("<model><resources><object id=\"1\"><mesh></model")?,
            Expect::Error,
        ),
        (
            "3mf_vertex_out_of_range",
            "3mf",
            threemf(&model_xml(r#"<triangle v1="0" v2="1" v3="99"/>"#, "", item))?,
            Expect::Error,
        ),
        (
            "3mf_item_names_missing_object",
            "3mf",
            threemf(&model_xml(CORNER_TRIANGLES, "", r#"<item objectid="7"/>"#))?,
            Expect::Error,
        ),
        (
            "3mf_component_cycle",
            "3mf",
            threemf(&model_xml(
                CORNER_TRIANGLES,
                r#"<object id="2" type="model"><components><component objectid="3"/></components></object><object id="3" type="model"><components><component objectid="2"/><component objectid="1"/></components></object>"#,
                r#"<item objectid="2"/>"#,
            ))?,
            Expect::Error,
        ),
        (
            "gltf_draco_garbage",
            "gltf",
            compressed_gltf(&garbage, draco_ext, "", 3, r#""KHR_draco_mesh_compression""#).into_bytes(),
            Expect::Error,
        ),
        (
            "gltf_meshopt_garbage",
            "gltf",
            compressed_gltf(&garbage, "", &meshopt(42), 42, r#""EXT_meshopt_compression""#).into_bytes(),
            Expect::Error,
        ),
        (
            "gltf_meshopt_count_huge",
            "gltf",
            compressed_gltf(
                &garbage,
                "",
                &meshopt(1_000_000_000),
                1_000_000_000,
                r#""EXT_meshopt_compression""#,
            )
            .into_bytes(),
            Expect::Error,
        ),
        (
            "gltf_unknown_required_extension",
            "gltf",
            compressed_gltf(&floats(&CORNER), "", "", 6, r#""KHR_no_such_thing""#).into_bytes(),
            Expect::Error,
        ),
    ];
    write_files(dir, files)
}
