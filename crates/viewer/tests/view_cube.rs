//! The view cube and the Properties section with real X input (Xvfb + lavapipe): a click on the cube's top face
//! gives the top view (the picture key 7 gives, the box's footprint where the fit-all camera puts it) without
//! selecting anything, and a click on the box shows its triangles in the Properties section.
use std::path::Path;
use std::time::Duration;

mod common;
use common::*;

/// The box: 40 × 20 × 10 mm, Z up.
const MAX: [f32; 3] = [40.0, 20.0, 10.0];

/// Screenshot pixels that differ from the background, as a bounding box (x0, y0, x1, y1), inclusive; the
/// background of a row is its left edge's colour (the box stands clear of it).
fn foreground_box(png: &Path) -> (u32, u32, u32, u32) {
    let img = image::open(png).unwrap().to_rgb8();
    let mut b = (u32::MAX, u32::MAX, 0, 0);
    for y in 0..img.height() {
        let bg = img.get_pixel(0, y).0;
        for x in 0..img.width() {
            let p = img.get_pixel(x, y).0;
            if (0..3).any(|c| p[c].abs_diff(bg[c]) > 12) {
                b = (b.0.min(x), b.1.min(y), b.2.max(x), b.3.max(y));
            }
        }
    }
    b
}

/// The fraction of pixels whose colour differs by more than 40 in a channel (pictures of one size).
fn differing(a: &Path, b: &Path) -> f64 {
    let (a, b) = (
        image::open(a).unwrap().to_rgb8(),
        image::open(b).unwrap().to_rgb8(),
    );
    assert_eq!(a.dimensions(), b.dimensions());
    let n = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 40))
        .count();
    n as f64 / (a.width() * a.height()) as f64
}

/// Waits for the next "at rest" (the image converged after the last change), counted from `before`.
fn rest_after(v: &mut Running, before: usize) {
    v.wait_for("at rest", before + 1, Duration::from_secs(120));
}

/// F12, and the path of the new screenshot (the `n`-th).
fn shot(v: &mut Running, shots: &Path, n: usize) -> std::path::PathBuf {
    xdotool(&["key", "F12"]);
    wait_for_screenshots(shots, n, v);
    // Let the frame after the screenshot settle before the next step counts rests.
    std::thread::sleep(Duration::from_millis(1500));
    screenshots(shots)[n - 1].clone()
}

#[test]
fn clicking_the_cube_top_face_gives_the_top_view_and_properties_count_the_selection() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("view-cube");
    let shots = dir.join("screenshots");
    let stl = dir.join("box.stl");
    write_box_stl(&stl, [0.0; 3], MAX);
    // Seen from above, in front and to the right, off the diagonals: the middle of the cube is its top face.
    let cam = dir.join("cam.json");
    std::fs::write(
        &cam,
        r#"{"eye":[35,-15,65],"target":[20,10,5],"up":[0,0,1],"fov_y_deg":40,"width":520,"height":560}"#,
    )
    .unwrap();
    let mut v = Running::start_with(
        &[
            stl.to_str().unwrap(),
            "--camera",
            cam.to_str().unwrap(),
            "--up",
            "z",
            "--size",
            "820x420",
        ],
        &dir,
        &[("HRTAO_UI_PROBE", Some("1"))],
    );
    v.wait_for("ui probe: view cube at", 1, Duration::from_secs(90));
    rest_after(&mut v, 0);
    let window = v.focus_window();
    let start = shot(&mut v, &shots, 1);

    // Key 7: the top view, as the keys give it.
    let before = v.seen("at rest");
    xdotool(&["key", "7"]);
    rest_after(&mut v, before);
    let key7 = shot(&mut v, &shots, 2);

    // Back to the starting camera (Enter), then a click on the middle of the cube: its top face.
    let before = v.seen("at rest");
    xdotool(&["key", "Return"]);
    rest_after(&mut v, before);
    let cube = v.probed("view cube");
    let before = v.seen("at rest");
    v.click_until(&window, cube, "view cube: Top view", 1);
    rest_after(&mut v, before);
    let clicked = shot(&mut v, &shots, 3);
    assert_eq!(
        v.seen("selected instance") + v.seen("selection:"),
        0,
        "a click on the cube picks nothing in the scene:\n{}",
        v.log_text()
    );

    // The same picture as key 7's, and not the starting one.
    let same = differing(&key7, &clicked);
    let moved = differing(&start, &clicked);
    eprintln!("cube click vs key 7: {same:.4} of the pixels differ; vs the start: {moved:.4}");
    assert!(same < 0.01, "the cube's top view is key 7's: {same:.4} differ");
    assert!(moved > 0.02, "the view changed: {moved:.4} differ");

    // The footprint: the top view looks down -Z with +Y up and +X right, orthographic, the box's bounding sphere
    // filling the smaller extent of the view (nav::fit): 40 × 20 units centred.
    let (w, h) = image::image_dimensions(&clicked).unwrap();
    let radius = (MAX[0] * MAX[0] + MAX[1] * MAX[1] + MAX[2] * MAX[2]).sqrt() * 0.5;
    let view_height = 2.0 * radius / (w as f32 / h as f32).min(1.0);
    let px = h as f32 / view_height;
    let expect = (
        w as f32 * 0.5 - MAX[0] * 0.5 * px,
        h as f32 * 0.5 - MAX[1] * 0.5 * px,
        w as f32 * 0.5 + MAX[0] * 0.5 * px,
        h as f32 * 0.5 + MAX[1] * 0.5 * px,
    );
    let got = foreground_box(&clicked);
    eprintln!("footprint {got:?}, expected {expect:?} ({w}x{h})");
    for (g, e) in [
        (got.0, expect.0),
        (got.1, expect.1),
        (got.2, expect.2),
        (got.3, expect.3),
    ] {
        assert!(
            (g as f32 - e).abs() <= 4.0,
            "footprint {got:?}, expected {expect:?}"
        );
    }
    let start_box = foreground_box(&start);
    assert!(
        start_box.3.abs_diff(got.3) > 10 || start_box.1.abs_diff(got.1) > 10,
        "the starting view shows the box otherwise: {start_box:?}"
    );

    // A click on the box (the middle of the 3D view, left of the panel) selects it: Properties count its 12
    // triangles.
    xdotool(&["mousemove", "--window", &window, "0", "0"]);
    let centre = (w as i32 / 2, h as i32 / 2);
    v.click_until(&window, centre, "selected instance 0", 1);
    v.wait_for("ui probe: properties: triangles = 12", 1, Duration::from_secs(30));
    v.finish(&dir);
}
