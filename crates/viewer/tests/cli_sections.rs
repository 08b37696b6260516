//! `hrtao render --section`: a plane cutting one of two boxes away gives the image of the scene without it, a
//! plane through a box shows the section colour, and bad planes give clear errors.
use std::path::{Path, PathBuf};
use std::process::Command;

mod cli;
mod common;

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-cli-sections-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Closed, outward-facing boxes (min, max) as OBJ, with a floor quad at z = 0 for x in -6..0.
fn write_obj(path: &Path, boxes: &[([f32; 3], [f32; 3])]) {
    let boxes: Vec<_> = boxes.iter().map(|(lo, hi)| ("", *lo, *hi)).collect();
    let s = "v -6 -6 0\nv 0 -6 0\nv 0 6 0\nv -6 6 0\nf 1 2 3 4\n".to_string() + &common::boxes_obj(&boxes, 4);
    std::fs::write(path, s).unwrap();
}

fn render(obj: &Path, camera: &Path, sections: &[&str], tag: &str) -> (Vec<f32>, image::RgbaImage) {
    let (pfm, png) = (dir().join(format!("{tag}.pfm")), dir().join(format!("{tag}.png")));
    let mut args = vec![
        "render".to_string(),
        "--scene".into(),
        obj.display().to_string(),
        "--camera".into(),
        camera.display().to_string(),
        "--mode".into(),
        "rtao".into(),
        "--radius".into(),
        "3".into(),
        "--rays".into(),
        "16".into(),
        "--ao-out".into(),
        pfm.display().to_string(),
        "--out".into(),
        png.display().to_string(),
    ];
    for s in sections {
        args.push("--section".into());
        args.push(s.to_string());
    }
    cli::hrtao_ok(&args);
    let (_, _, ao) = hrtao_core::imageio::read_pfm(&pfm).unwrap();
    (ao, image::open(&png).unwrap().to_rgba8())
}

fn mean_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32
}

/// Pixels whose colours differ by more than 8 in a channel.
fn differing(a: &image::RgbaImage, b: &image::RgbaImage) -> usize {
    a.pixels()
        .zip(b.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 8))
        .count()
}

fn section_coloured(img: &image::RgbaImage) -> usize {
    img.pixels()
        .filter(|p| p[0] as i32 > p[1] as i32 + 60 && p[0] as i32 > p[2] as i32 + 60)
        .count()
}

#[test]
fn render_section_cuts_geometry_and_shows_caps() {
    let d = dir();
    let a = ([-2.5, -1.0, 0.01], [-0.5, 1.0, 2.0]);
    let b = ([0.5, -1.0, 0.01], [2.5, 1.0, 3.0]);
    let (both, only_a) = (d.join("both.obj"), d.join("only_a.obj"));
    write_obj(&both, &[a, b]);
    write_obj(&only_a, &[a]);
    let camera = d.join("camera.json");
    std::fs::write(
        &camera,
        r#"{"eye":[1,-9,8],"target":[0,0,1],"up":[0,0,1],"fov_y_deg":45,"width":120,"height":80}"#,
    )
    .unwrap();

    let (uncut, img_uncut) = render(&both, &camera, &[], "uncut");
    let (reference, img_reference) = render(&only_a, &camera, &[], "reference");
    // x > 0.2 cuts B away and spares A and the floor.
    let (cut, img_cut) = render(&both, &camera, &["1,0,0,0.2"], "cut");
    let b_pixels = differing(&img_uncut, &img_reference);
    assert!(b_pixels > 300, "B is in the image: {b_pixels} pixels");
    assert!(mean_abs_diff(&uncut, &reference) > 0.001, "B shades A");
    let e = mean_abs_diff(&cut, &reference);
    assert!(
        e < 0.0005,
        "with B cut away the AO is that of the scene without B: {e}"
    );
    let left = differing(&img_cut, &img_reference);
    assert!(
        left < 20,
        "with B cut away the image is that of the scene without B: {left} pixels differ"
    );

    // Planes through both boxes at z = 1: cutting z > 1 opens them to the camera above (two caps); cutting
    // z < 1 (a negative normal) leaves caps that face down, out of sight.
    let (_, img_top) = render(&both, &camera, &["0,0,1,1"], "top_cut");
    let (_, img_bottom) = render(&both, &camera, &["0,0,-1,-1"], "bottom_cut");
    assert_eq!(
        section_coloured(&img_uncut),
        0,
        "no section colour without a plane"
    );
    assert!(
        section_coloured(&img_top) > 200,
        "caps: {}",
        section_coloured(&img_top)
    );
    assert_eq!(
        section_coloured(&img_bottom),
        0,
        "the caps of a bottom cut face away"
    );
    // Repeatable: two planes.
    let (_, img_two) = render(&both, &camera, &["0,0,1,1", "1,0,0,0.2"], "two");
    let two = section_coloured(&img_two);
    assert!(
        two > 100 && two < section_coloured(&img_top),
        "one cap left: {two}"
    );
}

#[test]
fn bad_sections_give_clear_errors() {
    for (args, needle) in [
        (vec!["--section", "1,0,0"], "four numbers"),
        (vec!["--section", "0,0,0,1"], "non-zero normal"),
        (vec!["--section", "1,0,x,1"], "section"),
        (
            vec![
                "--section",
                "1,0,0,0",
                "--section",
                "0,1,0,0",
                "--section",
                "0,0,1,0",
                "--section",
                "1,1,0,0",
            ],
            "at most 3",
        ),
    ] {
        let mut all = vec!["render", "--scene", "gen:box", "--width", "16", "--height", "16"];
        all.extend(args);
        let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .args(&all)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && !err.contains("panicked"),
            "{all:?}: {err}"
        );
        assert!(err.contains(needle), "{all:?} should mention `{needle}`: {err}");
    }
}
