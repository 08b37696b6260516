//! Feature edges: drawn at a known silhouette, absent on flat faces, never in the AO image.
mod common;
use common::*;
use hrtao_core::gpu::NO_INSTANCE;
use hrtao_core::SceneGpu;
use hrtao_scene::glam::Vec3;

/// A floor and a 4 x 4 x 2 box (its own instance) seen from above.
fn floor_and_box() -> hrtao_scene::Scene {
    let (h, a) = (2.0, 2.0);
    let sides = vec![
        quad(Vec3::new(0.0, 0.0, h), Vec3::X * a, Vec3::Y * a),
        quad(Vec3::new(a, 0.0, h / 2.0), Vec3::Y * a, Vec3::Z * h / 2.0),
        quad(Vec3::new(-a, 0.0, h / 2.0), Vec3::Y * a, Vec3::Z * h / 2.0),
        quad(Vec3::new(0.0, a, h / 2.0), Vec3::X * a, Vec3::Z * h / 2.0),
        quad(Vec3::new(0.0, -a, h / 2.0), Vec3::X * a, Vec3::Z * h / 2.0),
    ];
    floor_with_part("box", sides, Vec3::new(3.0, 1.0, 0.0))
}

#[test]
fn edges_outline_a_box_and_leave_flat_faces_and_ao_alone() {
    outline_check(&top_down_camera(20.0, 160, 90));
}

#[test]
fn orthographic_edges_outline_a_box_and_leave_flat_faces_alone() {
    // The same view in orthographic projection (its depth tests use the constant pixel size).
    let cam = top_down_camera(20.0, 160, 90).with_projection(hrtao_core::camera::Projection::Orthographic);
    outline_check(&cam);
}

fn outline_check(cam: &hrtao_core::Camera) {
    let gpu = gpu();
    let scene = floor_and_box();
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    // Per-pixel RTAO: deterministic, so the AO images can be compared exactly.
    let frame = |edges: bool| {
        let settings = {
            let mut s = rtao(4, 3.0);
            s.display.edges = edges;
            s
        };
        let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
        for _ in 0..2 {
            r.render(&sg, scene.f(), cam).unwrap();
        }
        (
            r.read_rgba().unwrap(),
            r.read_ao().unwrap(),
            r.read_gbuffer().unwrap(),
        )
    };
    let (with, ao_with, gb) = frame(true);
    let (without, ao_without, _) = frame(false);
    assert!(ao_with == ao_without, "edges never reach the AO image");
    let (w, hgt) = (cam.width as i32, cam.height as i32);
    let instance = |x: i32, y: i32| gb[(y.clamp(0, hgt - 1) * w + x.clamp(0, w - 1)) as usize].instance;
    let near_other_part = |x: i32, y: i32| {
        let me = instance(x, y);
        (-2..=2).any(|dy| (-2..=2).any(|dx| instance(x + dx, y + dy) != me))
    };
    let mut changed = 0;
    for y in 0..hgt {
        for x in 0..w {
            let i = (y * w + x) as usize * 4;
            if with[i..i + 3] != without[i..i + 3] {
                changed += 1;
                assert!(
                    near_other_part(x, y),
                    "pixel ({x}, {y}) darkened on a flat face away from any silhouette"
                );
                assert_ne!(
                    instance(x, y),
                    NO_INSTANCE,
                    "lines are drawn on the surface, not the background"
                );
            }
        }
    }
    // The box top spans about 17 pixels: its outline is some 70 pixels long.
    let box_pixels = gb.iter().filter(|p| p.instance == 1).count();
    println!("{changed} edge pixels around a box of {box_pixels} pixels");
    assert!(changed >= 50, "the silhouette is drawn ({changed} pixels)");
    assert!(changed < box_pixels, "only the outline, not the faces");
    assert_clean(&gpu);
}

/// Pixels whose colour the edges change, at internal size `w` x `h` in a view `view_height` pixels tall.
fn edge_pixels(
    gpu: &std::sync::Arc<hrtao_core::Gpu>,
    scene: &hrtao_scene::Scene,
    w: u32,
    h: u32,
    view_height: u32,
) -> usize {
    let cam = top_down_camera(10.0, w, h);
    let sg = SceneGpu::new(gpu, scene).unwrap();
    let image = |edges: bool| {
        let mut r = Headless::new(gpu, w, h, {
            let mut s = rtao(1, 3.0);
            s.display.edges = edges;
            s
        })
        .unwrap();
        r.view_height = view_height;
        r.render(&sg, scene.f(), &cam).unwrap();
        r.read_rgba().unwrap()
    };
    let (with, without) = (image(true), image(false));
    with.chunks(4)
        .zip(without.chunks(4))
        .filter(|(a, b)| a[..3] != b[..3])
        .count()
}

#[test]
fn edge_width_counts_view_pixels_at_any_render_scale() {
    let gpu = gpu();
    let scene = floor_and_box();
    // The same 160 x 90 view rendered at internal scale 1, 2 and 0.5.
    let base = edge_pixels(&gpu, &scene, 160, 90, 90);
    let double = edge_pixels(&gpu, &scene, 320, 180, 90);
    let half = edge_pixels(&gpu, &scene, 80, 45, 90);
    // At scale 1 of a 180-pixel view, lines are one internal pixel wide: twice as long, as wide.
    let thin = edge_pixels(&gpu, &scene, 320, 180, 180);
    println!("edge pixels: scale 1 {base}, scale 2 {double} (view 180: {thin}), scale 0.5 {half}");
    let ratio = double as f32 / base as f32;
    // Twice as long and twice as wide in internal pixels: the same lines in view pixels.
    assert!((3.2..=4.8).contains(&ratio), "scale 2 / scale 1 = {ratio}");
    let thin_ratio = thin as f32 / base as f32;
    assert!(
        (1.6..=2.4).contains(&thin_ratio),
        "one internal pixel at scale 1: {thin_ratio}"
    );
    // Below scale 1 a line cannot be thinner than one pixel: half as long.
    let half_ratio = half as f32 / base as f32;
    assert!(
        (0.35..=0.65).contains(&half_ratio),
        "scale 0.5 / scale 1 = {half_ratio}"
    );
    assert_clean(&gpu);
}
