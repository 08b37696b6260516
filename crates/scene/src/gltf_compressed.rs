//! Compressed glTF geometry: buffer views compressed by meshoptimizer (EXT_meshopt_compression and its KHR_
//! successor, what gltfpack writes) and Draco-compressed primitives (KHR_draco_mesh_compression, what
//! gltf-pipeline and Blender write). Both decode into the plain bytes or values the loader reads anyway, so the
//! accessor rules (strides, sparse data, KHR_mesh_quantization's normalized integers) stay in one place.
//!
//! Extension rules (glTF 2.0 §3.12): a compressed view or primitive is decoded whenever its extension is
//! present; when decoding a primitive fails and the extension is only *used* (not required), its uncompressed
//! accessors are read instead. Every size is checked before the decoders see it (meshoptimizer asserts on bad
//! strides), and the decoders themselves bounds-check their input.
use std::collections::HashMap;

use gltf::json::Value;

/// The glTF names of meshoptimizer's buffer-view compression (the vendor extension and its KHR_ successor).
pub const MESHOPT: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];
/// The glTF name of Draco primitive compression.
pub const DRACO: &str = "KHR_draco_mesh_compression";

/// The meshopt extension object of an extensible glTF value, by either name.
fn meshopt_ext<'a>(value: impl Fn(&str) -> Option<&'a Value>) -> Option<&'a Value> {
    MESHOPT.iter().find_map(|name| value(name))
}

/// Whether `buffer` only stands in for data that compressed views carry (`"fallback": true`): it may have
/// no bytes at all, and nothing reads it once the views are decoded.
pub fn is_fallback(buffer: &gltf::Buffer) -> bool {
    meshopt_ext(|n| buffer.extension_value(n))
        .and_then(|e| e.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false)
}

/// The bytes the meshopt-compressed views decode to (their byteLengths): the loader's budget takes them first.
pub fn meshopt_bytes(doc: &gltf::Document) -> u64 {
    doc.views()
        .filter(|v| meshopt_ext(|n| v.extension_value(n)).is_some())
        .map(|v| v.length() as u64)
        .sum()
}

/// Decodes every meshopt-compressed buffer view: view index → its uncompressed bytes (`count × byteStride`).
/// `buffers` are the file's buffers as loaded (fallback buffers may be empty).
pub fn decode_meshopt_views(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<HashMap<usize, Vec<u8>>, String> {
    let mut out = HashMap::new();
    for view in doc.views() {
        let Some(ext) = meshopt_ext(|n| view.extension_value(n)) else {
            continue;
        };
        let at = format!("bufferView {}", view.index());
        let field = |name: &str| {
            ext.get(name)
                .and_then(Value::as_u64)
                .ok_or_else(|| format!("{at}: meshopt compression without a valid `{name}`"))
        };
        let (buffer, offset, length) = (
            field("buffer")?,
            field("byteOffset").unwrap_or(0),
            field("byteLength")?,
        );
        let (stride, count) = (field("byteStride")?, field("count")?);
        let mode = ext.get("mode").and_then(Value::as_str).unwrap_or("");
        let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
        let data = buffers
            .get(buffer as usize)
            .ok_or_else(|| format!("{at}: meshopt data in missing buffer {buffer}"))?;
        let encoded = offset
            .checked_add(length)
            .filter(|&end| end <= data.len() as u64)
            .map(|end| &data[offset as usize..end as usize])
            .ok_or_else(|| {
                format!(
                    "{at}: meshopt data ({offset} + {length} bytes) exceeds buffer {buffer} of {} bytes",
                    data.len()
                )
            })?;
        let size = stride
            .checked_mul(count)
            .filter(|&s| s <= view.length() as u64)
            .ok_or_else(|| {
                format!(
                    "{at}: {count} × {stride} decoded bytes exceed the view's byteLength {}",
                    view.length()
                )
            })?;
        let mut bytes = vec![0u8; view.length()];
        decode(
            mode,
            filter,
            stride as usize,
            count as usize,
            encoded,
            &mut bytes[..size as usize],
        )
        .map_err(|m| format!("{at}: {m}"))?;
        out.insert(view.index(), bytes);
    }
    Ok(out)
}

/// meshoptimizer's decoders on `count` elements of `stride` bytes into `out` (exactly `count × stride` bytes),
/// then the view's filter, in place.
fn decode(
    mode: &str,
    filter: &str,
    stride: usize,
    count: usize,
    encoded: &[u8],
    out: &mut [u8],
) -> Result<(), String> {
    let dst = out.as_mut_ptr().cast();
    let status = match mode {
        // The decoder asserts (aborts) on these, so they are refused first.
        "ATTRIBUTES" if stride.is_multiple_of(4) && (4..=256).contains(&stride) => unsafe {
            meshopt::ffi::meshopt_decodeVertexBuffer(dst, count, stride, encoded.as_ptr(), encoded.len())
        },
        "TRIANGLES" if (stride == 2 || stride == 4) && count.is_multiple_of(3) => unsafe {
            meshopt::ffi::meshopt_decodeIndexBuffer(dst, count, stride, encoded.as_ptr(), encoded.len())
        },
        "INDICES" if stride == 2 || stride == 4 => unsafe {
            meshopt::ffi::meshopt_decodeIndexSequence(dst, count, stride, encoded.as_ptr(), encoded.len())
        },
        "ATTRIBUTES" | "TRIANGLES" | "INDICES" => {
            return Err(format!(
                "meshopt {mode} with byteStride {stride} and count {count} is not decodable"
            ))
        }
        other => return Err(format!("unknown meshopt mode `{other}`")),
    };
    if status != 0 {
        return Err(format!(
            "meshopt {mode} data is corrupt (decoder status {status})"
        ));
    }
    if mode != "ATTRIBUTES" && filter != "NONE" {
        return Err(format!("meshopt filter {filter} on {mode} data"));
    }
    let ok = match filter {
        "NONE" => true,
        "OCTAHEDRAL" | "COLOR" if stride == 4 || stride == 8 => true,
        "QUATERNION" => stride == 8,
        "EXPONENTIAL" => stride.is_multiple_of(4),
        _ => false,
    };
    if !ok {
        return Err(format!(
            "meshopt filter {filter} does not apply to byteStride {stride}"
        ));
    }
    unsafe {
        match filter {
            "OCTAHEDRAL" => meshopt::ffi::meshopt_decodeFilterOct(dst, count, stride),
            "COLOR" => meshopt::ffi::meshopt_decodeFilterColor(dst, count, stride),
            "QUATERNION" => meshopt::ffi::meshopt_decodeFilterQuat(dst, count, stride),
            "EXPONENTIAL" => meshopt::ffi::meshopt_decodeFilterExp(dst, count, stride),
            _ => {}
        }
    }
    Ok(())
}

/// A Draco-compressed primitive's geometry: positions, triangle indices and, when the primitive maps them,
/// normals (one per point) and the mean vertex colour. None when the primitive has no Draco extension.
pub struct DracoGeometry {
    pub positions: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub mean_color: Option<[f32; 4]>,
}

/// Whether `prim` is Draco-compressed.
pub fn is_draco(prim: &gltf::Primitive) -> bool {
    prim.extension_value(DRACO).is_some()
}

/// Decodes `prim`'s Draco data (the extension's bufferView, read with `view_bytes`), or None when it has none.
/// The decoder's own limits (`draco_core::DecodeLimits::default`) bound what a hostile stream may allocate; the
/// loader's budget has taken the accessors' declared counts, which the decoded counts must match.
pub fn decode_draco(
    prim: &gltf::Primitive,
    doc: &gltf::Document,
    view_bytes: &dyn Fn(&gltf::buffer::View) -> Result<Vec<u8>, String>,
) -> Result<Option<DracoGeometry>, String> {
    let Some(ext) = prim.extension_value(DRACO) else {
        return Ok(None);
    };
    let view = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .and_then(|v| doc.views().nth(v as usize))
        .ok_or("Draco compression without a valid bufferView")?;
    let id = |name: &str| {
        ext.get("attributes")
            .and_then(|a| a.get(name))
            .and_then(Value::as_u64)
    };
    let position_id = id("POSITION").ok_or("Draco compression without a POSITION attribute")?;
    let points = prim
        .get(&gltf::Semantic::Positions)
        .map_or(0, |a| a.count() as u64);

    let data = view_bytes(&view)?;
    let mut buffer = draco_core::DecoderBuffer::new(&data);
    let mut mesh = draco_core::Mesh::new();
    draco_core::MeshDecoder::new()
        .decode(&mut buffer, &mut mesh)
        .map_err(|e| format!("Draco data is corrupt: {e}"))?;
    let n = mesh.num_points();
    if points > 0 && n as u64 != points {
        return Err(format!(
            "Draco data has {n} points, the POSITION accessor declares {points}"
        ));
    }
    let attribute = |unique: u64, what: &str| -> Result<Vec<[f32; 3]>, String> {
        let a = (0..mesh.num_attributes().max(0))
            .map(|i| mesh.attribute(i))
            .find(|a| a.unique_id() as u64 == unique)
            .ok_or_else(|| format!("Draco data has no attribute {unique} ({what})"))?;
        if a.num_components() != 3 {
            return Err(format!(
                "Draco {what} has {} components, expected 3",
                a.num_components()
            ));
        }
        let flat = a.read_f32s(n, 3);
        Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    };
    let positions = attribute(position_id, "POSITION")?;
    let normals = match id("NORMAL") {
        Some(normal_id) => Some(attribute(normal_id, "NORMAL")?),
        None => None,
    };
    let mean_color = match id("COLOR_0") {
        Some(color_id) => mean_color(&mesh, color_id, n)?,
        None => None,
    };
    let faces = mesh.num_faces();
    let mut indices = Vec::with_capacity(faces * 3);
    for f in 0..faces {
        let face = mesh.face(draco_core::FaceIndex(f as u32));
        for p in face {
            let i = p.0;
            if i as usize >= n {
                return Err(format!("Draco face {f} names point {i} of {n}"));
            }
            indices.push(i);
        }
    }
    Ok(Some(DracoGeometry {
        positions,
        indices,
        normals,
        mean_color,
    }))
}

/// The mean of a Draco colour attribute (RGB or RGBA; integer colours are normalized, as in glTF).
fn mean_color(mesh: &draco_core::Mesh, unique: u64, n: usize) -> Result<Option<[f32; 4]>, String> {
    let Some(a) = (0..mesh.num_attributes().max(0))
        .map(|i| mesh.attribute(i))
        .find(|a| a.unique_id() as u64 == unique)
    else {
        return Err(format!("Draco data has no attribute {unique} (COLOR_0)"));
    };
    let dims = a.num_components() as usize;
    if !(dims == 3 || dims == 4) || n == 0 {
        return Ok(None);
    }
    let scale = match a.data_type() {
        draco_core::DataType::Uint8 => 1.0 / 255.0,
        draco_core::DataType::Uint16 => 1.0 / 65535.0,
        _ => 1.0,
    };
    let flat = a.read_f32s(n, dims);
    let mut sum = [0.0f64; 4];
    for c in flat.chunks_exact(dims) {
        for k in 0..4 {
            sum[k] += if k < dims { (c[k] * scale) as f64 } else { 1.0 };
        }
    }
    Ok(Some(sum.map(|s| (s / n as f64) as f32)))
}
