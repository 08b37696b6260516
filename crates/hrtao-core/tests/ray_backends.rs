//! The two ways to trace (`RayBackend`: ray queries in compute shaders, or ray-tracing pipelines launched over
//! the same threads, trace.glsl) give the same frames: every pass that traces — primary visibility
//! (primary.comp), per-pixel RTAO (rtao.comp) and the cache's ray-tracing update (ao_update.comp, with the
//! near-field classification and adaptive sampling of our defaults, and the paper's plain first-hit rays) — on the
//! bundled scene, validation (synchronization validation included) silent under both. And the device decides: a
//! device without ray queries (the feature masked) picks the pipelines by itself. On a device without ray queries
//! (a pipelines-only GPU, or `HRTAO_HIDE_RAY_QUERY=1`) the parts that need them are skipped with a message
//! (`common::ray_queries_or_skip`).
mod common;

use std::sync::Arc;

use common::*;
use hrtao_core::{AoSettings, ContextOptions, Gpu, Primary, RayBackend, SceneGpu};

/// The AO radius used with the bundled scene (assets/README.md).
const R: f32 = 8.0;
const W: u32 = 160;
const H: u32 = 90;

fn device(ray_backend: Option<RayBackend>, mask_ray_query: bool) -> hrtao_core::Result<Arc<Gpu>> {
    let _ = env_logger::builder().is_test(true).try_init();
    Gpu::new(&ContextOptions {
        validation: true,
        device: std::env::var("HRTAO_DEVICE").ok(),
        ray_backend,
        mask_ray_query,
        ..Default::default()
    })
}

/// The settings whose frames `frames` renders: ours (defaults), the paper's, and per-pixel RTAO.
fn settings() -> [(&'static str, AoSettings); 3] {
    let mut defaults = AoSettings::default();
    defaults.map.ao_radius = R;
    defaults.map.hash_capacity = 1 << 17;
    let paper = defaults.paper();
    [("defaults", defaults), ("paper", paper), ("rtao", rtao(8, R))]
}

const FRAMES: [&str; 3] = ["frame 1", "frame 3", "navigation"];

/// Per setting of `settings()`: the AO of frame 1 (a young map), frame 3 (still frames) and frame 5 (the second
/// frame of a moving camera), with ray-traced primary visibility; and the G-buffer of the first frame.
fn frames(gpu: &Arc<Gpu>) -> (Vec<Vec<f32>>, Vec<hrtao_core::gpu::GPixel>) {
    frames_cut(gpu, None)
}

fn frames_cut(gpu: &Arc<Gpu>, cut: Option<u64>) -> (Vec<Vec<f32>>, Vec<hrtao_core::gpu::GPixel>) {
    let (scene, cam) = bundled(W, H);
    let sg = SceneGpu::new(gpu, &scene).unwrap();
    let mut out = Vec::new();
    let mut gbuffer = Vec::new();
    for (_, s) in settings() {
        let mut r = Headless::new(gpu, W, H, s).unwrap();
        r.set_primary(Primary::RayQuery);
        if let Some(c) = cut {
            r.r.set_max_rays_per_dispatch(c);
        }
        out.extend(five_frames(&mut r, &sg, &scene, &cam, |i, r| {
            // The barriers the recorder derived cover every hazard, in whichever stage the passes ran.
            let events = r.r.last_frame_events();
            let problems = hrtao_core::barrier::uncovered_hazards(events);
            assert!(problems.is_empty(), "frame {i}: {problems:?}");
            let stage = if gpu.info.ray_backend == RayBackend::Pipeline {
                hrtao_core::barrier::Stage::RayTracing
            } else {
                hrtao_core::barrier::Stage::Compute
            };
            let traced = events.iter().any(|e| match e {
                hrtao_core::barrier::Event::Command {
                    pass: Some(p), uses, ..
                } => p.traces() && uses.iter().any(|u| u.stage == stage),
                _ => false,
            });
            assert!(traced, "frame {i}: tracing passes ran in the {stage:?} stage");
            if i == 0 && gbuffer.is_empty() {
                gbuffer = r.read_gbuffer().unwrap();
            }
        }));
    }
    assert_clean(gpu);
    (out, gbuffer)
}

/// Pixels whose primary hit may differ between the backends: at most 0.1 % (14 of 160 x 90). Both backends run
/// the same GLSL (trace.glsl) on the same acceleration structure, but compiled apart (a compute shader and a
/// ray-generation shader): a GPU's compiler may contract or reorder the float operations of the ray's setup
/// differently, moving a ray's direction by an ulp or so, which changes its hit only where it passes within about
/// 1e-6 of an edge between two surfaces — far less than one pixel of an image this size is expected to, and
/// lavapipe gives none. A backend that is really wrong (another instance, another distance, a missed or a
/// culled surface) changes whole regions of the image, hundreds of pixels.
const PRIMARY_DIFFERING: f64 = 0.001;
/// Pixels whose per-pixel RTAO (8 rays) may differ by more than 1e-4 between the backends: at most 1 % (144). Each
/// pixel traces the same 8 QMC rays by both; for the reason above a ray may change its verdict where it grazes an
/// edge or leaves a surface at the self-intersection offset, moving that pixel by 1/8 (and the primary hits that
/// may differ carry their pixel along), i.e. a few pixels of the image. Wrong rays (another sequence, another
/// radius, missed hits) change most of the occluded pixels, thousands. Lavapipe: 0 (bit-equal).
const RTAO_DIFFERING: f64 = 0.01;

/// The backends trace the same rays, so per-pixel RTAO and primary visibility agree but for rays whose setup a
/// GPU's compiler rounds differently (`PRIMARY_DIFFERING`, `RTAO_DIFFERING`); the cache's images
/// differ as two runs of one backend do: which pixel of a cell claims which of its QMC rays is decided by atomics
/// (ray_target.glsl), and a ray-generation launch runs its threads in another order than a compute dispatch.
/// Measured on lavapipe (2 shared cores, LP_NUM_THREADS unset), MAE (`common::mae`) per image:
/// - query vs pipeline: 0.0048–0.0109 (paper frame 1 the largest), mean signed difference within ±0.0006;
/// - run to run, pipelines: 0.0004–0.0093 (it varies with the machine's load); ray queries: 0–0.0021;
/// - ray queries against ray queries with every pixel's claims interleaved (the update cut into one ray per pixel
///   per dispatch, as a GPU's thousands of threads may order them): 0.0076–0.0162;
/// - per-pixel RTAO and the primary hits: 0 (bit-equal).
///
/// So each image's MAE between the backends must lie within 1.5x this run's spread (the larger of the pipelines'
/// run to run and the interleaved claims') + 0.002, its mean signed difference within ±0.002 (three times the
/// measured: a ray that misses what it should hit would bias it), and per-pixel RTAO in all but `RTAO_DIFFERING`
/// of the pixels within 1e-4 (and within the MAE bound above: a spread of 0 leaves 0.002). (4 runs.)
#[test]
fn every_tracing_pass_agrees_between_the_backends_within_the_run_to_run_spread() {
    if !ray_queries_or_skip("the backends compared (ray queries against pipelines)") {
        return;
    }
    let query = device(Some(RayBackend::Query), false).expect("a device with ray queries");
    let (q, q_gbuffer) = frames(&query);
    let (qi, _) = frames_cut(&query, Some((W * H) as u64));
    drop(query);
    let pipeline = device(Some(RayBackend::Pipeline), false).expect("a device with ray-tracing pipelines");
    assert_eq!(pipeline.info.ray_backend, RayBackend::Pipeline);
    let (p, p_gbuffer) = frames(&pipeline);
    let (p2, _) = frames(&pipeline);
    drop(pipeline);

    // Primary visibility: the same hits (instance, distance) in every pixel but `PRIMARY_DIFFERING` of them.
    assert_eq!(q_gbuffer.len(), p_gbuffer.len());
    let mut differing = 0;
    for (a, b) in q_gbuffer.iter().zip(&p_gbuffer) {
        let same_hit = (a.t < 0.0) == (b.t < 0.0) && a.instance == b.instance;
        if !same_hit || (a.t - b.t).abs() > 1e-4 * a.t.abs().max(1.0) {
            differing += 1;
        }
    }
    let hits = q_gbuffer.iter().filter(|a| a.t >= 0.0).count();
    eprintln!("primary hits: {differing} of {} pixels differ", q_gbuffer.len());
    assert!(
        hits > q_gbuffer.len() / 4,
        "the view shows the scene: {hits} hits"
    );
    assert!(
        differing as f64 <= PRIMARY_DIFFERING * q_gbuffer.len() as f64,
        "{differing} of {} pixels' primary hit differs between the backends",
        q_gbuffer.len()
    );

    let names: Vec<String> = settings()
        .iter()
        .flat_map(|(s, _)| FRAMES.iter().map(move |f| format!("{s} {f}")))
        .collect();
    for (k, name) in names.iter().enumerate() {
        let spread = mae(&q[k], &qi[k]).max(mae(&p[k], &p2[k]));
        let cross = mae(&q[k], &p[k]);
        let signed = q[k].iter().zip(&p[k]).map(|(a, b)| a - b).sum::<f32>() / q[k].len() as f32;
        eprintln!(
            "{name}: MAE query-pipeline {cross:.5} (signed {signed:.5}); spread: pipeline run to run {:.5}, \
             query interleaved {:.5}",
            mae(&p[k], &p2[k]),
            mae(&q[k], &qi[k])
        );
        if name.starts_with("rtao") {
            let differing = q[k]
                .iter()
                .zip(&p[k])
                .filter(|(a, b)| (*a - *b).abs() > 1e-4)
                .count();
            let occluded = q[k].iter().filter(|&&a| a < 0.999).count();
            eprintln!("{name}: {differing} of {} pixels differ", q[k].len());
            // Enough occluded pixels (lavapipe: 2339, 16 %) that a wrong backend would show (RTAO_DIFFERING).
            assert!(
                occluded as f64 > 10.0 * RTAO_DIFFERING * q[k].len() as f64,
                "{name}: {occluded} occluded pixels"
            );
            assert!(
                differing as f64 <= RTAO_DIFFERING * q[k].len() as f64,
                "{name}: per-pixel RTAO differs between the backends in {differing} of {} pixels (MAE {cross})",
                q[k].len()
            );
        }
        assert!(
            cross <= 1.5 * spread + 0.002,
            "{name}: MAE {cross} between the backends, beyond this run's spread {spread}"
        );
        assert!(
            signed.abs() <= 0.002,
            "{name}: the backends differ on average by {signed}"
        );
    }
}

/// A device without ray queries (VK_KHR_ray_query masked) traces with pipelines by itself, renders every
/// tracing pass with validation silent (its compute shaders declare no ray-query capability); asking it for ray
/// queries finds no device. A device with both picks ray queries.
#[test]
fn a_device_without_ray_queries_picks_the_pipelines() {
    let masked = device(None, true).expect("a device with ray-tracing pipelines");
    assert_eq!(masked.info.ray_backend, RayBackend::Pipeline);
    let (scene, cam) = bundled(W, H);
    let sg = SceneGpu::new(&masked, &scene).unwrap();
    for (name, s) in settings() {
        let mut r = Headless::new(&masked, W, H, s).unwrap();
        r.set_primary(Primary::RayQuery);
        for _ in 0..2 {
            assert!(
                r.render(&sg, scene.f(), &cam).unwrap().rays > 0,
                "{name} traced rays"
            );
        }
        let ao = r.read_ao().unwrap();
        assert!(ao.iter().any(|&a| a < 0.9), "{name}: some occlusion");
    }
    assert_clean(&masked);
    drop((sg, masked));
    let refused = device(Some(RayBackend::Query), true);
    assert!(refused.is_err(), "ray queries forced on a device without them");

    if ray_queries_or_skip("a device with both backends picks ray queries") {
        let chosen = device(None, false).unwrap();
        assert_eq!(
            chosen.info.ray_backend,
            RayBackend::Query,
            "ray queries where the device has them"
        );
    }
    assert_eq!(RayBackend::choose(None, false, false).ok(), None);
    assert_eq!(RayBackend::choose(None, true, true), Ok(RayBackend::Query));
    assert_eq!(
        RayBackend::choose(Some(RayBackend::Pipeline), true, true),
        Ok(RayBackend::Pipeline)
    );
    assert!(RayBackend::choose(Some(RayBackend::Pipeline), true, false).is_err());
}
