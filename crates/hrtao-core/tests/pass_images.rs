//! Barriers only order passes: the AO of young, still and navigation frames of the bundled scene is the image
//! recorded before the frame's barriers were derived from the passes' declared accesses (when every dispatch was
//! followed by a full barrier): on any device within the spread of repeated runs (which pixel of a cell traces
//! its rays is decided by atomics, ray_target.glsl), and bit for bit on a CPU device run on one thread (lavapipe
//! with LP_NUM_THREADS=1, where the reference was recorded). `tests/data/pass_images.bin` (the paper's frames re-recorded when
//! `paper()` dropped our cell-size cap: bit-equal to the old ones with the cap kept; the defaults' frames when the
//! level blend was deleted, and when the still refinement's monotone cap took the exponent 1.5).
//!
//! Re-record (only for a change meant to change images, on lavapipe): `HRTAO_BLESS_PASS_IMAGES=1 cargo test -p
//! hrtao-core --test pass_images on_a_cpu`.
mod common;

use common::*;

use hrtao_core::{AoSettings, SceneGpu};

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
    let (scene, cam) = bundled(W, H);
    let sg = SceneGpu::new(gpu, &scene).unwrap();
    let mut r = Headless::new(gpu, W, H, settings).unwrap();
    five_frames(&mut r, &sg, &scene, &cam, |_, _| {})
}

const NAMES: [&str; 6] = [
    "defaults frame 1",
    "defaults frame 3",
    "defaults navigation",
    "paper frame 1",
    "paper frame 3",
    "paper navigation",
];

/// The tests of this file set LP_NUM_THREADS (or rely on its absence) when they create their device: one at a
/// time.
static DEVICE_ENV: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The six images (`NAMES`), each W x H, flattened.
fn rendered(gpu: &std::sync::Arc<hrtao_core::Gpu>) -> Vec<f32> {
    let defaults = {
        let mut s = AoSettings::default();
        s.map.ao_radius = R;
        s.map.hash_capacity = 1 << 17;
        s
    };
    let mut images = frames(gpu, defaults.clone());
    images.extend(frames(gpu, defaults.paper()));
    assert_clean(gpu);
    let flat: Vec<f32> = images.concat();
    assert_eq!(flat.len(), 6 * (W * H) as usize);
    assert!(
        flat.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
        "AO in [0, 1]"
    );
    flat
}

fn recorded() -> Vec<f32> {
    let path = reference_path();
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reference: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(reference.len(), 6 * (W * H) as usize, "reference size");
    reference
}

/// |a - b| per pixel: its mean and its 99th percentile.
fn differences(a: &[f32], b: &[f32]) -> (f32, f32) {
    let mut d: Vec<f32> = a.iter().zip(b).map(|(x, y)| (x - y).abs()).collect();
    d.sort_by(f32::total_cmp);
    let mean = d.iter().sum::<f32>() / d.len() as f32;
    (mean, d[(d.len() - 1) * 99 / 100])
}

/// Any device, any number of lavapipe threads: each image within twice the spread that the assignment of a
/// cell's QMC rays to its pixels (by atomics, ray_target.glsl) makes, measured against the one-thread reference
/// on lavapipe (2 cores):
/// - run to run with LP_NUM_THREADS unset, 6 runs: MAE up to 0.00067, 99th percentile of |AO - reference| up
///   to 0.019 (young frames mostly; which runs differ at all varies);
/// - every pixel's claims interleaved, as a GPU's thousands of threads may order them (the update cut into one
///   ray per pixel per dispatch, `Renderer::set_max_rays_per_dispatch`), on one thread and on all: MAE up to
///   0.0054 (paper frame 1), 99th percentile up to 0.064.
///
/// The tolerances are twice the latter.
#[test]
fn barriers_leave_images_within_the_spread_of_qmc_assignment() {
    let _env = DEVICE_ENV.lock().unwrap_or_else(|e| e.into_inner());
    let gpu = gpu();
    let (flat, reference) = (rendered(&gpu), recorded());
    let n = (W * H) as usize;
    let found: Vec<(f32, f32)> = (0..NAMES.len())
        .map(|k| differences(&flat[k * n..(k + 1) * n], &reference[k * n..(k + 1) * n]))
        .collect();
    for (name, (mae, p99)) in NAMES.iter().zip(&found) {
        eprintln!("{name}: MAE {mae}, 99th percentile {p99}");
    }
    for (name, &(mae, p99)) in NAMES.iter().zip(&found) {
        assert!(
            mae <= MAE_TOLERANCE && p99 <= P99_TOLERANCE,
            "{name}: MAE {mae}, 99th percentile {p99} from the recorded image (tolerances {MAE_TOLERANCE}, {P99_TOLERANCE})"
        );
    }
}

/// Twice the largest MAE of an image against the reference measured with every pixel's claims interleaved.
const MAE_TOLERANCE: f32 = 0.011;
/// Twice the largest 99th percentile of |AO - reference| in the same renders.
const P99_TOLERANCE: f32 = 0.13;

/// On a CPU device (lavapipe) run on one thread every frame is repeatable, and equals the recorded images bit for
/// bit; other devices (GPUs, whose atomics order differently in every run) skip it.
#[test]
fn on_a_cpu_device_with_one_thread_images_equal_the_recorded_ones() {
    let _env = DEVICE_ENV.lock().unwrap_or_else(|e| e.into_inner());
    // Lavapipe runs a dispatch's workgroups on several threads, and which pixel of a cell traces its rays is
    // decided by a race (ray_target.glsl): navigation frames then differ run to run by up to 0.24 in a pixel.
    // One thread makes every frame repeatable bit for bit (no effect on other drivers). Read when the device is
    // created: removed again after, for the other test.
    let before = std::env::var_os("LP_NUM_THREADS");
    std::env::set_var("LP_NUM_THREADS", "1");
    let gpu = gpu();
    match before {
        Some(v) => std::env::set_var("LP_NUM_THREADS", v),
        None => std::env::remove_var("LP_NUM_THREADS"),
    }
    if !gpu.info.is_software {
        eprintln!("skipped: {} is not a CPU device", gpu.info.name);
        return;
    }
    // Recorded with ray queries: the pipeline backend's invocations claim a cell's rays in another order, so its
    // frames differ bit for bit (6,201 pixels of the defaults' first frame, by up to 0.29, under
    // HRTAO_HIDE_RAY_QUERY=1) though they are as close to the references (the test above).
    if gpu.info.ray_backend != hrtao_core::RayBackend::Query {
        eprintln!(
            "skipped: {}: the recorded images are the ray-query backend's, this device traces with {:?}",
            gpu.info.name, gpu.info.ray_backend
        );
        return;
    }
    let flat = rendered(&gpu);
    let path = reference_path();
    if std::env::var_os("HRTAO_BLESS_PASS_IMAGES").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, bytemuck::cast_slice::<f32, u8>(&flat)).unwrap();
        return;
    }
    let reference = recorded();
    let n = (W * H) as usize;
    for (k, name) in NAMES.iter().enumerate() {
        let (a, b) = (&flat[k * n..(k + 1) * n], &reference[k * n..(k + 1) * n]);
        let worst = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        let differing = a.iter().zip(b).filter(|(x, y)| x != y).count();
        assert!(
            worst <= 1e-6,
            "{name}: {differing} pixels differ from the recorded image, by up to {worst}"
        );
    }
}
