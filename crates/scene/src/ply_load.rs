//! PLY loader (ASCII and binary, via ply-rs-bw): `vertex` x/y/z and `face` vertex_indices (or
//! vertex_index) become one mesh with one identity instance, coordinates as in the file; polygons are
//! fanned into triangles. The file goes through the guard; the element counts the header declares must
//! fit in the file's size, and the memory they imply is checked before the payload is read.
//!
//! Shading normals: the vertices' nx/ny/nz (float or double) when the `vertex` element declares all three; else
//! smooth normals by the load's crease angle ([`crate::normals::smooth`]).

use std::path::Path;

use ply_rs_bw::parser::Parser;
use ply_rs_bw::parser::Reader;
use ply_rs_bw::ply::{
    DefaultElement, ElementDef, Encoding, Property, PropertyAccess, PropertyAccessResult, PropertyType,
    ScalarType,
};

use crate::error::SceneError;
use crate::guard::{read_model, LoadOptions};
use crate::scene::{LoadProgress, Scene};

/// Memory per vertex (position, normal) and per face (index list, ~3 triangle indices) while decoding.
const VERTEX_BYTES: u64 = 12 + 12 + 16;
const FACE_BYTES: u64 = 24 + 16 + 12;

/// A vertex's position and normal (zero unless the file has nx/ny/nz).
#[derive(Default)]
struct Vertex([f32; 3], [f32; 3]);

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex::default()
    }
    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.0[0],
            "y" => &mut self.0[1],
            "z" => &mut self.0[2],
            "nx" => &mut self.1[0],
            "ny" => &mut self.1[1],
            "nz" => &mut self.1[2],
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = match p {
            Property::Float(v) => v,
            Property::Double(v) => v as f32,
            Property::Char(v) => v as f32,
            Property::UChar(v) => v as f32,
            Property::Short(v) => v as f32,
            Property::UShort(v) => v as f32,
            Property::Int(v) => v as f32,
            Property::UInt(v) => v as f32,
            _ => f32::NAN,
        };
        PropertyAccessResult::Set
    }
}

#[derive(Default)]
struct Face(Vec<i64>);

impl PropertyAccess for Face {
    fn new() -> Self {
        Face::default()
    }
    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        self.0 = match p {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => vec![-1],
        };
        PropertyAccessResult::Set
    }
}

fn scalar_bytes(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The fewest bytes one element can take in the payload (binary: scalar sizes and list counts; ASCII: one
/// digit and one separator per value).
fn min_element_bytes(e: &ElementDef, encoding: &Encoding) -> u64 {
    e.properties
        .values()
        .map(|p| match (encoding, &p.data_type) {
            (Encoding::Ascii, _) => 2,
            (_, PropertyType::Scalar(t)) => scalar_bytes(t),
            (_, PropertyType::List(count, _)) => scalar_bytes(count),
        })
        .sum::<u64>()
        .max(1)
}

pub fn load_ply(
    path: &Path,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    let err = |message: String| SceneError::Ply {
        path: path.to_path_buf(),
        message,
    };
    let (bytes, mut budget) = read_model(path, opts, progress)?;
    let mut reader = Reader::new(bytes.as_slice());
    let header = Parser::<DefaultElement>::new()
        .read_header(&mut reader)
        .map_err(|e| err(format!("bad header: {e}")))?;
    let payload = reader.get_ref().len() as u64;
    let mut need = 0u64;
    for (name, e) in &header.elements {
        let min = (e.count as u64).saturating_mul(min_element_bytes(e, &header.encoding));
        if min > payload {
            return Err(err(format!(
                "header declares {} `{name}` elements (at least {min} bytes) but only {payload} bytes follow",
                e.count
            )));
        }
        need = need.saturating_add((e.count as u64).saturating_mul(match name.as_str() {
            "vertex" => VERTEX_BYTES,
            "face" => FACE_BYTES,
            _ => 0,
        }));
    }
    budget.reserve(need, "the declared vertices and faces")?;
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for (name, e) in &header.elements {
        opts.check_cancel(path)?;
        let bad = |x: ply_rs_bw::parser::ParseError| err(format!("`{name}` elements: {x}"));
        match name.as_str() {
            "vertex" => {
                vertices = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, e, &header)
                    .map_err(bad)?
            }
            "face" => {
                faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, e, &header)
                    .map_err(bad)?
            }
            _ => {
                Parser::<DefaultElement>::new()
                    .read_payload_for_element(&mut reader, e, &header)
                    .map_err(bad)?;
            }
        }
        progress(LoadProgress {
            stage: "elements",
            done: e.count as u64,
            total: e.count as u64,
        });
    }
    let n = vertices.len() as i64;
    let mut indices = Vec::new();
    for (fi, f) in faces.iter().enumerate() {
        if let Some(&i) = f.0.iter().find(|&&i| !(0..n).contains(&i)) {
            return Err(err(format!("face {fi}: vertex index {i} outside 0..{n}")));
        }
        for k in 1..f.0.len().saturating_sub(1) {
            indices.extend([f.0[0] as u32, f.0[k] as u32, f.0[k + 1] as u32]);
        }
    }
    // Normals only when the file declares all three components (a lone `nx` is not a normal).
    let has_normals = header.elements.get("vertex").is_some_and(|e| {
        ["nx", "ny", "nz"].iter().all(|k| {
            matches!(
                e.properties.get(*k).map(|p| &p.data_type),
                Some(PropertyType::Scalar(_))
            )
        })
    });
    if !has_normals && opts.crease_deg.is_some() {
        budget.reserve(
            (indices.len() as u64 / 3).saturating_mul(crate::normals::SMOOTH_BYTES_PER_TRIANGLE),
            "smoothing the normals",
        )?;
    }
    let normals = if has_normals {
        vertices.iter().map(|v| v.1).collect()
    } else {
        Vec::new()
    };
    let mut scene = Scene::single_mesh(path, vertices.into_iter().map(|v| v.0).collect(), indices);
    let prim = &mut scene.meshes[0].primitives[0];
    prim.normals = normals;
    if !has_normals {
        crate::normals::smooth_primitive(prim, opts.crease_deg, path)?;
    }
    scene.metadata = header
        .comments
        .iter()
        .map(|c| ("comment", c))
        .chain(header.obj_infos.iter().map(|c| ("obj_info", c)))
        .map(|(k, v)| (k.to_string(), v.trim().to_string()))
        .filter(|(_, v)| !v.is_empty())
        .collect();
    Ok(scene)
}
