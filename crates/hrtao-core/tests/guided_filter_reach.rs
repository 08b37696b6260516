//! The guided filter's reach in a young map's first frame (ours, shaders/filter.comp `GUIDED_REACH`,
//! `GUIDED_PLANE`): a face of a few pixels borrows the rays of nearby parallel faces whose AO agrees within the
//! noise.
mod common;
use common::*;
use hrtao_core::{Renderer, SceneGpu};

/// One frame from an empty map at 8 rays per pixel on the shared duplex view (320x180) against its Cycles
/// reference, within the budget. Measured 0.0099 with the narrow filter, 0.0087-0.0088 with the wider reach
/// (640x360: 0.0093 -> 0.0083): the bound fails a return to the narrow filter.
#[test]
fn guided_filter_reach_first_frame_error() {
    let gpu = gpu();
    let (scene, cam, radius) = shared_scene("duplex", 320, 180);
    let cycles = cycles_ref("duplex", 320, 180);
    let sg = SceneGpu::new(&gpu, &scene).expect("scene upload");
    let settings = hrtao(8, radius);
    assert!(settings.filter_sigma > 0.0, "the guided filter is on by default");
    let mut r = Renderer::new(&gpu, cam.width, cam.height, settings).expect("renderer");
    let rays = r.render(&sg, scene.f(), &cam).expect("frame").rays;
    let e = mae(&r.read_ao().unwrap(), &cycles);
    println!("duplex 320x180, HRTAO 1 frame: {e:.4} ({rays} rays)");
    assert!(
        rays as f64 <= 8.05 * (cam.width * cam.height) as f64,
        "no more than the budget: {rays} rays"
    );
    assert!(e < BOUND, "duplex one frame {e}, bound {BOUND}");
    assert_clean(&gpu);
}

const BOUND: f32 = 0.0092;
