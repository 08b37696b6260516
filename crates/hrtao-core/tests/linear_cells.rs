//! Linear cells (ours, `cell_gradient`, docs/algorithm.md): a cell's AO read along its least-squares slope at
//! the pixel, instead of the cell's mean.
mod common;
use common::*;
use hrtao_core::{AoSettings, Renderer, SceneGpu};

/// One frame from an empty map at 8 rays per pixel on a shared view at 320x180 against its Cycles reference,
/// with constant cells and with linear cells over the same rays: the line reads the AO's slope across a cell
/// (contact shadows fading along a wall), so the error falls. The margin is above the run-to-run spread of
/// one frame (thread order decides which pixel takes which of a cell's rays). Contact detail is off: it brings
/// back the same detail finer than a cell from the G-buffer (with it on both measure 0.0243).
fn first_frame_errors(key: &str) -> (f32, f32) {
    let gpu = gpu();
    let (scene, cam, radius) = shared_scene(key, 320, 180);
    let cycles = cycles_ref(key, 320, 180);
    let sg = SceneGpu::new(&gpu, &scene).expect("scene upload");
    let mut errors = [0.0; 2];
    for (e, cell_gradient) in errors.iter_mut().zip([0.0, 2.0]) {
        let settings = AoSettings {
            cell_gradient,
            contact_detail: 0.0,
            ..hrtao(8, radius)
        };
        let mut r = Renderer::new(&gpu, cam.width, cam.height, settings).expect("renderer");
        r.render(&sg, scene.f(), &cam).expect("frame");
        *e = mae(&r.read_ao().unwrap(), &cycles);
    }
    assert_clean(&gpu);
    println!(
        "{key} 320x180, HRTAO 1 frame: constant cells {:.4}, linear cells {:.4}",
        errors[0], errors[1]
    );
    (errors[0], errors[1])
}

#[test]
fn linear_cells_lower_the_first_frame_error() {
    let (constant, linear) = first_frame_errors("engine");
    assert!(
        linear < constant - 0.0004,
        "engine: constant {constant}, linear {linear}"
    );
}
