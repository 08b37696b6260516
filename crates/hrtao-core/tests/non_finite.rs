//! The non-finite guard (common.glsl `finite_or_count`, sky.glsl `sky_finite`): no NaN or infinity enters the
//! map's sums or the still accumulation, whatever a device returns where GLSL leaves a result undefined.
mod common;

use common::*;
use hrtao_core::camera::UpAxis;
use hrtao_core::AoSettings;
use hrtao_scene::glam::Vec3;

/// A Y-up floor whose up-facing normals are exactly (0, 1, 0) (axis-aligned edges: the cross product has no
/// rounding), with a block standing on it, seen from above at an angle.
fn y_up_floor() -> (hrtao_scene::Scene, hrtao_core::Camera) {
    let mut scene = scene_of(vec![quad(Vec3::ZERO, Vec3::Z * 10.0, Vec3::X * 10.0)]);
    add_part(
        &mut scene,
        "block",
        vec![cube(Vec3::ONE)],
        Vec3::new(0.0, 1.0, 0.0),
    );
    let camera =
        hrtao_core::Camera::perspective([3.0, 7.0, 6.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 50.0, (96, 64));
    (scene, camera)
}

fn sky_settings() -> AoSettings {
    let mut s = hrtao(8, 1.0);
    s.light.sky_light = true;
    s.light.environment = "gradient".to_string();
    s.light.sky_up = UpAxis::Y;
    s
}

/// The first frame (rays still young: pixels without cells light as open surfaces, whose transfer is the sky
/// basis at their normal, the pole of a Y-up sky frame) and a few still frames. Returns each frame's light and
/// its count of values the guard replaced.
fn frames(inject: bool) -> Vec<(Vec<[f32; 3]>, u32)> {
    let gpu = gpu();
    let (scene, cam) = y_up_floor();
    let sg = hrtao_core::SceneGpu::new(&gpu, &scene).expect("scene upload");
    let mut r = Headless::new(&gpu, cam.width, cam.height, sky_settings()).expect("renderer");
    r.set_inject_pole_nan(inject);
    // A moving frame's fraction of the pixels trace (one in 16, as a viewer's smallest budget): the cells of
    // the others hold no rays yet, and they light as open surfaces.
    r.budget = Some(hrtao_core::RayBudget {
        rays_per_pixel: 1,
        trace_fraction: 1.0 / 16.0,
    });
    let out = (0..3)
        .map(|_| {
            let report = r.render(&sg, scene.f(), &cam).expect("frame");
            (r.read_light().expect("light"), report.non_finite)
        })
        .collect();
    assert_clean(&gpu);
    out
}

/// Every light value is finite on a Y-up floor, also when the pole's azimuth comes out NaN (as atan(0, 0) may
/// on a GPU; injected by `Renderer::set_inject_pole_nan`): the guard replaces what it finds, counts it, and the
/// image is the sound one (at the pole the azimuthal terms are 0 anyway). Without the guard the injected frames
/// show black pixels and a darker image (checked when the guard was written: mean light 1.84 against 1.88).
#[test]
fn the_sky_light_stays_finite_when_the_pole_gives_nan() {
    let sound = frames(false);
    let injected = frames(true);
    for (frame, ((light, non_finite), (nan_light, _))) in sound.iter().zip(&injected).enumerate() {
        assert_eq!(
            *non_finite, 0,
            "frame {frame}: a sound build finds nothing non-finite"
        );
        for (what, l) in [("sound", light), ("injected", nan_light)] {
            let bad = l.iter().filter(|p| p.iter().any(|v| !v.is_finite())).count();
            assert_eq!(bad, 0, "frame {frame} ({what}): {bad} pixels of non-finite light");
        }
        // A NaN light shows black (GLSL's max(NaN, 0) is 0 here): every pixel the sound image lights is lit.
        let lit = |l: &[[f32; 3]]| l.iter().filter(|p| p.iter().any(|v| *v > 0.0)).count();
        let (lit, nan_lit) = (lit(light), lit(nan_light));
        assert!(
            lit > light.len() / 2,
            "frame {frame}: the floor and block are lit ({lit} pixels)"
        );
        assert!(
            nan_lit + 2 >= lit,
            "frame {frame}: {lit} pixels lit, {nan_lit} with the NaN injected"
        );
        // Frames of the same view differ run to run (which pixel claims a cell first): the guarded image is
        // the sound one on the whole, not pixel by pixel.
        let mean = |l: &[[f32; 3]]| l.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / l.len() as f32;
        let (a, b) = (mean(light), mean(nan_light));
        assert!(
            (a - b).abs() <= 0.01 * a,
            "frame {frame}: mean light {a} sound, {b} guarded"
        );
    }
    assert!(
        injected[0].1 > 0,
        "the first frame's open transfers reach the pole: the guard counted the injected NaN"
    );
}
