//! STL loader (binary and ASCII, via stl_io): one mesh, one identity instance, coordinates as in the file.
//! The file goes through the guard; the triangle count a binary file declares must match its size, and
//! the memory it implies is checked before decoding.
//!
//! Shading normals: STL's stored facet normals are not trusted (exporters often write zeros, or normals that
//! disagree with the winding), and they are per facet anyway; the mesh gets smooth normals by the load's crease
//! angle ([`crate::normals::smooth`], which also welds the file's separate triangle corners), or face normals
//! when [`LoadOptions::crease_deg`] is `None`.

use std::path::Path;

use stl_io::TriangleIterator;

use crate::error::SceneError;
use crate::guard::{read_model, LoadOptions};
use crate::scene::{LoadProgress, Scene};

/// Header (80) + triangle count (4), then 50 bytes per triangle.
const HEADER: u64 = 84;
const RECORD: u64 = 50;
/// Memory per decoded triangle: 3 positions and 3 indices.
const TRIANGLE_BYTES: u64 = 36 + 12;
/// Triangles decoded between two checks of the cancel flag.
const CANCEL_EVERY: usize = 1 << 16;

pub fn load_stl(
    path: &Path,
    opts: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Scene, SceneError> {
    let err = |message: String| SceneError::Stl {
        path: path.to_path_buf(),
        message,
    };
    let (mut bytes, mut budget) = read_model(path, opts, progress)?;
    let size = bytes.len() as u64;
    let declared =
        (size >= HEADER).then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let binary = declared.is_some_and(|n| HEADER + n * RECORD == size);
    let metadata = header_text(&bytes, binary);
    let triangles = if binary {
        // A binary header may begin with "solid": hide it so the ASCII probe does not take it.
        if bytes.starts_with(b"solid") {
            bytes[..5].fill(b' ');
        }
        declared.unwrap_or(0)
    } else if bytes.trim_ascii_start().starts_with(b"solid") {
        count_facets(&bytes)
    } else {
        return Err(err(match declared {
            Some(n) => format!(
                "binary STL declares {n} triangles ({} bytes) but the file has {size} bytes",
                HEADER + n * RECORD
            ),
            None => format!("only {size} bytes: neither a binary STL header nor ASCII `solid`"),
        }));
    };
    budget.reserve(triangles.saturating_mul(TRIANGLE_BYTES), "the declared triangles")?;
    if opts.crease_deg.is_some() {
        budget.reserve(
            triangles.saturating_mul(crate::normals::SMOOTH_BYTES_PER_TRIANGLE),
            "smoothing the normals",
        )?;
    }
    opts.check_cancel(path)?;
    let mut cursor = std::io::Cursor::new(bytes);
    let reader: Box<dyn TriangleIterator<Item = std::io::Result<stl_io::Triangle>>> =
        stl_io::create_stl_reader(&mut cursor).map_err(|e| err(format!("cannot parse: {e}")))?;
    let mut positions = Vec::with_capacity(triangles as usize * 3);
    for (k, t) in reader.enumerate() {
        if k % CANCEL_EVERY == 0 {
            opts.check_cancel(path)?;
            progress(LoadProgress {
                stage: "triangles",
                done: k as u64,
                total: triangles,
            });
        }
        let t = t.map_err(|e| err(format!("triangle {k}: {e}")))?;
        if positions.len() as u64 >= triangles * 3 {
            return Err(err(format!("more than the {triangles} triangles counted")));
        }
        positions.extend(t.vertices.iter().map(|v| v.0));
    }
    let n = u32::try_from(positions.len()).map_err(|_| err("more than 2^32 vertices".into()))?;
    let mut scene = Scene::single_mesh(path, positions, (0..n).collect());
    opts.check_cancel(path)?;
    crate::normals::smooth_primitive(&mut scene.meshes[0].primitives[0], opts.crease_deg, path)?;
    scene.metadata = metadata.into_iter().collect();
    Ok(scene)
}

/// What an STL says about itself: an ASCII file's solid name (the rest of its first line), a binary file's
/// 80-byte header as text (printable ASCII, trimmed; nothing if it is blank or binary data).
fn header_text(bytes: &[u8], binary: bool) -> Option<(String, String)> {
    let (key, raw) = if binary {
        ("header", &bytes[..80])
    } else {
        let start = bytes.trim_ascii_start();
        let line = start.split(|&b| b == b'\n').next().unwrap_or_default();
        ("solid name", line.strip_prefix(b"solid").unwrap_or_default())
    };
    let text = raw.strip_suffix(b"\r").unwrap_or(raw);
    let text: &[u8] = match text.iter().position(|&b| b == 0) {
        Some(end) if binary => &text[..end],
        _ => text,
    };
    let text = text.trim_ascii();
    let printable = text.iter().all(|b| b.is_ascii_graphic() || *b == b' ');
    (printable && !text.is_empty() && text.len() <= 256)
        .then(|| (key.to_string(), String::from_utf8_lossy(text).into_owned()))
}

/// Facets of an ASCII STL (lines starting with `facet`).
fn count_facets(text: &[u8]) -> u64 {
    text.split(|&b| b == b'\n')
        .filter(|l| l.trim_ascii_start().starts_with(b"facet"))
        .count() as u64
}
