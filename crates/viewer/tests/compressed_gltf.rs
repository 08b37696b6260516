//! rod.glb compressed by gltfpack (meshopt) and gltf-pipeline (Draco), and written as 3MF, renders the AO of
//! rod.glb: per-pixel RTAO (each pixel's own deterministic ray sequence) of the files from one camera,
//! MAE ≤ 0.005.
use std::path::{Path, PathBuf};

mod common;
#[path = "../../scene/tests/common/threemf.rs"]
mod threemf_writer;

fn rod(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/scenes/rod_assembly")
        .join(name)
}

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-compressed-ao-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `hrtao render --mode rtao` of `scene` from `camera`: the linear AO image.
fn render(scene: &Path, camera: &Path, radius: f32) -> Vec<f32> {
    common::render_rtao(scene, camera, radius, (16, 8), &dir())
}

#[test]
fn compressed_and_3mf_rod_render_the_ao_of_rod() {
    // A camera on the model's diagonal, from rod.glb's bounds; the AO radius a tenth of its size.
    let scene = hrtao_scene::load(rod("rod.glb").to_str().unwrap(), &mut |_| {}).unwrap();
    let b = scene.bounds();
    let (lo, hi) = (b.min, b.max);
    let (centre, size) = ((lo + hi) / 2.0, (hi - lo).length());
    let eye = centre + glam::Vec3::new(0.6, -0.9, 0.5).normalize() * size * 1.1;
    let camera = dir().join("rod.camera.json");
    let json = serde_json::json!({"eye": eye.to_array(), "target": centre.to_array(), "up": [0, 0, 1],
        "fov_y_deg": 40, "width": 320, "height": 180});
    std::fs::write(&camera, json.to_string()).unwrap();
    let radius = size / 10.0;
    let plain = render(&rod("rod.glb"), &camera, radius);
    let occluded = plain.iter().filter(|&&v| v < 0.9).count();
    assert!(occluded > 2000, "the view shows occlusion ({occluded} pixels)");
    // rod.glb as 3MF: its 29 instances as build items of 3 objects.
    let as_3mf = dir().join("rod.3mf");
    threemf_writer::write_3mf(&scene, &as_3mf, "millimeter");
    let loaded = hrtao_scene::load(as_3mf.to_str().unwrap(), &mut |_| {}).unwrap();
    assert_eq!((loaded.instances.len(), loaded.meshes.len()), (29, 3));
    for path in [rod("rod.meshopt.glb"), rod("rod.draco.glb"), as_3mf] {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let ao = render(&path, &camera, radius);
        let e = hrtao_core::metrics::ao_error(&ao, &plain);
        println!("{name}: MAE {:.4} over {} pixels", e.mae, e.pixels);
        assert!(e.mae <= 0.005, "{name}: MAE {} against rod.glb", e.mae);
    }
}
