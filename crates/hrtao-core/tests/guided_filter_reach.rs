//! The guided filter's reach in a young map's first frame (ours, shaders/filter.comp `GUIDED_REACH`,
//! `GUIDED_PLANE`): a face of a few pixels borrows the rays of nearby parallel faces whose AO agrees within the
//! noise.
mod common;
use common::*;
use hrtao_core::camera::UpAxis;
use hrtao_core::{Camera, SceneGpu};

/// A generated city block (towers with recessed windows: many faces of a few pixels beside parallel ones).
const CITY: &str = "gen:city?blocks=2&per_block=2&floors=12&seed=3";
const RADIUS: f32 = 3.0;

/// One frame from an empty map at 8 rays per pixel on the generated city (320x180) against its converged
/// per-pixel RTAO (1024 rays per pixel), within the budget. Measured 0.0302 with the narrow filter, 0.0261 with
/// the wider reach (the same to four digits on a second run): the bound fails a return to the narrow filter.
#[test]
fn guided_filter_reach_first_frame_error() {
    let gpu = gpu();
    let scene = hrtao_scene::generate(CITY, &mut |_| {}).unwrap();
    let b = scene.bounds();
    let cam = Camera::fit(b.min, b.max, UpAxis::Z, 45.0, 320, 180);
    let radius = RADIUS;
    let converged = reference(&gpu, &scene, &cam, radius, 64, 16);
    let sg = SceneGpu::new(&gpu, &scene).expect("scene upload");
    let settings = hrtao(8, radius);
    assert!(
        settings.filter.variance_filter,
        "the guided filter is on by default"
    );
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).expect("renderer");
    let rays = r.render(&sg, scene.f(), &cam).expect("frame").rays;
    let e = mae(&r.read_ao().unwrap(), &converged);
    println!("city 320x180, HRTAO 1 frame: {e:.4} ({rays} rays)");
    assert!(
        rays as f64 <= 8.05 * (cam.width * cam.height) as f64,
        "no more than the budget: {rays} rays"
    );
    assert!(e < BOUND, "city one frame {e}, bound {BOUND}");
    assert_clean(&gpu);
}

const BOUND: f32 = 0.028;
