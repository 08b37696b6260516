//! Barriers only order passes: the AO of young, still and navigation frames of the bundled scene equals the
//! images recorded before the frame's barriers were derived from the passes' declared accesses (when every
//! dispatch was followed by a full barrier): `tests/data/pass_images.bin` (the paper's frames re-recorded when
//! `paper()` dropped our cell-size cap: bit-equal to the old ones with the cap kept; the defaults' frames when the
//! level blend was deleted, and when the still refinement's monotone cap took the exponent 1.5).
//!
//! Re-record (only for a change meant to change images): `HRTAO_BLESS_PASS_IMAGES=1 cargo test -p hrtao-core
//! --test pass_images`.
mod common;

use common::*;

use hrtao_core::{AoSettings, Camera, SceneGpu};

/// The AO radius used with the bundled scene (assets/README.md).
const R: f32 = 8.0;
const W: u32 = 160;
const H: u32 = 90;

fn reference_path() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pass_images.bin")
}

/// Per setting: the AO of frame 1 (a young map), frame 3 (still frames on a settling map) and frame 5 (the
/// second frame of a moving camera: navigation over a settled map).
fn frames(gpu: &std::sync::Arc<hrtao_core::Gpu>, settings: AoSettings) -> Vec<Vec<f32>> {
    let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let scene = hrtao_scene::load(assets.join("default.glb").to_str().unwrap(), &mut |_| {}).unwrap();
    let cam = Camera {
        width: W,
        height: H,
        ..Camera::load(&assets.join("default.camera.json")).unwrap()
    };
    let sg = SceneGpu::new(gpu, &scene).unwrap();
    let mut r = Headless::new(gpu, W, H, settings).unwrap();
    let mut out = Vec::new();
    for i in 0..5u32 {
        let mut c = cam;
        if i >= 3 {
            // Orbit a little: a new view every frame.
            c.eye[0] += 0.5 * (i - 2) as f32;
        }
        let report = r.render(&sg, scene.f(), &c).unwrap();
        assert!(report.rays > 0, "frame {i} traced rays");
        if matches!(i, 0 | 2 | 4) {
            out.push(r.read_ao().unwrap());
        }
    }
    out
}

#[test]
fn barriers_leave_images_unchanged() {
    // Lavapipe runs a dispatch's workgroups on several threads, and which pixel of a cell traces its rays is
    // decided by a race (ray_target.glsl): navigation frames then differ run to run by up to 0.24 in a pixel.
    // One thread makes every frame repeatable bit for bit (no effect on other drivers).
    std::env::set_var("LP_NUM_THREADS", "1");
    let gpu = gpu();
    let defaults = {
        let mut s = AoSettings::default();
        s.map.ao_radius = R;
        s.map.hash_capacity = 1 << 17;
        s
    };
    let mut images = frames(&gpu, defaults.clone());
    images.extend(frames(&gpu, defaults.paper()));
    assert_clean(&gpu);
    let flat: Vec<f32> = images.concat();
    assert_eq!(flat.len(), 6 * (W * H) as usize);
    assert!(
        flat.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
        "AO in [0, 1]"
    );
    let path = reference_path();
    if std::env::var_os("HRTAO_BLESS_PASS_IMAGES").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, bytemuck::cast_slice::<f32, u8>(&flat)).unwrap();
        return;
    }
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reference: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(reference.len(), flat.len(), "reference size");
    let names = [
        "defaults frame 1",
        "defaults frame 3",
        "defaults navigation",
        "paper frame 1",
        "paper frame 3",
        "paper navigation",
    ];
    let n = (W * H) as usize;
    for (k, name) in names.iter().enumerate() {
        let (a, b) = (&flat[k * n..(k + 1) * n], &reference[k * n..(k + 1) * n]);
        let worst = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        let differing = a.iter().zip(b).filter(|(x, y)| x != y).count();
        assert!(
            worst <= 1e-6,
            "{name}: {differing} pixels differ from the recorded image, by up to {worst}"
        );
    }
}
