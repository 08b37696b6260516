//! Image files: linear float AO as PFM (bottom row first, little endian) or OpenEXR, linear RGB (the sky light)
//! as colour PFM or RGB OpenEXR, shaded RGBA8 as PNG.
use std::io::Write;
use std::path::Path;

use crate::error::{CoreError, Result};

fn io_err(path: &Path, e: std::io::Error) -> CoreError {
    CoreError::Io {
        path: path.display().to_string(),
        source: e,
    }
}

/// Writes a one-channel float image (`data` row 0 = top) as greyscale PFM ("Pf", negative scale).
pub fn write_pfm(path: &Path, width: u32, height: u32, data: &[f32]) -> Result<()> {
    check_len(width, height, data.len())?;
    let mut out = Vec::with_capacity(data.len() * 4 + 32);
    write!(out, "Pf\n{width} {height}\n-1.0\n").unwrap();
    for y in (0..height as usize).rev() {
        for v in &data[y * width as usize..(y + 1) * width as usize] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, out).map_err(|e| io_err(path, e))
}

fn check_len(width: u32, height: u32, len: usize) -> Result<()> {
    if width as usize * height as usize != len {
        return Err(CoreError::Invalid(format!(
            "image of {width}x{height} needs {} values, got {len}",
            width * height
        )));
    }
    Ok(())
}

/// Reads a PFM file ("Pf" greyscale or "PF" colour: the first channel is kept) into rows top first.
pub fn read_pfm(path: &Path) -> Result<(u32, u32, Vec<f32>)> {
    let (w, h, rgb) = read_pfm_rgb(path)?;
    Ok((w, h, rgb.iter().map(|p| p[0]).collect()))
}

/// Reads a PFM file as RGB ("Pf" greyscale in every channel), rows top first.
fn read_pfm_rgb(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let bytes = std::fs::read(path).map_err(|e| io_err(path, e))?;
    let bad = |why: &str| CoreError::Invalid(format!("{}: not a valid PFM file ({why})", path.display()));
    let mut fields = Vec::new();
    let mut pos = 0;
    while fields.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err(bad("truncated header"));
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    pos += 1; // the single whitespace byte after the scale
    let channels = match fields[0].as_str() {
        "Pf" => 1,
        "PF" => 3,
        _ => return Err(bad("bad magic")),
    };
    let w: u32 = fields[1].parse().map_err(|_| bad("bad width"))?;
    let h: u32 = fields[2].parse().map_err(|_| bad("bad height"))?;
    let scale: f32 = fields[3].parse().map_err(|_| bad("bad scale"))?;
    let n = w as usize * h as usize * channels;
    if bytes.len() < pos + n * 4 {
        return Err(bad("truncated data"));
    }
    let mut data = vec![[0f32; 3]; w as usize * h as usize];
    for y in 0..h as usize {
        for x in 0..w as usize {
            let px = &mut data[(h as usize - 1 - y) * w as usize + x];
            for (c, v) in px.iter_mut().enumerate() {
                let i = pos + ((y * w as usize + x) * channels + c.min(channels - 1)) * 4;
                let raw = [bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]];
                *v = if scale < 0.0 {
                    f32::from_le_bytes(raw)
                } else {
                    f32::from_be_bytes(raw)
                };
            }
        }
    }
    Ok((w, h, data))
}

/// Writes a one-channel float image as an OpenEXR file (R, G and B all equal to the value).
pub fn write_exr(path: &Path, width: u32, height: u32, data: &[f32]) -> Result<()> {
    check_len(width, height, data.len())?;
    let w = width as usize;
    exr::prelude::write_rgb_file(path, w, height as usize, |x, y| {
        let v = data[y * w + x];
        (v, v, v)
    })
    .map_err(|e| CoreError::Invalid(format!("writing {}: {e}", path.display())))
}

/// Reads the red channel of an OpenEXR file's first RGBA layer (row 0 = top): the AO `write_exr` writes, and
/// Blender's AO references (R = G = B). Missing channels read as NaN; any NaN is an error.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<f32>)> {
    let (w, h, rgb) = read_exr_rgb(path)?;
    Ok((w, h, rgb.iter().map(|p| p[0]).collect()))
}

/// Reads the RGB channels of an OpenEXR file's first RGBA layer (row 0 = top). Missing channels read as NaN;
/// any NaN is an error.
fn read_exr_rgb(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| (size.width(), vec![[f32::NAN; 3]; size.area()]),
        |(width, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * *width + pos.x()] = [r, g, b],
    )
    .map_err(|e| CoreError::Invalid(format!("reading {}: {e}", path.display())))?;
    let size = image.layer_data.size;
    let (_, data) = image.layer_data.channel_data.pixels;
    if data.iter().flatten().any(|v| v.is_nan()) {
        return Err(CoreError::Invalid(format!(
            "{}: the image has NaN values",
            path.display()
        )));
    }
    Ok((size.width() as u32, size.height() as u32, data))
}

/// Reads an AO image written as .pfm or .exr, chosen by the extension (row 0 = top).
pub fn read_ao(path: &Path) -> Result<(u32, u32, Vec<f32>)> {
    match ao_format(path)? {
        AoFormat::Pfm => read_pfm(path),
        AoFormat::Exr => read_exr(path),
    }
}

enum AoFormat {
    Pfm,
    Exr,
}

fn ao_format(path: &Path) -> Result<AoFormat> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("pfm") => Ok(AoFormat::Pfm),
        Some("exr") => Ok(AoFormat::Exr),
        _ => Err(CoreError::Invalid(format!(
            "{}: an AO image must end in .pfm or .exr",
            path.display()
        ))),
    }
}

/// Writes the AO image as .pfm or .exr, chosen by the extension.
pub fn write_ao(path: &Path, width: u32, height: u32, data: &[f32]) -> Result<()> {
    match ao_format(path)? {
        AoFormat::Pfm => write_pfm(path, width, height, data),
        AoFormat::Exr => write_exr(path, width, height, data),
    }
}

/// Writes a linear RGB image (row 0 = top) as a colour PFM ("PF") or an RGB OpenEXR, chosen by the extension.
pub fn write_rgb(path: &Path, width: u32, height: u32, data: &[[f32; 3]]) -> Result<()> {
    check_len(width, height, data.len())?;
    match ao_format(path)? {
        AoFormat::Pfm => {
            let mut out = Vec::with_capacity(data.len() * 12 + 32);
            write!(out, "PF\n{width} {height}\n-1.0\n").unwrap();
            for y in (0..height as usize).rev() {
                for p in &data[y * width as usize..(y + 1) * width as usize] {
                    for c in p {
                        out.extend_from_slice(&c.to_le_bytes());
                    }
                }
            }
            std::fs::write(path, out).map_err(|e| io_err(path, e))
        }
        AoFormat::Exr => {
            let w = width as usize;
            exr::prelude::write_rgb_file(path, w, height as usize, |x, y| {
                let p = data[y * w + x];
                (p[0], p[1], p[2])
            })
            .map_err(|e| CoreError::Invalid(format!("writing {}: {e}", path.display())))
        }
    }
}

/// Reads a linear RGB image written as .pfm or .exr, chosen by the extension (row 0 = top; a greyscale PFM in
/// every channel).
pub fn read_rgb(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    match ao_format(path)? {
        AoFormat::Pfm => read_pfm_rgb(path),
        AoFormat::Exr => read_exr_rgb(path),
    }
}

/// Writes packed RGBA8 pixels (row 0 = top) as PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    check_len(width, height, rgba.len() / 4)?;
    image::save_buffer(path, rgba, width, height, image::ExtendedColorType::Rgba8)
        .map_err(|e| CoreError::Invalid(format!("writing {}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ao_round_trips_through_exr_and_pfm_with_rows_top_first() {
        let dir = std::env::temp_dir().join(format!("hrtao-ao-rt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // 3 x 2, every value distinct, so a flipped or transposed read fails.
        let data = [0.0, 0.125, 0.25, 0.5, 0.75, 1.0];
        for name in ["ao.exr", "ao.PFM"] {
            let path = dir.join(name);
            write_ao(&path, 3, 2, &data).unwrap();
            assert_eq!(read_ao(&path).unwrap(), (3, 2, data.to_vec()), "{name}");
        }
        assert!(read_ao(&dir.join("ao.png")).is_err());
        std::fs::write(dir.join("bad.exr"), b"not an exr").unwrap();
        let err = read_ao(&dir.join("bad.exr")).unwrap_err().to_string();
        assert!(err.contains("bad.exr"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn rgb_round_trips_through_colour_pfm_and_exr() {
        let dir = std::env::temp_dir().join(format!("hrtao-rgb-rt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let data: Vec<[f32; 3]> = (0..6)
            .map(|i| [i as f32, 0.5 * i as f32, 2.0 + i as f32])
            .collect();
        for name in ["light.pfm", "light.exr"] {
            let path = dir.join(name);
            write_rgb(&path, 3, 2, &data).unwrap();
            assert_eq!(read_rgb(&path).unwrap(), (3, 2, data.clone()), "{name}");
        }
        let bytes = std::fs::read(dir.join("light.pfm")).unwrap();
        assert!(bytes.starts_with(b"PF\n3 2\n-1.0\n"), "a colour PFM");
        // A greyscale PFM reads into every channel.
        write_pfm(&dir.join("grey.pfm"), 1, 1, &[0.25]).unwrap();
        assert_eq!(read_rgb(&dir.join("grey.pfm")).unwrap().2, [[0.25; 3]]);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn pfm_round_trip_keeps_rows_top_first() {
        let dir = std::env::temp_dir().join(format!("hrtao-pfm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.pfm");
        let data: Vec<f32> = (0..6).map(|i| i as f32 / 5.0).collect();
        write_pfm(&p, 3, 2, &data).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert!(bytes.starts_with(b"Pf\n3 2\n-1.0\n"));
        // Bottom row first in the file: the first value stored is data[3].
        let first = f32::from_le_bytes(bytes[12..16].try_into().unwrap());
        assert_eq!(first, data[3]);
        let (w, h, back) = read_pfm(&p).unwrap();
        assert_eq!((w, h), (3, 2));
        assert_eq!(back, data);
        assert!(read_pfm(&dir.join("missing.pfm")).is_err());
        std::fs::write(dir.join("bad.pfm"), b"P6\n1 1\n").unwrap();
        assert!(read_pfm(&dir.join("bad.pfm")).is_err());
    }
}
