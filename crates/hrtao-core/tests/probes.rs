//! Probe rays (`FrameDesc::probes`, probes.rs): traced in the frame by the device's ray backend and answered with
//! the frame's report, they hit what the view shows: the closest surface at its analytic distance with its normal
//! turned toward the ray and its instance, nothing for a hidden instance, nothing where a section plane cuts the
//! geometry away; under ray queries and ray-tracing pipelines alike (each where the device has it).
mod common;

use std::sync::Arc;

use common::*;
use hrtao_core::gpu::{ProbeHit, ProbeRay, MAX_PROBE_RAYS};
use hrtao_core::{ContextOptions, FrameDesc, Gpu, RayBackend, Renderer, SceneGpu, SectionPlane, Sections};
use hrtao_scene::glam::Vec3;

fn device(backend: RayBackend) -> Option<Arc<Gpu>> {
    let _ = env_logger::builder().is_test(true).try_init();
    match Gpu::new(&ContextOptions {
        validation: true,
        device: std::env::var("HRTAO_DEVICE").ok(),
        ray_backend: Some(backend),
        ..Default::default()
    }) {
        Ok(g) => Some(g),
        Err(e) => {
            println!("skipped {backend:?}: {e}");
            None
        }
    }
}

/// The floor (instance 0, z = 0) and 2 x 2 x 2 blocks at x = -4, 0, 4 (instances 1, 2, 3), the last hidden.
fn scene() -> hrtao_scene::Scene {
    let mut s = row_of_blocks(floor(), 3, 4.0);
    s.instances[3].visible = false;
    s
}

fn rays() -> Vec<ProbeRay> {
    let r =
        |o: [f32; 3], d: [f32; 3], len: f32, tag: u32| ProbeRay::new(Vec3::from(o), Vec3::from(d), len, tag);
    vec![
        // Down onto block 1's top (z = 2).
        r([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], 100.0, 7),
        // Down onto the floor.
        r([10.0, 10.0, 5.0], [0.0, 0.0, -1.0], 100.0, 7),
        // Along +x into block 0's -x face (x = -5).
        r([-10.0, 0.0, 1.0], [1.0, 0.0, 0.0], 100.0, 7),
        // Along -x: block 2 is hidden, so block 1's +x face (x = 1).
        r([10.0, 0.0, 1.0], [-1.0, 0.0, 0.0], 100.0, 7),
        // Up into nothing.
        r([50.0, 50.0, 1.0], [0.0, 0.0, 1.0], 100.0, 7),
        // Too short to reach the floor.
        r([10.0, 10.0, 5.0], [0.0, 0.0, -1.0], 4.0, 7),
    ]
}

fn trace(gpu: &Arc<Gpu>, sections: Option<Sections>, rays: &[ProbeRay]) -> Vec<ProbeHit> {
    let s = scene();
    let mut sg = SceneGpu::new(gpu, &s).unwrap();
    if let Some(sec) = sections {
        sg.set_sections(&s, &sec, u32::MAX).unwrap();
    }
    let mut r = Renderer::new(gpu).unwrap();
    let settings = hrtao(1, 1.0);
    let cam = top_down_camera(30.0, 32, 18);
    let report = r
        .render(&FrameDesc {
            probes: rays,
            ..FrameDesc::new(&sg, s.f(), cam, &settings)
        })
        .unwrap();
    // A frame without probes answers none.
    let none = r.render(&FrameDesc::new(&sg, s.f(), cam, &settings)).unwrap();
    assert!(none.probe_hits.is_empty());
    assert_clean(gpu);
    report.probe_hits
}

fn check(backend: RayBackend) {
    let Some(gpu) = device(backend) else { return };
    let hits = trace(&gpu, None, &rays());
    let want: [(f32, [f32; 3], u32); 6] = [
        (3.0, [0.0, 0.0, 1.0], 2),
        (5.0, [0.0, 0.0, 1.0], 0),
        (5.0, [-1.0, 0.0, 0.0], 1),
        (9.0, [1.0, 0.0, 0.0], 2),
        (-1.0, [0.0; 3], u32::MAX),
        (-1.0, [0.0; 3], u32::MAX),
    ];
    assert_eq!(hits.len(), want.len());
    for (i, (h, (t, n, inst))) in hits.iter().zip(want).enumerate() {
        assert_eq!(h.tag, 7, "ray {i}: the tag comes back");
        assert!(
            (h.t - t).abs() < 1e-4,
            "{backend:?} ray {i}: t {} (want {t})",
            h.t
        );
        if t >= 0.0 {
            assert!(
                (Vec3::from(h.normal) - Vec3::from(n)).length() < 1e-5,
                "ray {i}: {:?}",
                h.normal
            );
            assert_eq!(h.instance, inst, "ray {i}");
        }
    }
    // A section plane cutting away x > 0.5: the ray from x = 10 along -x is clipped to the kept region, so it
    // misses block 1's +x face (x = 1, cut away) and meets the next surface, block 1's -x face (x = -1).
    let cut = Sections::new(vec![SectionPlane::new([1.0, 0.0, 0.0], 0.5).unwrap()]).unwrap();
    let hits = trace(&gpu, Some(cut), &rays()[3..4]);
    assert!(
        (hits[0].t - 11.0).abs() < 1e-4,
        "{backend:?} behind the section: t {}",
        hits[0].t
    );
    // More rays than a frame traces: the first MAX_PROBE_RAYS are answered.
    let many: Vec<ProbeRay> = (0..MAX_PROBE_RAYS + 5).map(|_| rays()[1]).collect();
    let hits = trace(&gpu, None, &many);
    assert_eq!(hits.len(), MAX_PROBE_RAYS as usize);
    assert!(hits.iter().all(|h| (h.t - 5.0).abs() < 1e-4));
}

#[test]
fn probe_rays_by_ray_queries() {
    if ray_queries_or_skip("probe rays by ray queries") {
        check(RayBackend::Query);
    }
}

#[test]
fn probe_rays_by_ray_tracing_pipelines() {
    check(RayBackend::Pipeline);
}
