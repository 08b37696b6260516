//! What a CAD kernel hands back for a STEP or IGES file (unique parts tessellated once, the product structure as
//! nodes, units), and the framing that carries it from the kernel's worker process to the loader.
//!
//! The worker writes frames to its stdout; each frame is a tag byte, a little-endian `u64` payload length and the
//! payload: `P` progress (stage, fraction), `M` the model, `E` an error message. The model's payload starts with
//! its layout's version ([`MODEL_FRAME_VERSION`]): a worker of another hrtao build is a clear error, not a
//! misread. The reader checks every count against the bytes the frame holds before allocating, so a truncated or
//! corrupt stream is an error, never a huge allocation.

use std::io::{Read, Write};

/// Most entities a STEP/IGES file may have: the kernel keeps every entity in memory, and 2 million take about
/// 2 GiB.
pub const MAX_CAD_ENTITIES: u64 = 2_000_000;
/// Memory the kernel takes per entity of the file, as estimated for the memory limit (a B-rep entity read and
/// transferred by OpenCASCADE takes about 1 KiB).
pub const CAD_ENTITY_BYTES: u64 = 1024;

/// The layout of the model frame: 2 added the per-vertex normals.
pub const MODEL_FRAME_VERSION: u32 = 2;

/// Triangles of one colour of a part, in the part's coordinates (the model unit).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CadPrimitive {
    pub positions: Vec<[f32; 3]>,
    /// The B-rep surface's unit normal at each position (out of the face's front, the side its triangles wind
    /// toward), or empty: the triangles shade flat. Normals are per face, so an edge between faces is a crease.
    pub normals: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
    /// Linear RGBA, `None` without colour.
    pub color: Option<[f32; 4]>,
    /// The colour was set on the part's faces: it wins over an occurrence's colour.
    pub face_color: bool,
}

impl CadPrimitive {
    /// Triangles without normals (flat shading) or colour; the other fields come from `with_…`.
    pub fn new(positions: Vec<[f32; 3]>, indices: Vec<u32>) -> CadPrimitive {
        CadPrimitive {
            positions,
            indices,
            ..Default::default()
        }
    }

    /// The B-rep surface's normals, one per position (empty: flat shading).
    pub fn with_normals(self, normals: Vec<[f32; 3]>) -> CadPrimitive {
        CadPrimitive { normals, ..self }
    }

    /// The colour (`None`: none) and whether it was set on the part's faces.
    pub fn with_color(self, color: Option<[f32; 4]>, face_color: bool) -> CadPrimitive {
        CadPrimitive {
            color,
            face_color,
            ..self
        }
    }
}

/// A unique part (one shape definition), tessellated once.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CadPart {
    pub name: String,
    pub primitives: Vec<CadPrimitive>,
}

/// A node of the product structure, in pre-order (a parent comes before its children).
#[derive(Clone, Debug, PartialEq)]
pub struct CadNode {
    pub name: String,
    pub parent: Option<u32>,
    /// The part this occurrence places; `None` for an assembly (or a part without triangles).
    pub part: Option<u32>,
    /// Column-major placement in the file's coordinates (model unit).
    pub world: [f64; 16],
    /// The nearest colour set on this occurrence or an enclosing one.
    pub color: Option<[f32; 4]>,
    pub visible: bool,
}

/// Parts, nodes and units of a CAD file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CadModel {
    pub parts: Vec<CadPart>,
    pub nodes: Vec<CadNode>,
    /// Metres per unit of the coordinates above.
    pub model_unit_m: f64,
    /// Metres per unit the file declares, `None` if it declares none.
    pub file_unit_m: Option<f64>,
}

/// Meshes placed by more than one instance, the most placed first (then by mesh order): each mesh's name and its
/// instance count. An assembly's bolts and nuts show here as one mesh each.
pub fn shared_meshes(scene: &crate::Scene) -> Vec<(String, usize)> {
    let mut uses = vec![0usize; scene.meshes.len()];
    for i in &scene.instances {
        if let Some(n) = uses.get_mut(i.mesh as usize) {
            *n += 1;
        }
    }
    let mut shared: Vec<(usize, usize)> = uses.into_iter().enumerate().filter(|(_, n)| *n > 1).collect();
    shared.sort_by_key(|&(m, n)| (std::cmp::Reverse(n), m));
    shared
        .into_iter()
        .map(|(m, n)| (scene.meshes[m].name.clone(), n))
        .collect()
}

/// The log line of a scene a CAD worker (`kernel`) read and tessellated in `read_s` seconds: its meshes,
/// instances (the most shared meshes named) and triangles.
pub fn loaded_summary(path: &std::path::Path, scene: &crate::Scene, kernel: &str, read_s: f64) -> String {
    let shared = shared_meshes(scene);
    format!(
        "{}: {} unique meshes, {} instances{}, {} unique / {} instanced triangles; read and tessellated in \
         {read_s:.2} s ({kernel} worker)",
        path.display(),
        scene.meshes.len(),
        scene.instances.len(),
        if shared.is_empty() {
            String::new()
        } else {
            format!(" ({})", shared_meshes_text(&shared, 4))
        },
        scene.unique_triangle_count(),
        scene.instanced_triangle_count(),
    )
}

/// "nut ×8, bolt ×6, bracket ×2": the first `max` of [`shared_meshes`], "and K more" after them.
pub fn shared_meshes_text(shared: &[(String, usize)], max: usize) -> String {
    let mut parts: Vec<String> = shared
        .iter()
        .take(max)
        .map(|(name, n)| format!("{name} ×{n}"))
        .collect();
    if shared.len() > max {
        parts.push(format!("and {} more", shared.len() - max));
    }
    parts.join(", ")
}

/// One frame of the worker's stream.
#[derive(Clone, Debug, PartialEq)]
pub enum Frame {
    Progress { stage: String, fraction: f64 },
    Model(CadModel),
    Error(String),
}

/// Writes a progress frame.
pub fn write_progress(w: &mut impl Write, stage: &str, fraction: f64) -> std::io::Result<()> {
    let mut p = Vec::new();
    put_str(&mut p, stage);
    p.extend_from_slice(&fraction.to_le_bytes());
    frame(w, b'P', &p)
}

/// Writes an error frame.
pub fn write_error(w: &mut impl Write, message: &str) -> std::io::Result<()> {
    let mut p = Vec::new();
    put_str(&mut p, message);
    frame(w, b'E', &p)
}

/// Writes the model frame.
pub fn write_model(w: &mut impl Write, m: &CadModel) -> std::io::Result<()> {
    let mut p = Vec::new();
    p.extend_from_slice(&MODEL_FRAME_VERSION.to_le_bytes());
    p.extend_from_slice(&m.model_unit_m.to_le_bytes());
    p.extend_from_slice(&m.file_unit_m.unwrap_or(0.0).to_le_bytes());
    p.extend_from_slice(&(m.parts.len() as u64).to_le_bytes());
    for part in &m.parts {
        put_str(&mut p, &part.name);
        p.extend_from_slice(&(part.primitives.len() as u64).to_le_bytes());
        for q in &part.primitives {
            put_color(&mut p, q.color);
            p.push(q.face_color as u8);
            p.extend_from_slice(&(q.positions.len() as u64).to_le_bytes());
            for v in &q.positions {
                for c in v {
                    p.extend_from_slice(&c.to_le_bytes());
                }
            }
            p.extend_from_slice(&(q.normals.len() as u64).to_le_bytes());
            for v in &q.normals {
                for c in v {
                    p.extend_from_slice(&c.to_le_bytes());
                }
            }
            p.extend_from_slice(&(q.indices.len() as u64).to_le_bytes());
            for i in &q.indices {
                p.extend_from_slice(&i.to_le_bytes());
            }
        }
    }
    p.extend_from_slice(&(m.nodes.len() as u64).to_le_bytes());
    for n in &m.nodes {
        put_str(&mut p, &n.name);
        p.extend_from_slice(&n.parent.map_or(u64::MAX, u64::from).to_le_bytes());
        p.extend_from_slice(&n.part.map_or(u64::MAX, u64::from).to_le_bytes());
        for v in &n.world {
            p.extend_from_slice(&v.to_le_bytes());
        }
        put_color(&mut p, n.color);
        p.push(n.visible as u8);
    }
    frame(w, b'M', &p)
}

fn frame(w: &mut impl Write, tag: u8, payload: &[u8]) -> std::io::Result<()> {
    w.write_all(&[tag])?;
    w.write_all(&(payload.len() as u64).to_le_bytes())?;
    w.write_all(payload)?;
    w.flush()
}

fn put_str(p: &mut Vec<u8>, s: &str) {
    p.extend_from_slice(&(s.len() as u64).to_le_bytes());
    p.extend_from_slice(s.as_bytes());
}

fn put_color(p: &mut Vec<u8>, c: Option<[f32; 4]>) {
    p.push(c.is_some() as u8);
    for v in c.unwrap_or_default() {
        p.extend_from_slice(&v.to_le_bytes());
    }
}

/// Reads the next frame: `Ok(None)` at a clean end of stream. `max_payload` bounds a frame's size (the memory
/// limit of the load); `reserve` is told a frame's size before it is allocated and may refuse it.
pub fn read_frame(
    r: &mut impl Read,
    reserve: &mut dyn FnMut(u64) -> Result<(), String>,
) -> Result<Option<Frame>, String> {
    let mut head = [0u8; 9];
    let mut got = 0;
    while got < head.len() {
        let n = r
            .read(&mut head[got..])
            .map_err(|e| format!("reading the worker's output: {e}"))?;
        if n == 0 {
            if got == 0 {
                return Ok(None);
            }
            return Err("the worker's output ended inside a frame header".into());
        }
        got += n;
    }
    let len = u64::from_le_bytes(head[1..9].try_into().unwrap());
    if head[0] == b'M' {
        reserve(len)?;
    } else if len > 1 << 20 {
        return Err(format!("a {len}-byte message frame from the worker"));
    }
    let mut payload = Vec::new();
    let read = r
        .take(len)
        .read_to_end(&mut payload)
        .map_err(|e| format!("reading the worker's output: {e}"))?;
    if read as u64 != len {
        return Err(format!(
            "the worker's output ended after {read} of a {len}-byte frame"
        ));
    }
    let mut c = Cursor { b: &payload, at: 0 };
    let frame = match head[0] {
        b'P' => Frame::Progress {
            stage: c.str()?,
            fraction: c.f64()?,
        },
        b'E' => Frame::Error(c.str()?),
        b'M' => Frame::Model(c.model()?),
        t => return Err(format!("unknown frame tag {t:#04x} from the worker")),
    };
    Ok(Some(frame))
}

struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn take(&mut self, n: u64) -> Result<&[u8], String> {
        let left = (self.b.len() - self.at) as u64;
        if n > left {
            return Err(format!(
                "a model frame cut short (needs {n} more bytes, has {left})"
            ));
        }
        let s = &self.b[self.at..self.at + n as usize];
        self.at += n as usize;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn f32(&mut self) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    /// A count of items of `size` bytes each, checked against what is left.
    fn count(&mut self, size: u64) -> Result<usize, String> {
        let n = self.u64()?;
        let left = (self.b.len() - self.at) as u64;
        if n.saturating_mul(size) > left {
            return Err(format!(
                "a model frame declares {n} items, more than its {left} bytes hold"
            ));
        }
        Ok(n as usize)
    }
    fn str(&mut self) -> Result<String, String> {
        let n = self.count(1)?;
        Ok(String::from_utf8_lossy(self.take(n as u64)?).into_owned())
    }
    fn opt_index(&mut self) -> Result<Option<u32>, String> {
        let v = self.u64()?;
        Ok(if v == u64::MAX {
            None
        } else {
            Some(u32::try_from(v).map_err(|_| format!("index {v}"))?)
        })
    }
    fn color(&mut self) -> Result<Option<[f32; 4]>, String> {
        let some = self.u8()? != 0;
        let c = [self.f32()?, self.f32()?, self.f32()?, self.f32()?];
        Ok(some.then_some(c))
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    fn vec3s(&mut self) -> Result<Vec<[f32; 3]>, String> {
        let n = self.count(12)?;
        let mut v = Vec::with_capacity(n);
        for _ in 0..n {
            v.push([self.f32()?, self.f32()?, self.f32()?]);
        }
        Ok(v)
    }
    fn model(&mut self) -> Result<CadModel, String> {
        let version = self.u32()?;
        if version != MODEL_FRAME_VERSION {
            return Err(format!(
                "a model frame of layout version {version}, this loader reads version {MODEL_FRAME_VERSION} \
                 (the worker is another hrtao build)"
            ));
        }
        let model_unit_m = self.f64()?;
        let file_unit_m = Some(self.f64()?).filter(|&u| u > 0.0 && u.is_finite());
        let nparts = self.count(16)?;
        let mut parts = Vec::with_capacity(nparts);
        for _ in 0..nparts {
            let name = self.str()?;
            // Colour 17 bytes, face flag 1, three counts of 8.
            let nprims = self.count(42)?;
            let mut primitives = Vec::with_capacity(nprims);
            for _ in 0..nprims {
                let color = self.color()?;
                let face_color = self.u8()? != 0;
                let positions = self.vec3s()?;
                let normals = self.vec3s()?;
                if !normals.is_empty() && normals.len() != positions.len() {
                    return Err(format!(
                        "a model frame with {} normals for {} vertices",
                        normals.len(),
                        positions.len()
                    ));
                }
                let ni = self.count(4)?;
                let mut indices = Vec::with_capacity(ni);
                for _ in 0..ni {
                    indices.push(u32::from_le_bytes(self.take(4)?.try_into().unwrap()));
                }
                primitives.push(
                    CadPrimitive::new(positions, indices)
                        .with_normals(normals)
                        .with_color(color, face_color),
                );
            }
            parts.push(CadPart { name, primitives });
        }
        let nnodes = self.count(8 + 16 + 128 + 17 + 1)?;
        let mut nodes = Vec::with_capacity(nnodes);
        for _ in 0..nnodes {
            let name = self.str()?;
            let parent = self.opt_index()?;
            let part = self.opt_index()?;
            let mut world = [0.0; 16];
            for v in &mut world {
                *v = self.f64()?;
            }
            let color = self.color()?;
            let visible = self.u8()? != 0;
            nodes.push(CadNode {
                name,
                parent,
                part,
                world,
                color,
                visible,
            });
        }
        if self.at != self.b.len() {
            return Err(format!("{} bytes after the model", self.b.len() - self.at));
        }
        Ok(CadModel {
            parts,
            nodes,
            model_unit_m,
            file_unit_m,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> CadModel {
        CadModel {
            parts: vec![CadPart {
                name: "bolt".into(),
                primitives: vec![CadPrimitive::new(
                    vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                    vec![0, 1, 2],
                )
                .with_normals(vec![[0.0, 0.0, 1.0]; 3])
                .with_color(Some([1.0, 0.0, 0.0, 1.0]), true)],
            }],
            nodes: vec![CadNode {
                name: "bolt1".into(),
                parent: None,
                part: Some(0),
                world: glam::DMat4::from_translation(glam::DVec3::new(5.0, 6.0, 7.0)).to_cols_array(),
                color: None,
                visible: false,
            }],
            model_unit_m: 1e-3,
            file_unit_m: Some(0.0254),
        }
    }

    #[test]
    fn frames_round_trip() {
        let mut buf = Vec::new();
        write_progress(&mut buf, "tessellate", 0.5).unwrap();
        write_model(&mut buf, &sample()).unwrap();
        write_error(&mut buf, "boom").unwrap();
        let mut r = &buf[..];
        let mut ok = |_| Ok(());
        assert_eq!(
            read_frame(&mut r, &mut ok).unwrap(),
            Some(Frame::Progress {
                stage: "tessellate".into(),
                fraction: 0.5
            })
        );
        assert_eq!(read_frame(&mut r, &mut ok).unwrap(), Some(Frame::Model(sample())));
        assert_eq!(
            read_frame(&mut r, &mut ok).unwrap(),
            Some(Frame::Error("boom".into()))
        );
        assert_eq!(read_frame(&mut r, &mut ok).unwrap(), None);
    }

    /// Normals are all or nothing per primitive: none (flat) round-trips, a count other than the vertices' is an
    /// error naming both counts.
    #[test]
    fn normals_are_one_per_vertex_or_none() {
        let mut flat = sample();
        flat.parts[0].primitives[0].normals.clear();
        let mut buf = Vec::new();
        write_model(&mut buf, &flat).unwrap();
        assert_eq!(
            read_frame(&mut &buf[..], &mut |_| Ok(())).unwrap(),
            Some(Frame::Model(flat))
        );
        let mut short = sample();
        short.parts[0].primitives[0].normals.pop();
        let mut buf = Vec::new();
        write_model(&mut buf, &short).unwrap();
        let e = read_frame(&mut &buf[..], &mut |_| Ok(())).unwrap_err();
        assert!(e.contains("2 normals for 3 vertices"), "{e}");
    }

    #[test]
    fn every_truncation_is_an_error() {
        let mut buf = Vec::new();
        write_model(&mut buf, &sample()).unwrap();
        for cut in 1..buf.len() {
            let mut r = &buf[..cut];
            assert!(read_frame(&mut r, &mut |_| Ok(())).is_err(), "cut at {cut}");
        }
        // A count that claims more than the frame holds is refused before allocating.
        let mut bad = buf.clone();
        let parts = 9 + 4 + 16;
        bad[parts..parts + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(read_frame(&mut &bad[..], &mut |_| Ok(()))
            .unwrap_err()
            .contains("items"));
        // Another layout version is named as such.
        let mut other = buf.clone();
        other[9..13].copy_from_slice(&1u32.to_le_bytes());
        let e = read_frame(&mut &other[..], &mut |_| Ok(())).unwrap_err();
        assert!(
            e.contains("layout version 1") && e.contains("another hrtao build"),
            "{e}"
        );
        // The reserve callback sees the size first.
        let e = read_frame(&mut &buf[..], &mut |n| Err(format!("{n} over"))).unwrap_err();
        assert!(e.ends_with("over"), "{e}");
    }
}
