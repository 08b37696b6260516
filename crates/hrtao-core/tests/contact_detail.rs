//! Contact detail (ours, `contact_detail`, docs/algorithm.md): the G-buffer's obscurance detail added to a young
//! pixel's AO with a gain fitted to the frame's own rays.
mod common;
use common::*;
use hrtao_core::{AoSettings, Renderer, SceneGpu};

/// One frame from an empty map at 8 rays per pixel on a shared view at 320x180 against its Cycles reference,
/// without and with contact detail (every other setting at its default): the creases between the engine's fins
/// are finer than its cells, and the detail brings them back, so the error falls. The margin is several times
/// the run-to-run spread of one frame (thread order decides which pixel takes which of a cell's rays).
#[test]
fn contact_detail_lowers_the_first_frame_error() {
    let gpu = gpu();
    let key = "engine";
    let (scene, cam, radius) = shared_scene(key, 320, 180);
    let cycles = cycles_ref(key, 320, 180);
    let sg = SceneGpu::new(&gpu, &scene).expect("scene upload");
    let mut errors = [0.0; 2];
    for (e, contact_detail) in errors.iter_mut().zip([0.0, 1.0]) {
        let settings = AoSettings {
            contact_detail,
            ..hrtao(8, radius)
        };
        let mut r = Renderer::new(&gpu, cam.width, cam.height, settings).expect("renderer");
        r.render(&sg, scene.f(), &cam).expect("frame");
        *e = mae(&r.read_ao().unwrap(), &cycles);
    }
    assert_clean(&gpu);
    println!(
        "{key} 320x180, HRTAO 1 frame: without contact detail {:.4}, with {:.4}",
        errors[0], errors[1]
    );
    assert!(
        errors[1] < errors[0] - 0.001,
        "{key}: without {}, with {}",
        errors[0],
        errors[1]
    );
}
