//! Feature edges: drawn at a known silhouette, absent on flat faces, never in the AO image.
mod common;
use common::*;
use hrtao_core::gpu::NO_INSTANCE;
use hrtao_core::{AoSettings, Renderer, SceneGpu};
use hrtao_scene::glam::{Mat4, Vec3};
use hrtao_scene::{Instance, Mesh};

#[test]
fn edges_outline_a_box_and_leave_flat_faces_and_ao_alone() {
    let gpu = gpu();
    // A floor and a 4 x 4 x 2 box (its own instance) seen from above.
    let mut scene = scene_of(vec![floor()]);
    let (h, a) = (2.0, 2.0);
    let sides = vec![
        quad(Vec3::new(0.0, 0.0, h), Vec3::X * a, Vec3::Y * a),
        quad(Vec3::new(a, 0.0, h / 2.0), Vec3::Y * a, Vec3::Z * h / 2.0),
        quad(Vec3::new(-a, 0.0, h / 2.0), Vec3::Y * a, Vec3::Z * h / 2.0),
        quad(Vec3::new(0.0, a, h / 2.0), Vec3::X * a, Vec3::Z * h / 2.0),
        quad(Vec3::new(0.0, -a, h / 2.0), Vec3::X * a, Vec3::Z * h / 2.0),
    ];
    scene.meshes.push(Mesh {
        name: "box".into(),
        primitives: sides,
    });
    scene.instances.push(Instance {
        mesh: 1,
        transform: Mat4::from_translation(Vec3::new(3.0, 1.0, 0.0)),
        name: "box".into(),
        visible: true,
    });
    let cam = top_down_camera(20.0, 160, 90);
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    // Per-pixel RTAO: deterministic, so the AO images can be compared exactly.
    let frame = |edges: bool| {
        let settings = AoSettings {
            edges,
            ..rtao(4, 3.0)
        };
        let mut r = Renderer::new(&gpu, cam.width, cam.height, settings).unwrap();
        for _ in 0..2 {
            r.render(&sg, scene.f(), &cam).unwrap();
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
