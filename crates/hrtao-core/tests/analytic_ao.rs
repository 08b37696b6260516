//! Per-pixel RTAO and HRTAO against closed-form AO (cosine-weighted, radius R) on simple scenes, validation on.
mod common;
use common::*;
use hrtao_scene::glam::Vec3;

/// The analytic scenes are checked for per-pixel RTAO (converged), for HRTAO's first frame (the cell estimate)
/// and for HRTAO after still frames (the refinement converges to the ray-traced value).
fn modes(radius: f32) -> [(&'static str, hrtao_core::AoSettings, u32); 3] {
    [
        ("per-pixel RTAO", rtao(64, radius), 8),
        ("HRTAO, 1 frame", hrtao(8, radius), 1),
        ("HRTAO, 8 still frames", hrtao(32, radius), 8),
    ]
}

#[test]
fn open_plane_is_unoccluded() {
    let gpu = gpu();
    let scene = scene_of(vec![floor()]);
    let cam = top_down_camera(20.0, 160, 90);
    for (label, settings, frames) in modes(5.0) {
        let (r, _sg) = render(&gpu, &scene, &cam, settings, frames);
        let ao = r.read_ao().unwrap();
        let min = ao.iter().cloned().fold(f32::MAX, f32::min);
        assert!(min >= 0.99, "{label}: open plane AO min {min}");
        let gb = r.read_gbuffer().unwrap();
        assert!(gb.iter().all(|p| p.t > 0.0), "the camera sees only the floor");
        assert!(
            gb.iter().all(|p| (p.normal[2] - 1.0).abs() < 1e-5),
            "normals face the camera"
        );
    }
    assert_clean(&gpu);
}

#[test]
fn wedge_matches_analytic_value() {
    let gpu = gpu();
    let scene = wedge();
    let radius = 4.0;
    let cam = wedge_camera([6.0, 0.0, 8.0], [2.0, 0.0, 0.0]);
    for (label, settings, frames) in modes(radius) {
        let (r, _sg) = render(&gpu, &scene, &cam, settings, frames);
        let ao = r.read_ao().unwrap();
        let gb = r.read_gbuffer().unwrap();
        let (mut n, mut err_sum, mut near_wall) = (0, 0.0f32, Vec::new());
        for (p, a) in gb.iter().zip(&ao) {
            if p.t < 0.0 || p.normal[2] < 0.99 || p.position[0] < 0.02 {
                continue; // floor pixels only, away from the crease itself
            }
            let expect = wedge_ao(p.position[0], radius);
            err_sum += (a - expect).abs();
            n += 1;
            if p.position[0] < 0.3 {
                near_wall.push(*a);
            }
        }
        assert!(n > 2000, "enough floor pixels ({n})");
        let mae = err_sum / n as f32;
        let mean_near = near_wall.iter().sum::<f32>() / near_wall.len().max(1) as f32;
        println!("wedge, {label}: {n} floor pixels, mean |AO - analytic| = {mae:.4}, AO at the crease {mean_near:.3}");
        assert!(
            mae < 0.02,
            "{label}: mean absolute error {mae} against the analytic wedge"
        );
        assert!(
            (mean_near - 0.5).abs() < 0.06,
            "{label}: AO at the crease {mean_near} ~ 0.5"
        );
    }
    assert_clean(&gpu);
}

#[test]
fn slab_below_radius_is_darker_and_matches_analytic() {
    let gpu = gpu();
    let radius = 4.0;
    for (label, settings, frames) in modes(radius) {
        let mut means = Vec::new();
        for h in [2.0f32, 6.0] {
            // A 120 x 120 slab at height h over the floor; the camera sits between them looking down.
            let slab = quad(Vec3::new(0.0, 0.0, h), Vec3::X * 60.0, Vec3::Y * 60.0);
            let scene = scene_of(vec![floor(), slab]);
            let cam = top_down_camera(h * 0.9, 160, 90);
            let (r, _sg) = render(&gpu, &scene, &cam, settings.clone(), frames);
            let ao = r.read_ao().unwrap();
            let mean = ao.iter().sum::<f32>() / ao.len() as f32;
            // Under an infinite slab at height h < R, rays with cos(theta) >= h/R hit it: AO = (h/R)^2.
            let expect = if h < radius { (h / radius).powi(2) } else { 1.0 };
            println!("slab h={h}, {label}: mean AO {mean:.4}, analytic {expect:.4}");
            assert!(
                (mean - expect).abs() < 0.02,
                "{label}, slab h={h}: {mean} vs {expect}"
            );
            means.push(mean);
        }
        assert!(means[0] < means[1] - 0.5);
    }
    assert_clean(&gpu);
}

#[test]
fn validation_layer_is_live_and_counts_messages() {
    // Proves `assert_clean` means something: an invalid call (a buffer with no usage flags) must be counted.
    let gpu = gpu();
    if !validation_or_skip(&gpu, "the validation layer counts messages") {
        return;
    }
    let before = gpu.validation_messages();
    unsafe {
        use ash::vk;
        let info = vk::BufferCreateInfo::default()
            .size(0)
            .usage(vk::BufferUsageFlags::STORAGE_BUFFER);
        if let Ok(b) = gpu.device.create_buffer(&info, None) {
            gpu.device.destroy_buffer(b, None);
        }
    }
    assert!(
        gpu.validation_messages() > before,
        "the invalid call was not reported"
    );
}
