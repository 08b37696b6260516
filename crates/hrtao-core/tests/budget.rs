//! Fractional ray budget (ours, `AoSettings::trace_fraction`): below one ray per pixel, a random subset of the
//! pixels traces each frame; the cells, which pool the rays of all their pixels (§3), still fill and converge.
mod common;
use common::*;
use hrtao_core::{AoSettings, FrameDesc, RayBudget};

#[test]
fn a_quarter_of_the_pixels_trace_and_the_cells_still_converge() {
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("rod", 160, 90);
    let run = |settings: AoSettings, fraction: f32, frames: u32| {
        let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
        r.budget = Some(RayBudget {
            rays_per_pixel: 2,
            trace_fraction: fraction,
        });
        let mut rays = Vec::new();
        for _ in 0..frames {
            rays.push(r.render(&sg, scene.f(), &cam).unwrap().rays);
        }
        (rays, r.read_ao().unwrap())
    };
    let full = {
        let mut s = hrtao(2, radius);
        s.still.refine = false;
        s
    };
    let (full_rays, full_ao) = run(full.clone(), 1.0, 4);
    let (quarter_rays, quarter_ao) = run(full.clone(), 0.25, 16);
    // The first frame from an empty map: every pixel's cell takes rays, so the fraction is the ray ratio.
    let ratio = quarter_rays[0] as f64 / full_rays[0] as f64;
    println!(
        "first-frame rays: {} vs {} (ratio {ratio:.3})",
        quarter_rays[0], full_rays[0]
    );
    assert!((0.2..0.3).contains(&ratio), "ray ratio {ratio}");
    // 16 quarter frames trace about the rays of 4 full frames, and come as close to a converged reference.
    let (q16, f4): (u64, u64) = (quarter_rays.iter().sum(), full_rays.iter().sum());
    let truth = reference(&gpu, &scene, &cam, radius, 64, 4);
    let (eq, ef) = (mae(&quarter_ao, &truth), mae(&full_ao, &truth));
    println!(
        "MAE vs a 256-spp reference: 16 quarter frames ({q16} rays) {eq:.4}, 4 full frames ({f4} rays) {ef:.4}"
    );
    assert!(
        (q16 as f64) < 1.2 * f4 as f64 && eq < 1.2 * ef + 0.002,
        "quarter budget: {q16} rays, MAE {eq}; full budget: {f4} rays, MAE {ef}"
    );
    assert_clean(&gpu);
    // Out-of-range fractions are refused.
    let mut r = hrtao_core::Renderer::new(&gpu).unwrap();
    for bad in [0.0, -1.0, 1.5, f32::NAN] {
        let frame = FrameDesc {
            budget: Some(RayBudget {
                rays_per_pixel: 2,
                trace_fraction: bad,
            }),
            ..FrameDesc::new(&sg, scene.f(), cam, &full)
        };
        let e = r.render(&frame).unwrap_err().to_string();
        assert!(e.contains("trace fraction"), "{bad} accepted: {e}");
    }
}
