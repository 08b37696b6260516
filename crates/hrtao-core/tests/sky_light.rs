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

#[test]
fn sky_light_matches_cycles() {
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
            let mut r = Headless::new(&gpu, cam.width, cam.height, sky(8, radius, &env, rotation)).unwrap();
            let (first, last) = run(&mut r, &sg, scene.f(), &cam, 32, &reference);
            println!(
                "{key} {} {rotation}: frame 1 MAE {:.4} (AO {ao_first:.4}), frame 32 MAE {:.4} rel {:.4} (ref mean {:.3})",
                env.rsplit('/').next().unwrap(),
                first.mae,
                last.mae,
                last.relative(),
                last.reference_mean
            );
        }
    }
    assert_clean(&gpu);
}
