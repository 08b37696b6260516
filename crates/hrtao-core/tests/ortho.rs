//! Orthographic projection: the silhouette of a box has its analytic extent (ray queries and the rasteriser
//! alike), eq. 2 no longer depends on the distance, and HRTAO converges to per-pixel RTAO of the same camera.
mod common;
use common::*;
use hrtao_core::camera::Projection;
use hrtao_core::gpu::NO_INSTANCE;
use hrtao_core::{Camera, Primary, SceneGpu};
use hrtao_scene::glam::Vec3;

/// A closed box `2 a.x x 2 a.y x 2 a.z` centred at `c`.
fn box_prims(c: Vec3, a: Vec3) -> Vec<hrtao_scene::Primitive> {
    let (x, y, z) = (Vec3::X * a.x, Vec3::Y * a.y, Vec3::Z * a.z);
    vec![
        quad(c + z, x, y),
        quad(c - z, x, y),
        quad(c + x, y, z),
        quad(c - x, y, z),
        quad(c + y, x, z),
        quad(c - y, x, z),
    ]
}

fn ortho_top_down(eye_height: f32, ortho_height: f32, w: u32, h: u32) -> Camera {
    Camera {
        projection: Projection::Orthographic,
        ortho_height,
        ..top_down_camera(eye_height, w, h)
    }
}

#[test]
fn orthographic_box_silhouette_has_its_analytic_extent() {
    let gpu = gpu();
    // A 2 x 1 x 3 box (top at z = 3) seen straight down: its silhouette is its 2 x 1 top face.
    let scene = scene_of(box_prims(Vec3::new(0.0, 0.0, 1.5), Vec3::new(1.0, 0.5, 1.5)));
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    // 64 pixels span 4 world units: the box covers 32 x 16 pixel centres, at any eye height, even with the eye
    // inside the box (orthographic rays start in front of the scene bounds: nothing is clipped).
    let hits = |cam: &Camera, primary: Primary| {
        let mut r = Headless::new(&gpu, cam.width, cam.height, rtao(1, 1.0)).unwrap();
        r.set_primary(primary);
        r.render(&sg, scene.f(), cam).unwrap();
        r.read_gbuffer().unwrap()
    };
    for primary in [Primary::RayQuery, Primary::Raster] {
        for eye_height in [1.0, 3.5, 10.0, 400.0] {
            let cam = ortho_top_down(eye_height, 4.0, 64, 64);
            let gb = hits(&cam, primary);
            let covered: Vec<usize> = (0..gb.len()).filter(|&i| gb[i].instance != NO_INSTANCE).collect();
            assert_eq!(
                covered.len(),
                32 * 16,
                "{primary:?}, eye at {eye_height}: {} pixels covered",
                covered.len()
            );
            // Every hit is on the top face, at its distance from the eye plane (just above the top of the bounds
            // when the eye is inside them), with the normal facing up.
            for &i in &covered {
                let p = gb[i];
                assert!((p.position[2] - 3.0).abs() < 1e-4, "{:?}", p.position);
                if eye_height > 3.0 {
                    assert!((p.t - (eye_height - 3.0)).abs() < 1e-3 * eye_height, "t {}", p.t);
                } else {
                    assert!(p.t > 0.0 && p.t < 0.1, "t {}", p.t);
                }
                assert!(p.normal[2] > 0.999);
            }
            // The covered pixels form the centred 32 x 16 rectangle (x across, y = world -y down the image).
            let (x0, y0) = ((covered[0] % 64) as i32, (covered[0] / 64) as i32);
            assert_eq!((x0, y0), (16, 24), "{primary:?}: top-left covered pixel");
        }
    }
    // A perspective camera at the same eye height sees the near top face larger: ortho is really in use.
    let persp = hits(&top_down_camera(10.0, 64, 64), Primary::RayQuery);
    assert_ne!(
        persp.iter().filter(|p| p.instance != NO_INSTANCE).count(),
        32 * 16
    );
    assert_clean(&gpu);
}

#[test]
fn orthographic_feature_size_does_not_depend_on_distance() {
    let gpu = gpu();
    let settings = hrtao(4, 2.0);
    let r = Headless::new(&gpu, 64, 64, settings.clone()).unwrap();
    let sg = SceneGpu::new(&gpu, &scene_of(vec![floor()])).unwrap();
    let px = |t: f32| hrtao_core::gpu::GPixel {
        position: [0.3, 0.2, 0.0],
        t,
        normal: [0.0, 0.0, 1.0],
        instance: 0,
        color: 0xffff_ffff,
        flags: 0,
        shading: hrtao_core::gpu::pack_normal([0.0, 0.0, 1.0]),
    };
    // Orthographic: the same cell at 1 and 1000 units from the eye plane; its size is s_p ortho_height / R_y.
    let cam = ortho_top_down(10.0, 4.0, 64, 64);
    assert_eq!(
        r.pixel_cell_keys(&sg, &cam, 0, &px(1.0)),
        r.pixel_cell_keys(&sg, &cam, 0, &px(1000.0))
    );
    let s_w = settings.map.s_p * 4.0 / 64.0;
    let size = hrtao_core::hash::FeatureSize::for_camera(&cam, 64, settings.map.s_p);
    assert_eq!(size.at(1.0), s_w);
    assert_eq!(size.at(1000.0), s_w);
    // Perspective: the cells grow with the distance.
    let persp = top_down_camera(10.0, 64, 64);
    assert_ne!(
        r.pixel_cell_keys(&sg, &persp, 0, &px(1.0)),
        r.pixel_cell_keys(&sg, &persp, 0, &px(1000.0))
    );
    assert_clean(&gpu);
}

#[test]
fn orthographic_hrtao_converges_to_orthographic_rtao() {
    let gpu = gpu();
    let (scene, persp, radius) = shared_scene("rod", 160, 90);
    let cam = persp.with_projection(Projection::Orthographic);
    let reference = reference(&gpu, &scene, &cam, radius, 64, 4);
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    let mut r = Headless::new(&gpu, cam.width, cam.height, hrtao(4, radius)).unwrap();
    let mut errors = Vec::new();
    for _ in 0..16 {
        r.render(&sg, scene.f(), &cam).unwrap();
        errors.push(mae(&r.read_ao().unwrap(), &reference));
    }
    let gb = r.read_gbuffer().unwrap();
    let covered = gb.iter().filter(|p| p.t >= 0.0).count();
    println!(
        "orthographic rod, {covered} of {} pixels covered: HRTAO MAE vs RTAO reference over 16 frames {errors:.4?}",
        gb.len()
    );
    assert!(covered > gb.len() / 10, "the framing keeps the part in view");
    // The GPU's cells are the CPU mirror's keys for the orthographic eq. 2.
    check_map(&r, &sg, &cam, scene.f(), None);
    assert!(errors[15] <= 0.02, "MAE after 16 frames: {}", errors[15]);
    assert!(errors[15] < errors[0], "{errors:?}");
    assert_clean(&gpu);
}
