//! 3MF loader (the 3D-printing and CAD exchange format: a zip of XML model parts), through the `threemf` crate:
//! each object with a mesh becomes one mesh, each build item (and each component of a composed object, through
//! any depth) one instance of it with the composed transform, so a part placed many times is stored once.
//! The model's unit is kept, and each object's colour (`threemf_colors`: base materials and colour groups,
//! which the threemf crate does not parse).
//! Shading normals: 3MF stores none; meshes get smooth normals by the load's crease angle, as STL and PLY.
//!
//! The archive is read through the guard like every model file, and the decompressed size of its model parts
//! (as the zip's directory declares them) is taken from the memory budget, [`XML_MEMORY_FACTOR`] times, before
//! any part is inflated: a part too large for the budget is refused at once. The parts are then parsed as
//! streams ([`PartReader`]): no part is ever held whole, a part inflating past its declared size is an error,
//! whitespace runs between elements are squeezed (a part inflating to gigabytes of blanks costs time, not
//! memory) and no text or tag may be longer than [`MAX_TOKEN`], so what a part costs is what it describes.
use std::collections::HashMap;
use std::io::{BufReader, Cursor, Read};
use std::path::Path;

use glam::{DMat4, DVec4};
use serde::Deserialize;

use crate::error::SceneError;
use crate::guard::{read_model, LoadOptions};
use crate::scene::{recentre_origin, relative_transform, Instance, LoadProgress, Mesh, Primitive, Scene};
use crate::tree::NodeTree;

/// Memory per byte of model XML while it is parsed and kept: a vertex or a triangle takes at least 27 bytes of
/// XML (`<vertex x="0" y="0" z="0"/>`) and 24 bytes parsed (48 while its list grows), then 12 in the scene's mesh
/// and 12 of normals. The text itself is never held (the parts are streamed).
const XML_MEMORY_FACTOR: u64 = 3;
/// Whitespace kept of a run between elements (the rest is dropped as it streams by).
const MAX_WHITESPACE: u64 = 256;
/// The longest text or tag a model part may hold (a coordinate list or a name is far shorter; a longer one would
/// be held whole by the XML reader).
pub(crate) const MAX_TOKEN: u64 = 16 << 20;
/// Components nested deeper than this are refused (a cycle would never end).
const MAX_DEPTH: usize = 32;
/// Instances a file may place (components multiply: a small file could ask for billions).
const MAX_INSTANCES: usize = 1 << 22;

pub fn load_3mf(
    path: &Path,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    let err = |message: String| SceneError::Cad {
        format: "3MF",
        path: path.to_path_buf(),
        message,
    };
    let (bytes, mut budget) = read_model(path, opts, progress)?;
    let mut zip =
        zip::ZipArchive::new(Cursor::new(&bytes)).map_err(|e| err(format!("not a 3MF archive: {e}")))?;
    // The model parts: their index in the archive, name and declared (inflated) size.
    let mut parts = Vec::new();
    for i in 0..zip.len() {
        let entry = zip
            .by_index_raw(i)
            .map_err(|e| err(format!("archive entry {i}: {e}")))?;
        if let Some(name) = entry.name().ok().filter(|n| n.ends_with(".model")) {
            parts.push((i, name.to_string(), entry.size()));
        }
    }
    let declared = parts.iter().fold(0u64, |s, p| s.saturating_add(p.2));
    if declared == 0 {
        return Err(err("the archive holds no model part (3D/3dmodel.model)".into()));
    }
    // Before any part is inflated.
    budget.reserve(
        declared.saturating_mul(XML_MEMORY_FACTOR),
        &format!(
            "the 3MF model parts ({} inflated, {XML_MEMORY_FACTOR}x for parsing)",
            crate::guard::mib(declared)
        ),
    )?;
    opts.check_cancel(path)?;
    let mut colors = crate::threemf_colors::Colors::default();
    let mut models = Vec::with_capacity(parts.len());
    for (i, name, size) in &parts {
        let entry = zip.by_index(*i).map_err(|e| err(format!("{name}: {e}")))?;
        colors
            .read(BufReader::new(PartReader::new(entry, *size, name)))
            .map_err(|e| err(format!("{name}: {e}")))?;
        opts.check_cancel(path)?;
        let entry = zip.by_index(*i).map_err(|e| err(format!("{name}: {e}")))?;
        let mut de =
            quick_xml::de::Deserializer::from_reader(BufReader::new(PartReader::new(entry, *size, name)));
        models.push(
            threemf::model::Model::deserialize(&mut de)
                .map_err(|e| err(format!("cannot read {name}: {e}")))?,
        );
        opts.check_cancel(path)?;
    }
    let colors = colors.by_object();
    drop(zip);
    drop(bytes);
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut scene = Scene::new(name.clone());
    // The parts' objects by id: the root model part's (it has the build items) and any other part's.
    let objects: HashMap<usize, &threemf::model::Object> = models
        .iter()
        .flat_map(|m| m.resources.object.iter().map(|o| (o.id, o)))
        .collect();
    let root = models
        .iter()
        .find(|m| !m.build.item.is_empty())
        .ok_or_else(|| err("the model has no build item".into()))?;
    scene.unit_m = Some(unit_m(&root.unit));

    // One mesh per object with a mesh, made the first time an instance needs it.
    let mut mesh_of: HashMap<usize, u32> = HashMap::new();
    let mut placed: Vec<(u32, DMat4, String)> = Vec::new();
    let mut tree = NodeTree::default();
    let top = tree.add(name.clone(), None);
    let mut owner: Vec<u32> = Vec::new();
    for (k, item) in root.build.item.iter().enumerate() {
        let item_name = objects
            .get(&item.objectid)
            .and_then(|o| o.name.clone())
            .unwrap_or_else(|| format!("item {k}"));
        let node = tree.add(item_name, Some(top));
        let t = item.transform.map_or(DMat4::IDENTITY, matrix);
        let mut stack = vec![(item.objectid, t, 0usize)];
        while let Some((id, t, depth)) = stack.pop() {
            let object = objects
                .get(&id)
                .ok_or_else(|| err(format!("build item {k} names object {id}, which does not exist")))?;
            if depth > MAX_DEPTH {
                return Err(err(format!(
                    "components nest deeper than {MAX_DEPTH} (a cycle?) at object {id}"
                )));
            }
            if let Some(mesh) = &object.mesh {
                let m = match mesh_of.get(&id) {
                    Some(&m) => m,
                    None => {
                        let color = colors
                            .get(&id)
                            .copied()
                            .unwrap_or(crate::scene::DEFAULT_BASE_COLOR);
                        let prim = primitive(mesh, color).map_err(|m| err(format!("object {id}: {m}")))?;
                        let m = scene.meshes.len() as u32;
                        scene.meshes.push(Mesh {
                            name: object.name.clone().unwrap_or_else(|| format!("object {id}")),
                            primitives: vec![prim],
                        });
                        mesh_of.insert(id, m);
                        m
                    }
                };
                if placed.len() >= MAX_INSTANCES {
                    return Err(SceneError::TooLarge(format!(
                        "{}: more than {MAX_INSTANCES} instances",
                        path.display()
                    )));
                }
                let label = object.name.clone().unwrap_or_else(|| format!("object {id}"));
                placed.push((m, t, label));
                owner.push(node);
            }
            for c in object.components.iter().flat_map(|c| &c.component) {
                stack.push((
                    c.objectid,
                    t * c.transform.map_or(DMat4::IDENTITY, matrix),
                    depth + 1,
                ));
            }
        }
        opts.check_cancel(path)?;
    }
    // Positions far from the origin: the instances are re-centred as the glTF loader does.
    let centre = placed
        .iter()
        .map(|(_, t, _)| t.w_axis.truncate())
        .fold(glam::DVec3::ZERO, |s, p| s + p)
        / placed.len().max(1) as f64;
    let origin = recentre_origin(centre);
    scene.origin = origin.to_array();
    for (i, ((mesh, t, label), node)) in placed.into_iter().zip(owner).enumerate() {
        tree.nodes[node as usize].instances.push(i as u32);
        scene.instances.push(Instance {
            mesh,
            transform: relative_transform(&t, origin),
            name: label,
            visible: true,
        });
    }
    scene.tree = tree;
    for m in &mut scene.meshes {
        crate::normals::smooth_primitive(&mut m.primitives[0], opts.crease_deg, path)?;
    }
    scene.metadata = root
        .metadata
        .iter()
        .filter_map(|m| m.value.clone().map(|v| (m.name.clone(), v)))
        .collect();
    // 3MF is Z up (3MF core specification, 3.1: the build platform's plane is XY, Z points up).
    scene.up = Some(crate::UpAxis::Z);
    Ok(scene)
}

/// A 3MF transform (`m00 m01 m02 m10 ... m32`: row vectors, the translation last) as a column-vector matrix.
fn matrix(t: [f64; 12]) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(t[0], t[1], t[2], 0.0),
        DVec4::new(t[3], t[4], t[5], 0.0),
        DVec4::new(t[6], t[7], t[8], 0.0),
        DVec4::new(t[9], t[10], t[11], 1.0),
    )
}

fn unit_m(u: &threemf::model::Unit) -> f64 {
    use threemf::model::Unit;
    match u {
        Unit::Micron => 1e-6,
        Unit::Millimeter => 1e-3,
        Unit::Centimeter => 1e-2,
        Unit::Inch => 0.0254,
        Unit::Foot => 0.3048,
        Unit::Meter => 1.0,
    }
}

/// An object's mesh: every triangle's corners must name a vertex, every coordinate be finite.
fn primitive(mesh: &threemf::model::Mesh, base_color: [f32; 4]) -> Result<Primitive, String> {
    let positions: Vec<[f32; 3]> = mesh
        .vertices
        .vertex
        .iter()
        .map(|v| [v.x as f32, v.y as f32, v.z as f32])
        .collect();
    if let Some(k) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(format!("vertex {k} is not finite"));
    }
    let n = positions.len();
    let mut indices = Vec::with_capacity(mesh.triangles.triangle.len() * 3);
    for (k, t) in mesh.triangles.triangle.iter().enumerate() {
        for v in [t.v1, t.v2, t.v3] {
            if v >= n {
                return Err(format!("triangle {k} names vertex {v} of {n}"));
            }
            indices.push(v as u32);
        }
    }
    Ok(Primitive::new(positions, indices, base_color).with_double_sided(false))
}

/// A model part as it inflates, checked and squeezed on the way to the XML reader: more bytes than the archive
/// declares is an error (the budget took the declared size), whitespace past [`MAX_WHITESPACE`] bytes between
/// elements is dropped, and a text or tag longer than [`MAX_TOKEN`] is an error.
pub(crate) struct PartReader<R> {
    inner: R,
    name: String,
    declared: u64,
    inflated: u64,
    in_markup: bool,
    blanks: u64,
    token: u64,
}

impl<R: Read> PartReader<R> {
    pub(crate) fn new(inner: R, declared: u64, name: &str) -> PartReader<R> {
        PartReader {
            inner,
            name: name.to_string(),
            declared,
            inflated: 0,
            in_markup: false,
            blanks: 0,
            token: 0,
        }
    }
}

impl<R: Read> Read for PartReader<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let bad = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidData, m);
        loop {
            let n = self.inner.read(out)?;
            if n == 0 {
                return Ok(0);
            }
            self.inflated += n as u64;
            if self.inflated > self.declared {
                return Err(bad(format!(
                    "{} inflates past the {} bytes its archive entry declares",
                    self.name, self.declared
                )));
            }
            let mut kept = 0;
            for k in 0..n {
                let b = out[k];
                match b {
                    b'<' => (self.in_markup, self.token, self.blanks) = (true, 0, 0),
                    b'>' => (self.in_markup, self.token, self.blanks) = (false, 0, 0),
                    b' ' | b'\t' | b'\r' | b'\n' if !self.in_markup => {
                        self.blanks += 1;
                        if self.blanks > MAX_WHITESPACE {
                            continue;
                        }
                    }
                    _ => self.blanks = 0,
                }
                self.token += 1;
                if self.token > MAX_TOKEN {
                    return Err(bad(format!(
                        "{} holds a text or tag longer than {} MiB (at byte {})",
                        self.name,
                        MAX_TOKEN >> 20,
                        self.inflated - (n - k) as u64
                    )));
                }
                out[kept] = b;
                kept += 1;
            }
            if kept > 0 {
                return Ok(kept);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn squeeze(text: &[u8], declared: u64) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::new();
        PartReader::new(text, declared, "3D/3dmodel.model").read_to_end(&mut out)?;
        Ok(out)
    }

    #[test]
    fn parts_stream_squeezed_within_their_declared_size() {
        let blanks = " ".repeat(10_000);
        let xml = format!("<a x=\"1  2\">{blanks}<b/>\n\n<c>t  u</c>{blanks}</a>");
        let out = squeeze(xml.as_bytes(), xml.len() as u64).unwrap();
        let want = format!(
            "<a x=\"1  2\">{}<b/>\n\n<c>t  u</c>{}</a>",
            " ".repeat(MAX_WHITESPACE as usize),
            " ".repeat(MAX_WHITESPACE as usize)
        );
        assert_eq!(String::from_utf8(out).unwrap(), want);
        let e = squeeze(xml.as_bytes(), 100).unwrap_err().to_string();
        assert!(e.contains("inflates past the 100 bytes"), "{e}");
        let long = vec![b'x'; MAX_TOKEN as usize + 1];
        let e = squeeze(&long, u64::MAX).unwrap_err().to_string();
        assert!(e.contains("longer than 16 MiB"), "{e}");
    }
}
