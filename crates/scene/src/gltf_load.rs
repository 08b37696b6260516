//! glTF 2.0 loader (.gltf with external or embedded buffers, .glb).
//!
//! Only geometry is read: images are never loaded or decoded. Accessors are decoded here
//! with bounds-checked arithmetic instead of `gltf::mesh::Reader`, which can panic on
//! malformed accessors (zero counts, short strides, wrong component types).

use std::collections::HashMap;
use std::path::Path;

use glam::{DMat4, DVec3, Mat4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::Semantic;

use crate::error::SceneError;
use crate::gltf_compressed;
use crate::guard::{read_model, resolve_reference, Budget, Fetch, LoadOptions, Target};
use crate::scene::{
    recentre_origin, relative_transform, transform_ok, Instance, LoadProgress, Mesh, Primitive, Scene,
    DEFAULT_BASE_COLOR,
};
use crate::tree::NodeTree;

/// Maximum node nesting depth.
const MAX_DEPTH: usize = 256;
/// Maximum node visits while flattening (guards against exponential DAGs).
const MAX_NODE_VISITS: u64 = 10_000_000;
/// Maximum element count of an accessor that has no buffer view (implicit zeros).
const MAX_IMPLICIT_COUNT: usize = 50_000_000;
/// Memory of one instance (matrix, ids, a short name), for the memory estimate.
const INSTANCE_BYTES: u64 = std::mem::size_of::<Instance>() as u64 + 32;
/// Memory of one model tree node (name, child and instance lists), for the memory estimate.
const TREE_NODE_BYTES: u64 = std::mem::size_of::<crate::tree::Node>() as u64 + 48;

/// Loads a .gltf or .glb file. Unreferenced meshes are kept so that mesh ids equal glTF
/// mesh indices. The file and its buffers are read through the guard ([`crate::guard`]); the memory
/// the declared counts imply is checked before anything large is allocated.
pub fn load_gltf(
    path: &Path,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    let err = |message: String| SceneError::Gltf {
        path: path.to_path_buf(),
        message,
    };
    let (bytes, mut budget) = read_model(path, opts, progress)?;
    let is_glb_ext = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    check_glb_header(&bytes, is_glb_ext).map_err(err)?;

    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| err(format!("cannot parse: {e}")))?;
    drop(bytes);
    validate_document(&document).map_err(err)?;
    let post_order = check_acyclic(&document).map_err(err)?;
    budget.reserve(
        geometry_bytes(&document),
        "the declared geometry (accessor counts)",
    )?;
    budget.reserve(
        instance_count(&document, &post_order).saturating_mul(INSTANCE_BYTES),
        "the node hierarchy's mesh instances",
    )?;
    let mesh_below = mesh_below(&document, &post_order);
    budget.reserve(
        tree_node_count(&document, &post_order, &mesh_below).saturating_mul(TREE_NODE_BYTES),
        "the model tree",
    )?;
    let data = load_buffers(&document, path, blob, opts, &mut budget, progress)?;
    // Compressed buffer views (meshopt) decode to their plain bytes up front; Draco primitives decode in
    // `load_primitive` (gltf_compressed.rs).
    budget.reserve(
        gltf_compressed::meshopt_bytes(&document),
        "the meshopt-compressed buffer views",
    )?;
    let views = gltf_compressed::decode_meshopt_views(&document, &data).map_err(err)?;
    let buffers = Buffers { data, views };
    progress(LoadProgress {
        stage: "buffers",
        done: 1,
        total: 1,
    });

    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut scene = Scene::new(name);
    scene.metadata = asset_metadata(&document);

    let total = document.meshes().len() as u64;
    for (mi, mesh) in document.meshes().enumerate() {
        opts.check_cancel(path)?;
        let mut primitives = Vec::new();
        for (pi, prim) in mesh.primitives().enumerate() {
            let at = format!("mesh {mi} primitive {pi}");
            if let Some(p) =
                load_primitive(&prim, &document, &buffers).map_err(|m| err(format!("{at}: {m}")))?
            {
                primitives.push(p);
            } else {
                log::warn!(
                    "{}: {at}: skipping non-triangle primitive (mode {:?})",
                    path.display(),
                    prim.mode()
                );
            }
        }
        scene.meshes.push(Mesh {
            name: mesh
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("mesh {mi}")),
            primitives,
        });
        progress(LoadProgress {
            stage: "meshes",
            done: mi as u64 + 1,
            total,
        });
    }

    let (placed, tree) = flatten_nodes(&document, &mesh_below).map_err(|e| match e {
        Flatten::Invalid(m) => err(m),
        Flatten::TooLarge(m) => SceneError::TooLarge(format!("{}: {m}", path.display())),
    })?;
    // World transforms are composed in f64; far from the file's origin the scene is re-centred.
    let centre = placed_centre(&scene.meshes, &placed);
    let origin = recentre_origin(centre);
    scene.origin = origin.to_array();
    scene.instances = placed
        .into_iter()
        .map(|p| Instance {
            mesh: p.mesh,
            transform: relative_transform(&p.world, origin),
            name: p.name,
            visible: true,
        })
        .collect();
    scene.tree = tree;
    progress(LoadProgress {
        stage: "nodes",
        done: scene.instances.len() as u64,
        total: scene.instances.len() as u64,
    });
    // glTF is Y up (glTF 2.0 specification, 3.4 "Coordinate System and Units").
    scene.up = Some(crate::UpAxis::Y);
    Ok(scene)
}

/// The document's `asset`: generator, copyright, version and minimum version, where present.
fn asset_metadata(doc: &gltf::Document) -> Vec<(String, String)> {
    let asset = &doc.as_json().asset;
    [
        ("generator", asset.generator.as_deref()),
        ("copyright", asset.copyright.as_deref()),
        ("glTF version", Some(asset.version.as_str())),
        ("minimum glTF version", asset.min_version.as_deref()),
    ]
    .into_iter()
    .filter_map(|(k, v)| Some((k.to_string(), v?.trim().to_string())).filter(|(_, v)| !v.is_empty()))
    .collect()
}

/// Runs the gltf crate's validation (index references must be in range: the document
/// accessors panic otherwise), tolerating two common, harmless spec violations: missing
/// POSITION `min`/`max` (we compute bounds ourselves) and required extensions that do not
/// change geometry (`IGNORABLE_REQUIRED`; the compressions and quantization are decoded).
fn validate_document(doc: &gltf::Document) -> Result<(), String> {
    use gltf::json::validation::{Error as VError, Validate};
    let root = doc.as_json();
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, e| {
        let p = path().as_str().to_owned();
        // An accessor without a bufferView is zeros (glTF 2.0 §3.6.2.1), which sparse data or an extension
        // (Draco) may replace: the gltf crate requires one unless sparse.
        let harmless = (e == VError::Missing
            && (p.ends_with(".min")
                || p.ends_with(".max")
                || (p.starts_with("accessors[") && p.ends_with(".bufferView"))))
            || (e == VError::Unsupported && p.starts_with("extensionsRequired") && ignorable(&p));
        if harmless {
            log::warn!("ignoring glTF validation issue {p}: {e}");
        } else if e == VError::Unsupported && p.starts_with("extensionsRequired") {
            let name = required_name(&p).unwrap_or(&p);
            errors.push(format!(
                "the file requires the extension {name}, which hrtao does not implement"
            ));
        } else {
            errors.push(format!("{p}: {e}"));
        }
    });
    if errors.is_empty() {
        Ok(())
    } else {
        let n = errors.len();
        errors.truncate(10);
        Err(format!("invalid glTF ({n} problems): {}", errors.join("; ")))
    }
}

/// Required extensions that change only what hrtao does not draw (materials beyond the base colour, textures,
/// lights): a file that requires them still has the geometry and its AO. Any other required extension that
/// the gltf crate does not know (and the loader does not decode) may change the geometry: the file is refused,
/// as glTF 2.0 §3.12 asks of a loader that does not implement a required extension.
const IGNORABLE_REQUIRED: [&str; 5] = [
    "KHR_materials_",
    "KHR_texture_",
    "EXT_texture_",
    "KHR_lights_",
    "EXT_lights_",
];

/// Required extensions the loader decodes itself (`gltf_compressed`), unknown to the gltf crate.
const DECODED_REQUIRED: [&str; 4] = [
    gltf_compressed::DRACO,
    gltf_compressed::MESHOPT[0],
    gltf_compressed::MESHOPT[1],
    "KHR_mesh_quantization",
];

/// Whether the required extension the validation path `p` names is decoded or one of `IGNORABLE_REQUIRED`.
fn ignorable(p: &str) -> bool {
    required_name(p).is_some_and(|name| {
        DECODED_REQUIRED.contains(&name) || IGNORABLE_REQUIRED.iter().any(|prefix| name.starts_with(prefix))
    })
}

/// The extension a validation path names: `extensionsRequired[0] = "NAME"`.
fn required_name(p: &str) -> Option<&str> {
    p.split_once("= \"")?.1.strip_suffix('"')
}

/// Rejects truncated/garbled GLB headers before the gltf crate sees them (its reader
/// underflows on tiny declared lengths).
fn check_glb_header(bytes: &[u8], is_glb_ext: bool) -> Result<(), String> {
    let is_glb = bytes.starts_with(b"glTF");
    if !is_glb {
        if is_glb_ext {
            let n = bytes.len().min(4);
            return Err(format!(
                "not a binary glTF: expected magic \"glTF\", found {:?}",
                String::from_utf8_lossy(&bytes[..n])
            ));
        }
        return Ok(());
    }
    if bytes.len() < 20 {
        return Err(format!("truncated GLB: only {} bytes", bytes.len()));
    }
    let u32_at = |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let version = u32_at(4);
    if version != 2 {
        return Err(format!("unsupported GLB version {version} (need 2)"));
    }
    let declared = u32_at(8) as usize;
    if declared < 20 {
        return Err(format!("GLB header declares impossible length {declared}"));
    }
    if declared > bytes.len() {
        return Err(format!(
            "truncated GLB: header declares {declared} bytes but the file has {}",
            bytes.len()
        ));
    }
    let json_len = u32_at(12) as usize;
    if json_len > declared - 20 {
        return Err(format!(
            "truncated GLB: JSON chunk declares {json_len} bytes but only {} remain",
            declared - 20
        ));
    }
    Ok(())
}

/// Decodes one primitive into a triangle list; `Ok(None)` for points/lines.
fn load_primitive(
    prim: &gltf::Primitive,
    doc: &gltf::Document,
    buffers: &Buffers,
) -> Result<Option<Primitive>, String> {
    let mode = prim.mode();
    if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
        return Ok(None);
    }
    if gltf_compressed::is_draco(prim) {
        let bytes = |v: &gltf::buffer::View| view_bytes(v, buffers).map(<[u8]>::to_vec);
        match gltf_compressed::decode_draco(prim, doc, &bytes) {
            Ok(Some(g)) => {
                let indices = to_triangle_list(mode, g.indices);
                return Ok(Some(
                    Primitive::new(g.positions, indices, base_color(prim, g.mean_color))
                        .with_double_sided(prim.material().double_sided())
                        .with_normals(g.normals.unwrap_or_default()),
                ));
            }
            Ok(None) => {}
            // Used but not required: the uncompressed accessors stand in (glTF 2.0 §3.12).
            Err(m) if !doc.extensions_required().any(|e| e == gltf_compressed::DRACO) => {
                log::warn!("{m}; reading the primitive's uncompressed data instead");
            }
            Err(m) => return Err(m),
        }
    }
    let pos_acc = prim.get(&Semantic::Positions).ok_or("no POSITION attribute")?;
    if pos_acc.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "POSITION accessor {} has type {:?}, expected VEC3",
            pos_acc.index(),
            pos_acc.dimensions()
        ));
    }
    let positions = read_accessor(&pos_acc, buffers, "POSITION", |dt, norm, b| {
        let s = dt.size();
        [
            comp_f32(dt, norm, &b[..s]),
            comp_f32(dt, norm, &b[s..2 * s]),
            comp_f32(dt, norm, &b[2 * s..3 * s]),
        ]
    })?;

    let raw_indices: Vec<u32> = match prim.indices() {
        Some(acc) => {
            if acc.dimensions() != Dimensions::Scalar
                || !matches!(acc.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
            {
                return Err(format!(
                    "index accessor {} must be SCALAR u8/u16/u32, found {:?} {:?}",
                    acc.index(),
                    acc.dimensions(),
                    acc.data_type()
                ));
            }
            read_accessor(&acc, buffers, "indices", |dt, _, b| comp_u32(dt, b))?
        }
        None => {
            let n = u32::try_from(positions.len())
                .map_err(|_| format!("{} vertices exceed u32 indices", positions.len()))?;
            (0..n).collect()
        }
    };
    let indices = to_triangle_list(mode, raw_indices);
    let normals = match prim.get(&Semantic::Normals) {
        Some(acc) => read_normals(&acc, buffers)?,
        None => Vec::new(),
    };

    let mean = match prim.get(&Semantic::Colors(0)) {
        Some(acc) => mean_color(&acc, buffers)?,
        None => None,
    };
    Ok(Some(
        Primitive::new(positions, indices, base_color(prim, mean))
            .with_double_sided(prim.material().double_sided())
            .with_normals(normals),
    ))
}

/// The material's base colour factor times the mean vertex colour, either alone, or the default.
fn base_color(prim: &gltf::Primitive, mean: Option<[f32; 4]>) -> [f32; 4] {
    let factor = prim
        .material()
        .index()
        .map(|_| prim.material().pbr_metallic_roughness().base_color_factor());
    match (factor, mean) {
        (Some(f), Some(c)) => [f[0] * c[0], f[1] * c[1], f[2] * c[2], f[3] * c[3]],
        (Some(f), None) => f,
        (None, Some(c)) => c,
        (None, None) => DEFAULT_BASE_COLOR,
    }
}

/// The NORMAL attribute, one per vertex (strips and fans become lists by their indices only, so the normals
/// stay as they are): float, or normalized signed byte/short (KHR_mesh_quantization), sparse accessors
/// included. A type other than VEC3 or a non-normalized integer is a warning and face normals; counts and
/// values are checked for every load by [`Primitive::check_normals`].
fn read_normals(acc: &gltf::Accessor, buffers: &Buffers) -> Result<Vec<[f32; 3]>, String> {
    let quantized = matches!(acc.data_type(), DataType::I8 | DataType::I16) && acc.normalized();
    if acc.dimensions() != Dimensions::Vec3 || !(acc.data_type() == DataType::F32 || quantized) {
        log::warn!(
            "NORMAL accessor {} is {:?} {:?}{}, expected VEC3 float or normalized byte/short; shading flat",
            acc.index(),
            acc.dimensions(),
            acc.data_type(),
            if acc.normalized() { " normalized" } else { "" }
        );
        return Ok(Vec::new());
    }
    read_accessor(acc, buffers, "NORMAL", |dt, norm, b| {
        let s = dt.size();
        [
            comp_f32(dt, norm, &b[..s]),
            comp_f32(dt, norm, &b[s..2 * s]),
            comp_f32(dt, norm, &b[2 * s..3 * s]),
        ]
    })
}

/// Converts strips/fans to a list; drops a trailing partial triangle of a list.
fn to_triangle_list(mode: Mode, idx: Vec<u32>) -> Vec<u32> {
    let n = idx.len();
    match mode {
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .flat_map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i + 1], idx[i], idx[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..n.saturating_sub(1))
            .flat_map(|i| [idx[0], idx[i], idx[i + 1]])
            .collect(),
        _ => {
            let mut idx = idx;
            let extra = n % 3;
            if extra != 0 {
                log::warn!("triangle list with {n} indices; dropping the last {extra}");
                idx.truncate(n - extra);
            }
            idx
        }
    }
}

/// Mean RGBA of a COLOR_n accessor (float, or normalized u8/u16; RGB gets alpha 1).
fn mean_color(acc: &gltf::Accessor, buffers: &Buffers) -> Result<Option<[f32; 4]>, String> {
    let dims = match acc.dimensions() {
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 => 4,
        d => {
            return Err(format!(
                "COLOR_0 accessor {} has type {d:?}, expected VEC3/VEC4",
                acc.index()
            ))
        }
    };
    if !matches!(acc.data_type(), DataType::F32 | DataType::U8 | DataType::U16) {
        return Err(format!(
            "COLOR_0 accessor {} has component type {:?}, expected float/u8/u16",
            acc.index(),
            acc.data_type()
        ));
    }
    let colors = read_accessor(acc, buffers, "COLOR_0", |dt, _, b| {
        let s = dt.size();
        let mut c = [1.0f32; 4];
        for (k, v) in c.iter_mut().enumerate().take(dims) {
            // Integer colours are always normalized in glTF.
            *v = comp_f32(dt, true, &b[k * s..(k + 1) * s]);
        }
        c
    })?;
    if colors.is_empty() {
        return Ok(None);
    }
    let mut sum = [0.0f64; 4];
    for c in &colors {
        for k in 0..4 {
            sum[k] += c[k] as f64;
        }
    }
    let n = colors.len() as f64;
    Ok(Some(sum.map(|s| (s / n) as f32)))
}

fn comp_f32(dt: DataType, normalized: bool, b: &[u8]) -> f32 {
    match dt {
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        DataType::U8 => {
            let v = b[0] as f32;
            if normalized {
                v / 255.0
            } else {
                v
            }
        }
        DataType::I8 => {
            let v = b[0] as i8 as f32;
            if normalized {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                v / 65535.0
            } else {
                v
            }
        }
        DataType::I16 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
    }
}

fn comp_u32(dt: DataType, b: &[u8]) -> u32 {
    match dt {
        DataType::U8 => b[0] as u32,
        DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// The file's buffers as loaded, and the buffer views that meshopt compression decoded (by view index).
struct Buffers {
    data: Vec<gltf::buffer::Data>,
    views: HashMap<usize, Vec<u8>>,
}

/// A buffer view's bytes: decoded, or the range `offset..offset+len` of its buffer, checked against the loaded
/// data.
fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b Buffers) -> Result<&'b [u8], String> {
    if let Some(decoded) = buffers.views.get(&view.index()) {
        return Ok(decoded);
    }
    let data = buffers
        .data
        .get(view.buffer().index())
        .ok_or_else(|| format!("bufferView {} references missing buffer", view.index()))?;
    let end = view
        .offset()
        .checked_add(view.length())
        .filter(|&e| e <= data.len())
        .ok_or_else(|| {
            format!(
                "bufferView {} (offset {}, length {}) exceeds buffer {} of {} bytes",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                data.len()
            )
        })?;
    Ok(&data[view.offset()..end])
}

/// Slice of `count` elements of `elem` bytes each, `stride` apart, starting at `offset`.
fn elements<'b>(
    bytes: &'b [u8],
    offset: usize,
    stride: usize,
    elem: usize,
    count: usize,
    what: &str,
) -> Result<&'b [u8], String> {
    if count == 0 {
        return Ok(&[]);
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(elem))
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            format!(
                "{what}: {count} elements of {elem} bytes (stride {stride}, offset {offset}) \
                 exceed the {} bytes available",
                bytes.len()
            )
        })?;
    Ok(&bytes[offset..end])
}

/// Decodes all elements of an accessor (including sparse substitution) with `decode`,
/// which gets the component type, normalized flag and the element's bytes.
fn read_accessor<T: Copy>(
    acc: &gltf::Accessor,
    buffers: &Buffers,
    what: &str,
    decode: impl Fn(DataType, bool, &[u8]) -> T,
) -> Result<Vec<T>, String> {
    let what = format!("{what} accessor {}", acc.index());
    let dt = acc.data_type();
    let norm = acc.normalized();
    let elem = dt.size() * acc.dimensions().multiplicity();
    let count = acc.count();
    let mut out: Vec<T> = match acc.view() {
        Some(view) => {
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(format!("{what}: byteStride {stride} < element size {elem}"));
            }
            let bytes = elements(
                view_bytes(&view, buffers)?,
                acc.offset(),
                stride,
                elem,
                count,
                &what,
            )?;
            (0..count)
                .map(|k| decode(dt, norm, &bytes[k * stride..k * stride + elem]))
                .collect()
        }
        None => {
            if acc.sparse().is_none() {
                log::warn!("{what} has no bufferView and no sparse data; using zeros");
            }
            if count > MAX_IMPLICIT_COUNT {
                return Err(format!("{what}: implicit count {count} is too large"));
            }
            let zeros = vec![0u8; elem];
            vec![decode(dt, norm, &zeros); count]
        }
    };
    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        let idx = sparse.indices();
        let isize_ = idx.index_type().size();
        let ibytes = elements(
            view_bytes(&idx.view(), buffers)?,
            idx.offset(),
            isize_,
            isize_,
            n,
            &format!("{what} sparse indices"),
        )?;
        let vals = sparse.values();
        let vbytes = elements(
            view_bytes(&vals.view(), buffers)?,
            vals.offset(),
            elem,
            elem,
            n,
            &format!("{what} sparse values"),
        )?;
        for k in 0..n {
            let b = &ibytes[k * isize_..(k + 1) * isize_];
            let i = match isize_ {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            let slot = out
                .get_mut(i)
                .ok_or_else(|| format!("{what}: sparse index {i} >= count {count}"))?;
            *slot = decode(dt, norm, &vbytes[k * elem..(k + 1) * elem]);
        }
    }
    Ok(out)
}

enum Flatten {
    Invalid(String),
    TooLarge(String),
}

/// Errors if the node graph (all nodes, not only the displayed scene) has a cycle; else returns the
/// nodes in post-order (children before parents). Iterative three-colour DFS, so arbitrarily deep
/// graphs cannot overflow the stack.
fn check_acyclic(doc: &gltf::Document) -> Result<Vec<usize>, String> {
    let children: Vec<Vec<usize>> = doc
        .nodes()
        .map(|n| n.children().map(|c| c.index()).collect())
        .collect();
    // 0 = unvisited, 1 = on the DFS path, 2 = done
    let mut state = vec![0u8; children.len()];
    let mut order = Vec::with_capacity(children.len());
    for start in 0..children.len() {
        if state[start] != 0 {
            continue;
        }
        let mut stack = vec![(start, 0usize)];
        state[start] = 1;
        while let Some((node, next)) = stack.last_mut() {
            if let Some(&c) = children[*node].get(*next) {
                *next += 1;
                match state[c] {
                    0 => {
                        state[c] = 1;
                        stack.push((c, 0));
                    }
                    1 => {
                        return Err(format!(
                            "cyclic node graph: node {c} is its own ancestor (via node {node})"
                        ))
                    }
                    _ => {}
                }
            } else {
                state[*node] = 2;
                order.push(*node);
                stack.pop();
            }
        }
    }
    Ok(order)
}

/// A mesh instance with its world transform in f64 (file coordinates).
struct Placed {
    mesh: u32,
    world: DMat4,
    name: String,
}

/// The centre of the instances' world bounds (file coordinates, f64).
fn placed_centre(meshes: &[Mesh], placed: &[Placed]) -> DVec3 {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in placed {
        let Some(mesh) = meshes.get(p.mesh as usize) else {
            continue;
        };
        let b = mesh.local_bounds();
        if !(b.min.is_finite() && b.max.is_finite()) {
            continue;
        }
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x } as f64,
                if i & 2 == 0 { b.min.y } else { b.max.y } as f64,
                if i & 4 == 0 { b.min.z } else { b.max.z } as f64,
            );
            let w = p.world.transform_point3(c);
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    if lo.x > hi.x {
        DVec3::ZERO
    } else {
        (lo + hi) * 0.5
    }
}

/// Flattens the default scene (else scene 0, else all root nodes) into instances, and keeps the hierarchy as
/// a model tree (one tree node per visit, so a node reached twice appears twice; nodes placing no mesh
/// anywhere below are dropped). The node graph must be acyclic ([`check_acyclic`], run before by `load_gltf`).
fn flatten_nodes(doc: &gltf::Document, mesh_below: &[bool]) -> Result<(Vec<Placed>, NodeTree), Flatten> {
    let roots = root_nodes(doc);
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut w = Walker {
        nodes: &nodes,
        on_path: vec![false; nodes.len()],
        seen: vec![false; nodes.len()],
        visits: 0,
        out: Vec::new(),
        tree: NodeTree::default(),
        mesh_below,
    };
    for r in roots {
        w.visit(r, DMat4::IDENTITY, None, 0)?;
    }
    w.tree.prune_empty();
    Ok((w.out, w.tree))
}

/// Root nodes of the default scene (else scene 0, else all nodes that are nobody's child).
fn root_nodes(doc: &gltf::Document) -> Vec<usize> {
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            (0..is_child.len()).filter(|&i| !is_child[i]).collect()
        }
    }
}

/// Number of mesh instances flattening will produce (paths from the roots to nodes with a mesh),
/// computed over the acyclic graph's post-order without walking it; saturates instead of overflowing.
fn instance_count(doc: &gltf::Document, post_order: &[usize]) -> u64 {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut below = vec![0u64; nodes.len()];
    for &n in post_order {
        let own = u64::from(nodes[n].mesh().is_some());
        below[n] = nodes[n]
            .children()
            .fold(own, |acc, c| acc.saturating_add(below[c.index()]));
    }
    root_nodes(doc)
        .into_iter()
        .fold(0u64, |acc, r| acc.saturating_add(below[r]))
}

/// Whether each node has a mesh at or below it, over the acyclic graph's post-order.
fn mesh_below(doc: &gltf::Document, post_order: &[usize]) -> Vec<bool> {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut below = vec![false; nodes.len()];
    for &n in post_order {
        below[n] = nodes[n].mesh().is_some() || nodes[n].children().any(|c| below[c.index()]);
    }
    below
}

/// Number of model tree nodes flattening will create: the paths from the roots to every node with a mesh at or
/// below it (parents before children in reverse post-order); saturates instead of overflowing.
fn tree_node_count(doc: &gltf::Document, post_order: &[usize], mesh_below: &[bool]) -> u64 {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut paths = vec![0u64; nodes.len()];
    for r in root_nodes(doc) {
        paths[r] = paths[r].saturating_add(1);
    }
    for &n in post_order.iter().rev() {
        for c in nodes[n].children() {
            paths[c.index()] = paths[c.index()].saturating_add(paths[n]);
        }
    }
    (0..nodes.len())
        .filter(|&n| mesh_below[n])
        .fold(0u64, |acc, n| acc.saturating_add(paths[n]))
}

/// Bytes the decoded triangle primitives will take, from the accessor counts the file declares
/// (positions, normals, raw and converted indices, colours), before any of it is read.
fn geometry_bytes(doc: &gltf::Document) -> u64 {
    let mut total = 0u64;
    for prim in doc.meshes().flat_map(|m| m.primitives()) {
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            continue;
        }
        let count = |s: &Semantic| prim.get(s).map_or(0, |a| a.count() as u64);
        let vertices = count(&Semantic::Positions);
        let indices = prim.indices().map_or(vertices, |a| a.count() as u64);
        let converted = if mode == Mode::Triangles {
            0
        } else {
            indices.saturating_sub(2).saturating_mul(3)
        };
        let colors = count(&Semantic::Colors(0));
        let normals = count(&Semantic::Normals);
        total = total
            .saturating_add(vertices.saturating_mul(12))
            .saturating_add(normals.saturating_mul(12))
            .saturating_add(indices.saturating_add(converted).saturating_mul(4))
            .saturating_add(colors.saturating_mul(16));
    }
    total
}

/// Reads every buffer: the GLB BIN chunk, `data:` URIs (base64) and external files through the guard
/// (inside the model's folder, regular file, at least `byteLength` bytes, reading only those).
fn load_buffers(
    doc: &gltf::Document,
    path: &Path,
    mut blob: Option<Vec<u8>>,
    opts: &LoadOptions,
    budget: &mut Budget,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Vec<gltf::buffer::Data>, SceneError> {
    let err = |message: String| SceneError::Gltf {
        path: path.to_path_buf(),
        message,
    };
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        opts.check_cancel(path)?;
        let i = buffer.index();
        if gltf_compressed::is_fallback(&buffer) {
            // Stands in for meshopt-compressed views, which are decoded instead: nothing reads it.
            out.push(gltf::buffer::Data(Vec::new()));
            continue;
        }
        let declared = buffer.length() as u64;
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                err(format!(
                    "buffer {i} refers to the GLB BIN chunk, which is missing"
                ))
            })?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(rest) => {
                    let b64 = rest
                        .split_once(";base64,")
                        .map(|(_, b)| b)
                        .ok_or_else(|| err(format!("buffer {i}: data URI is not base64")))?;
                    budget.reserve(b64.len() as u64 / 4 * 3, &format!("buffer {i} (data URI)"))?;
                    base64::decode(b64).map_err(|e| err(format!("buffer {i}: bad base64 data URI: {e}")))?
                }
                None => {
                    let file = uri_path(path, uri)?;
                    Fetch {
                        model: path,
                        target: Target::Reference(uri),
                        declared: Some(declared),
                    }
                    .read(&file, opts, budget, progress)?
                }
            },
        };
        if (data.len() as u64) < declared {
            return Err(err(format!(
                "buffer {i} holds {} bytes but its byteLength declares {declared}",
                data.len()
            )));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        out.push(gltf::buffer::Data(data));
    }
    Ok(out)
}

/// The file a buffer URI names (`file://` absolute or a percent-encoded relative reference), inside the
/// model's folder; other schemes are refused.
fn uri_path(model: &Path, uri: &str) -> Result<std::path::PathBuf, SceneError> {
    let reference_err = |message: String| SceneError::Reference {
        model: model.to_path_buf(),
        uri: uri.to_string(),
        message,
    };
    let encoded = if let Some(rest) = uri.strip_prefix("file:") {
        let rest = rest.strip_prefix("//").unwrap_or(rest);
        let rest = rest.strip_prefix("localhost").unwrap_or(rest);
        if !rest.starts_with('/') {
            return Err(reference_err(
                "a file: URI must name an absolute path (file:///...)".into(),
            ));
        }
        rest
    } else if let Some((scheme, _)) = uri.split_once(':').filter(|(s, _)| !s.contains('/')) {
        return Err(reference_err(format!(
            "URI scheme `{scheme}:` is not supported (only files beside the model and data: URIs)"
        )));
    } else {
        uri
    };
    let decoded = percent_encoding::percent_decode_str(encoded)
        .decode_utf8()
        .map_err(|e| reference_err(format!("bad percent-encoding: {e}")))?;
    resolve_reference(model, Path::new(decoded.as_ref()), uri)
}

struct Walker<'a, 'd> {
    nodes: &'a [gltf::Node<'d>],
    on_path: Vec<bool>,
    seen: Vec<bool>,
    visits: u64,
    out: Vec<Placed>,
    tree: NodeTree,
    /// Nodes with a mesh at or below them: only those get a tree node.
    mesh_below: &'a [bool],
}

impl Walker<'_, '_> {
    fn visit(
        &mut self,
        idx: usize,
        parent: DMat4,
        parent_node: Option<u32>,
        depth: usize,
    ) -> Result<(), Flatten> {
        if depth > MAX_DEPTH {
            return Err(Flatten::Invalid(format!(
                "node {idx}: node hierarchy deeper than {MAX_DEPTH}"
            )));
        }
        if self.on_path[idx] {
            return Err(Flatten::Invalid(format!(
                "node {idx}: cyclic node graph (node is its own ancestor)"
            )));
        }
        if self.seen[idx] {
            log::warn!("node {idx} has more than one parent; instancing it again");
        }
        self.visits += 1;
        if self.visits > MAX_NODE_VISITS {
            return Err(Flatten::TooLarge(format!(
                "more than {MAX_NODE_VISITS} node visits while flattening the hierarchy"
            )));
        }
        self.seen[idx] = true;
        let node = &self.nodes[idx];
        let local = Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        if !world.is_finite() {
            return Err(Flatten::Invalid(format!(
                "node {idx}: non-finite world transform {:?}",
                world.to_cols_array()
            )));
        }
        let name = node
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("node {idx}"));
        let tree_node = self.mesh_below[idx].then(|| self.tree.add(name.clone(), parent_node));
        if let (Some(mesh), Some(tree_node)) = (node.mesh(), tree_node) {
            // The linear part decides singularity (the translation may be far from the origin).
            let linear = DMat4::from_mat3(glam::DMat3::from_mat4(world)).as_mat4();
            if transform_ok(&linear) {
                self.tree.nodes[tree_node as usize]
                    .instances
                    .push(self.out.len() as u32);
                self.out.push(Placed {
                    mesh: mesh.index() as u32,
                    world,
                    name,
                });
            } else {
                log::warn!("node {idx}: singular world transform; skipping its mesh instance");
            }
        }
        self.on_path[idx] = true;
        let children: Vec<usize> = node.children().map(|c| c.index()).collect();
        for c in children {
            self.visit(c, world, tree_node, depth + 1)?;
        }
        self.on_path[idx] = false;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strip_and_fan() {
        assert_eq!(
            to_triangle_list(Mode::TriangleStrip, vec![0, 1, 2, 3]),
            vec![0, 1, 2, 2, 1, 3]
        );
        assert_eq!(
            to_triangle_list(Mode::TriangleFan, vec![0, 1, 2, 3]),
            vec![0, 1, 2, 0, 2, 3]
        );
        assert_eq!(to_triangle_list(Mode::Triangles, vec![0, 1, 2, 3]), vec![0, 1, 2]);
        assert!(to_triangle_list(Mode::TriangleStrip, vec![0, 1]).is_empty());
    }

    #[test]
    fn glb_header_checks() {
        assert!(check_glb_header(b"{}", false).is_ok());
        assert!(check_glb_header(b"{}", true).unwrap_err().contains("magic"));
        let mut h = b"glTF".to_vec();
        h.extend(2u32.to_le_bytes());
        h.extend(1000u32.to_le_bytes());
        h.extend([0u8; 8]);
        assert!(check_glb_header(&h, true).unwrap_err().contains("truncated"));
        h[8..12].copy_from_slice(&3u32.to_le_bytes());
        assert!(check_glb_header(&h, true).unwrap_err().contains("impossible"));
    }
}
