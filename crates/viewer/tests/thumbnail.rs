//! `hrtao thumbnail` as the desktop runs it: the exact `Exec` line of packaging/hrtao.thumbnailer (%s, %i, %o
//! substituted) on a small model of every format of `hrtao_scene::SUPPORTED_EXTENSIONS` writes a PNG whose
//! longest side is at most the size, the model opaque on a transparent background and shaded (not blank); a file
//! over the size limit and a render over the time limit are refused (exit status non-zero) with no file left.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

mod common;
#[path = "../../scene/tests/common/threemf.rs"]
mod threemf_writer;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-thumbnail-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The thumbnailer's `Exec` line with %s, %i and %o substituted, `hrtao` being the binary under test.
fn exec_line(size: u32, input: &Path, output: &Path) -> Command {
    let entry = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../packaging/hrtao.thumbnailer"),
    )
    .unwrap();
    let mut lines = entry.lines().filter(|l| !l.trim().is_empty());
    assert_eq!(lines.next(), Some("[Thumbnailer Entry]"));
    let exec = entry
        .lines()
        .find_map(|l| l.strip_prefix("Exec="))
        .expect("an Exec line");
    let argv: Vec<String> = exec
        .split_whitespace()
        .map(|w| match w {
            "%s" => size.to_string(),
            "%i" => input.display().to_string(),
            "%o" => output.display().to_string(),
            w => w.to_string(),
        })
        .collect();
    assert_eq!(argv[0], "hrtao", "{exec}");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_hrtao"));
    cmd.args(&argv[1..]).env("HRTAO_VALIDATION", "1");
    cmd
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// A box standing on a plate (z up): where they meet, ambient occlusion darkens the plate.
fn box_on_plate() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    let mut t = Vec::new();
    for (lo, hi) in [
        ([-2.0, -2.0, 0.0], [2.0, 2.0, 0.2]),
        ([-0.6, -0.6, 0.2], [0.6, 0.6, 1.4]),
    ] {
        let b = v.len() as u32;
        v.extend(hrtao_scene::box_corners(lo, hi));
        t.extend(hrtao_scene::box_triangles().map(|f| f.map(|i| b + i)));
    }
    (v, t)
}

fn write_obj(path: &Path) {
    let (v, t) = box_on_plate();
    let mut s = String::from("o box_on_plate\n");
    for p in &v {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for f in &t {
        s += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    std::fs::write(path, s).unwrap();
}

fn write_stl(path: &Path) {
    let (v, t) = box_on_plate();
    let mut s = String::from("solid box_on_plate\n");
    for f in &t {
        s += " facet normal 0 0 0\n  outer loop\n";
        for &i in f {
            let p = v[i as usize];
            s += &format!("   vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s += "  endloop\n endfacet\n";
    }
    s += "endsolid box_on_plate\n";
    std::fs::write(path, s).unwrap();
}

fn write_ply(path: &Path) {
    let (v, t) = box_on_plate();
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        v.len(),
        t.len()
    );
    for p in &v {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for f in &t {
        s += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    std::fs::write(path, s).unwrap();
}

/// The glTF document and its binary buffer (positions, then u32 indices), Y up as glTF is.
fn gltf_parts(uri: Option<&str>) -> (serde_json::Value, Vec<u8>) {
    let (v, t) = box_on_plate();
    let v: Vec<[f32; 3]> = v.iter().map(|p| [p[0], p[2], -p[1]]).collect();
    let mut bin = Vec::new();
    for p in &v {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let positions = bin.len();
    for f in &t {
        for i in f {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let (mut min, mut max) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in &v {
        for (k, c) in p.iter().enumerate() {
            min[k] = min[k].min(*c);
            max[k] = max[k].max(*c);
        }
    }
    let mut buffer = serde_json::json!({"byteLength": bin.len()});
    if let Some(uri) = uri {
        buffer["uri"] = uri.into();
    }
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "box_on_plate"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": v.len(), "type": "VEC3", "min": min, "max": max},
            {"bufferView": 1, "componentType": 5125, "count": t.len() * 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions},
            {"buffer": 0, "byteOffset": positions, "byteLength": bin.len() - positions}
        ],
        "buffers": [buffer]
    });
    (doc, bin)
}

fn write_gltf(path: &Path) {
    let (doc, bin) = gltf_parts(Some("box_on_plate.bin"));
    std::fs::write(path.with_file_name("box_on_plate.bin"), bin).unwrap();
    std::fs::write(path, doc.to_string()).unwrap();
}

fn write_glb(path: &Path) {
    let (doc, mut bin) = gltf_parts(None);
    let mut json = doc.to_string().into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    std::fs::write(path, out).unwrap();
}

/// A small model of `ext` in `dir`; None (with the reason printed) only for IFC without the IfcOpenShell venv.
fn model(dir: &Path, ext: &str) -> Option<PathBuf> {
    let path = dir.join(format!("box_on_plate.{ext}"));
    match ext {
        "obj" => write_obj(&path),
        "stl" => write_stl(&path),
        "ply" => write_ply(&path),
        "gltf" => write_gltf(&path),
        "glb" => write_glb(&path),
        "3mf" => {
            let obj = dir.join("for_3mf.obj");
            write_obj(&obj);
            let scene = hrtao_scene::load(obj.to_str().unwrap(), &mut |_| {}).unwrap();
            threemf_writer::write_3mf(&scene, &path, "millimeter");
        }
        "step" | "stp" | "iges" | "igs" => {
            let format = if ext.starts_with('s') {
                hrtao_occt::Format::Step
            } else {
                hrtao_occt::Format::Iges
            };
            hrtao_occt::write_test_model(&path, format, hrtao_occt::TestModel::BoltPattern(4)).unwrap();
        }
        "ifc" => {
            let python = hrtao_scene::ifc_python();
            if !python.is_file() {
                println!(
                    "skipped .ifc: no IfcOpenShell interpreter at {} (install: {})",
                    python.display(),
                    hrtao_scene::ifc_install_command()
                );
                return None;
            }
            common::make_building(&python, &path, 3);
        }
        other => panic!("no test model of .{other}: add one here"),
    }
    Some(path)
}

/// The PNG's size, and over its opaque pixels: their count, and the spread of their luminance (the 95th minus
/// the 5th percentile, 0..=255).
fn measure(png: &Path) -> ((u32, u32), usize, u8) {
    let img = image::open(png).unwrap().to_rgba8();
    let mut lum: Vec<u8> = img
        .pixels()
        .filter(|p| p.0[3] == 255)
        .map(|p| ((p.0[0] as u32 * 3 + p.0[1] as u32 * 6 + p.0[2] as u32) / 10) as u8)
        .collect();
    lum.sort_unstable();
    let spread = match lum.len() {
        0 => 0,
        n => lum[n * 95 / 100] - lum[n * 5 / 100],
    };
    (img.dimensions(), lum.len(), spread)
}

/// Files of `dir` whose names look like the thumbnailer's temporary files.
fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".hrtao-"))
        .collect()
}

#[test]
fn the_thumbnailer_line_previews_every_format() {
    let dir = tmp("formats");
    let size = 64;
    for ext in hrtao_scene::SUPPORTED_EXTENSIONS {
        let Some(input) = model(&dir, ext) else {
            continue;
        };
        let png = dir.join(format!("{ext}.png"));
        let t0 = Instant::now();
        let o = exec_line(size, &input, &png).output().unwrap();
        let t = text(&o);
        assert!(o.status.success(), ".{ext}: {t}");
        assert!(!t.contains("validation layer reported"), ".{ext}: {t}");
        let ((w, h), opaque, spread) = measure(&png);
        println!(
            ".{ext}: {w}×{h}, {opaque} opaque pixels, luminance spread {spread}, {:.1} s",
            t0.elapsed().as_secs_f64()
        );
        assert!(w.max(h) <= size && w.min(h) >= 8, ".{ext}: {w}×{h}");
        // The model fills its cut-out (the crop leaves a margin, the box's silhouette some background).
        assert!(
            opaque * 3 >= (w * h) as usize && opaque < (w * h) as usize,
            ".{ext}: {opaque} of {w}×{h} opaque"
        );
        assert!(spread >= 24, ".{ext}: flat (spread {spread})");
    }
    // The AO: the same thumbnail without it (the same view and cut-out) is nowhere darker, and lighter where the
    // box meets the plate.
    let glb = dir.join("box_on_plate.glb");
    let no_ao = dir.join("no-ao.png");
    let o = exec_line(size, &glb, &no_ao)
        .args(["--mode", "none"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let (with, without) = (
        image::open(dir.join("glb.png")).unwrap().to_rgba8(),
        image::open(&no_ao).unwrap().to_rgba8(),
    );
    assert_eq!(with.dimensions(), without.dimensions());
    let darker: Vec<i32> = with
        .pixels()
        .zip(without.pixels())
        .filter(|(a, _)| a.0[3] == 255)
        .map(|(a, b)| b.0[1] as i32 - a.0[1] as i32)
        .collect();
    let occluded = darker.iter().filter(|&&d| d > 24).count();
    assert!(
        occluded >= 20 && darker.iter().all(|&d| d >= -8),
        "{occluded} pixels darkened by the AO, the least {:?}",
        darker.iter().min()
    );
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A thumbnail run that gave up: it failed (with exit status `code` where given), saying `says`, within `limit` of
/// `t0`, writing no PNG (`png`) and leaving no temporary file in `dir`, which is then removed.
fn gave_up(
    o: &Output,
    code: Option<i32>,
    says: &str,
    (t0, limit): (Instant, Duration),
    (dir, png): (&Path, &Path),
) {
    let took = t0.elapsed();
    let t = text(o);
    match code {
        Some(c) => assert_eq!(o.status.code(), Some(c), "{t}"),
        None => assert!(!o.status.success(), "{t}"),
    }
    assert!(t.contains(says), "{t}");
    assert!(took < limit, "{took:?}");
    assert!(!png.exists());
    assert!(leftovers(dir).is_empty(), "{:?}", leftovers(dir));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_file_over_the_size_limit_gets_no_thumbnail() {
    let dir = tmp("too-big");
    // A sparse 300 MiB file: over the default --max-file-mb of 256, and refused before it is read.
    let big = dir.join("big.stl");
    std::fs::File::create(&big).unwrap().set_len(300 << 20).unwrap();
    let png = dir.join("big.png");
    let t0 = Instant::now();
    let o = exec_line(256, &big, &png).output().unwrap();
    gave_up(
        &o,
        None,
        "--max-file-mb",
        (t0, Duration::from_secs(10)),
        (&dir, &png),
    );
}

#[test]
fn a_render_over_the_time_limit_gets_no_thumbnail() {
    let dir = tmp("too-slow");
    let png = dir.join("racks.png");
    let t0 = Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        // Generating the racks alone takes longer than 0.2 s (94 ms for a quarter of them here; at --timeout 1
        // a warm shader cache let a quarter of them finish in 0.96 s).
        .args(["thumbnail", "--size", "64", "--timeout", "0.2"])
        .arg("gen:racks?rows=120&cols=200")
        .arg(&png)
        .output()
        .unwrap();
    let says = "no thumbnail within 0.2 s (--timeout)";
    gave_up(&o, Some(1), says, (t0, Duration::from_secs(6)), (&dir, &png));
}
