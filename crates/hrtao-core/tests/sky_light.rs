//! The sky light (`LightSettings::sky_light`, shaders/sky.glsl) against the committed Cycles references of the
//! `--light-out` contract (testdata/refs/sky: rod and cycloidal at 160×90, Z-up, under `uniform`, `gradient` and
//! the generated lobe .hdr at rotations 0 and 90), validation on.
mod common;
use common::*;
use hrtao_core::camera::UpAxis;
use hrtao_core::metrics::{light_error, LightError};
use hrtao_core::{AoSettings, SceneGpu};

/// A view of the sky references: (environment setting, rotation, reference file).
fn views(key: &str) -> Vec<(String, f32, Vec<[f32; 3]>)> {
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(testdata("refs/sky/index.json")).unwrap()).unwrap();
    index[key]["views"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| {
            let env = v["environment"].as_str().unwrap();
            let env = match env {
                "uniform" | "gradient" => env.to_string(),
                name => testdata(&format!("env/{name}.hdr")).to_str().unwrap().to_string(),
            };
            let file = testdata(&format!("refs/sky/{}", v["file"].as_str().unwrap()));
            let (w, h, light) = hrtao_core::imageio::read_rgb(&file).unwrap();
            assert_eq!((w, h), (160, 90), "{}", file.display());
            (env, v["rotation_deg"].as_f64().unwrap() as f32, light)
        })
        .collect()
}

fn sky(rays: u32, radius: f32, environment: &str, rotation: f32) -> AoSettings {
    let mut s = hrtao(rays, radius);
    s.light.sky_light = true;
    s.light.environment = environment.to_string();
    s.light.environment_rotation = rotation;
    s.light.sky_up = UpAxis::Z;
    s.still.still_samples = 1024;
    s
}

/// Frame 1 and frame `frames` of a still view: the light's errors against `reference`.
fn run(
    r: &mut Headless,
    sg: &SceneGpu,
    f: u32,
    cam: &hrtao_core::Camera,
    frames: u32,
    reference: &[[f32; 3]],
) -> (LightError, LightError) {
    let mut first = LightError::default();
    for i in 0..frames {
        r.render(sg, f, cam).unwrap();
        if i == 0 {
            first = light_error(&r.read_light().unwrap(), reference);
        }
    }
    (first, light_error(&r.read_light().unwrap(), reference))
}

/// Every committed view (the rotation-invariant `uniform` and `gradient` at 0 only): after 32 still frames at 8
/// rays per pixel MAE ≤ 0.01 under `uniform` and MAE ÷ the reference's mean ≤ 0.02 under the others; the first
/// frame within 1.5× the AO mode's first-frame MAE on the same view (against its own Cycles reference).
/// Measured: frame 32 uniform 0.0054–0.0055, relative 0.006–0.009 (gradient), 0.0095–0.015 (the lobe, whose
/// band-3 truncation is most of it); frame 1 0.73–1.28× the AO's (before the transfer came from coarser cells
/// in a young map and the own rays took the AO's weight: 0.81–1.49×).
#[test]
fn sky_light_converges_to_cycles_and_starts_as_close_as_the_ao() {
    let gpu = gpu();
    for key in REFERENCE_SCENES {
        let (scene, cam, radius) = shared_scene(key, 160, 90);
        let sg = SceneGpu::new(&gpu, &scene).unwrap();
        let ao_first = {
            let mut r = Headless::new(&gpu, cam.width, cam.height, hrtao(8, radius)).unwrap();
            r.render(&sg, scene.f(), &cam).unwrap();
            mae(&r.read_ao().unwrap(), &cycles_ref(key, 160, 90))
        };
        for (env, rotation, reference) in views(key) {
            if rotation != 0.0 && !env.ends_with(".hdr") {
                continue;
            }
            // A still image of 32 frames: its final image is the 32nd frame's (the own rays' weight reaches
            // the AO's final es / (k + es) there, composite.comp `monotone_weight`).
            let mut settings = sky(8, radius, &env, rotation);
            settings.still.still_samples = 32 * 8;
            let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
            let (first, last) = run(&mut r, &sg, scene.f(), &cam, 32, &reference);
            let name = format!("{key} {} at {rotation}°", env.rsplit('/').next().unwrap());
            println!(
                "{name}: frame 1 MAE {:.4} (AO {ao_first:.4}), frame 32 MAE {:.4}, relative {:.4}",
                first.mae,
                last.mae,
                last.relative()
            );
            assert!(
                first.pixels > 1000,
                "{name}: the model covers {} pixels",
                first.pixels
            );
            assert!(
                first.mae as f32 <= 1.5 * ao_first,
                "{name}: first frame MAE {} against the AO's {ao_first}",
                first.mae
            );
            if env == "uniform" {
                assert!(last.mae <= 0.01, "{name}: frame 32 MAE {}", last.mae);
            } else {
                assert!(
                    last.relative() <= 0.02,
                    "{name}: frame 32 relative MAE {}",
                    last.relative()
                );
            }
        }
    }
    assert_clean(&gpu);
}

/// Rotation is free: turning the lobe environment by 90° at frame 16 traces, frame for frame, the rays of a run
/// that never turns it (within 1 %), keeps the still image accumulating, and its frame 48 is within 1.2× the
/// error of a fresh 48-frame render at 90° against the 90° reference.
#[test]
fn turning_the_environment_traces_no_new_rays() {
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("rod", 160, 90);
    let lobe = testdata("env/sky_lobe_64x32.hdr").to_str().unwrap().to_string();
    let reference = views("rod")
        .into_iter()
        .find(|(env, rot, _)| *env == lobe && *rot == 90.0)
        .unwrap()
        .2;
    let frames = |turn_at: Option<u32>| {
        let start = if turn_at.is_some() { 0.0 } else { 90.0 };
        let mut r = Headless::new(&gpu, cam.width, cam.height, sky(8, radius, &lobe, start)).unwrap();
        let mut reports = Vec::new();
        for i in 0..48 {
            if Some(i) == turn_at {
                let mut s = r.settings.clone();
                s.light.environment_rotation = 90.0;
                r.set_settings(s).unwrap();
            }
            reports.push(r.render(&sg, scene.f(), &cam).unwrap());
        }
        (reports, light_error(&r.read_light().unwrap(), &reference))
    };
    let (turned, turned_error) = frames(Some(16));
    let (fresh, fresh_error) = frames(None);
    println!(
        "frame 48 MAE: turned at 16 {:.4}, fresh {:.4}",
        turned_error.mae, fresh_error.mae
    );
    for (i, (a, b)) in turned.iter().zip(&fresh).enumerate() {
        let (a, b) = (a.rays as f64, b.rays as f64);
        assert!(
            (a - b).abs() <= 0.01 * b.max(1.0),
            "frame {i}: {a} rays against {b}"
        );
    }
    assert_eq!(
        turned[16].accumulated_frames,
        turned[15].accumulated_frames + 1,
        "the still image goes on accumulating through the turn"
    );
    assert!(
        turned_error.mae <= 1.2 * fresh_error.mae,
        "turned {} against fresh {}",
        turned_error.mae,
        fresh_error.mae
    );
    assert_clean(&gpu);
}

/// An environment that cannot be read is a clear error of the frame, and the renderer renders on once it is
/// fixed; asking for the light of a frame that was not lit by the sky is an error too.
#[test]
fn a_missing_environment_is_a_clear_error() {
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("rod", 160, 90);
    let mut r = Headless::new(&gpu, 32, 18, hrtao(2, radius)).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    assert!(r.read_light().is_err(), "the AO look has no sky light to read");
    r.set_settings(sky(2, radius, "/nonexistent/sky.hdr", 0.0))
        .unwrap();
    let err = r.render(&sg, scene.f(), &cam).unwrap_err().to_string();
    assert!(err.contains("/nonexistent/sky.hdr"), "{err}");
    r.set_settings(sky(2, radius, "uniform", 0.0)).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    let light = r.read_light().unwrap();
    assert!(
        light.iter().any(|p| p[0] > 0.2),
        "lit once the environment is readable"
    );
    assert_clean(&gpu);
}
