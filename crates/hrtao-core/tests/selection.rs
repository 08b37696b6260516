//! A selection change and a section-plane drag on the GPU side: a highlight rewrites the instance table's
//! flags in the next frame's commands (no TLAS build, no device wait, the AO and its refinement untouched),
//! and the TLAS rebuilt at every plane step reuses its storage.
mod common;

use common::*;
use hrtao_core::accel::SceneGpu;
use hrtao_core::gpu::{InstanceInfo, INSTANCE_SELECTED, NO_INSTANCE};
use hrtao_core::section::{SectionPlane, Sections};

/// A converged still image of a floor and three blocks; the middle block is selected. The change builds no TLAS
/// and waits for nothing; the still image restarts (the composite accumulates each pixel's shade with its AO)
/// while the map keeps its cells, and once converged again the block's pixels show the highlight and no other
/// pixel differs by more than the refinement's own noise. Deselected, the image comes back. Fails with
/// `update_instances` in place of `set_highlight` (a TLAS build), with `record_uploads` left out of the frame
/// (no pixel changes) and with the highlight left out of `FrameKey` (the converged image is shown again).
#[test]
fn a_selection_changes_the_selected_pixels_only_without_a_tlas_or_a_wait() {
    let (gpu, scene, cam, mut sg) = on_gpu((row_of_blocks(floor(), 3, 4.0), top_down_camera(14.0, 96, 64)));
    let settings = {
        let mut s = hrtao(4, 2.0);
        s.still.still_samples = 8;
        s
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
    let converge = |r: &mut Headless, sg: &SceneGpu| {
        let mut frames = 0;
        while !r.render(sg, scene.f(), &cam).unwrap().converged {
            frames += 1;
            assert!(frames < 64, "the still image converges");
        }
        r.read_rgba().unwrap()
    };
    let plain = converge(&mut r, &sg);
    let instances: Vec<u32> = r.read_gbuffer().unwrap().iter().map(|p| p.instance).collect();
    let selected = 2u32; // the middle block (instance 0 is the floor)
    let (tlas, waits) = (sg.tlas_generation(), gpu.idle_waits());

    assert!(sg.set_highlight(&[selected][..]));
    assert!(
        !sg.set_highlight(&[selected][..]),
        "the same selection again changes nothing"
    );
    assert!(
        !r.shows_final(&sg, scene.f(), &cam),
        "the output no longer shows the view"
    );
    let lit = converge(&mut r, &sg);
    assert_eq!(sg.tlas_generation(), tlas, "a selection builds no TLAS");
    assert_eq!(gpu.idle_waits(), waits, "a selection waits for no device idle");

    // Mean absolute difference (0..255 levels, RGB) over the pixels of instance `on` or of every other one.
    let diff = |a: &[u8], b: &[u8], pick: &dyn Fn(u32) -> bool| {
        let px: Vec<usize> = (0..instances.len()).filter(|&i| pick(instances[i])).collect();
        assert!(!px.is_empty());
        let sum: u32 = px
            .iter()
            .flat_map(|&i| (0..3).map(move |c| 4 * i + c))
            .map(|k| a[k].abs_diff(b[k]) as u32)
            .sum();
        sum as f64 / (3 * px.len()) as f64
    };
    let on = diff(&plain, &lit, &|i| i == selected);
    let off = diff(&plain, &lit, &|i| i != selected && i != NO_INSTANCE);
    println!("selected block: {on:.2} levels, the rest: {off:.3} levels");
    assert!(
        on > 10.0,
        "the selected block shows the highlight: {on:.2} levels"
    );
    assert!(off < 0.5, "no other pixel changes: {off:.3} levels");

    // Deselected: the image before the selection, within the refinement's noise.
    assert!(sg.set_highlight(u32::MAX));
    let back = converge(&mut r, &sg);
    let all = diff(&plain, &back, &|i| i != NO_INSTANCE);
    assert!(all < 0.5, "deselected: {all:.3} levels from the first image");
    assert_eq!(gpu.idle_waits(), waits);
    assert_clean(&gpu);
}

/// The instance table on the device, read back: each instance's flags.
fn device_flags(sg: &SceneGpu, n: usize) -> Vec<u32> {
    let infos: Vec<InstanceInfo> = sg.instance_info.read(n).unwrap();
    infos.iter().map(|i| i.flags).collect()
}

/// The queued table reaches the device with the next frame, not before; an instance update (an edit) queued
/// after it writes its own selection and supersedes it. Fails when `update_instances` leaves the queued table
/// in place (the old selection comes back a frame later) and when `set_highlight` writes from the host at once.
#[test]
fn a_highlight_reaches_the_device_with_the_next_frame_unless_an_update_supersedes_it() {
    let gpu = gpu();
    let scene = row_of_blocks(floor(), 3, 4.0);
    let n = scene.instances.len();
    let cam = top_down_camera(14.0, 32, 24);
    let mut sg = SceneGpu::new(&gpu, &scene).unwrap();
    let mut r = Headless::new(&gpu, cam.width, cam.height, hrtao(1, 2.0)).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    sg.set_highlight(1u32);
    assert_eq!(
        device_flags(&sg, n),
        [0, 0, 0, 0],
        "queued, not written from the host"
    );
    r.render(&sg, scene.f(), &cam).unwrap();
    let sel = INSTANCE_SELECTED;
    assert_eq!(device_flags(&sg, n), [0, sel, 0, 0], "written by the frame");
    sg.set_highlight(3u32);
    sg.update_instances(&scene, &[2u32][..]).unwrap();
    assert_eq!(device_flags(&sg, n), [0, 0, sel, 0], "the update's own selection");
    r.render(&sg, scene.f(), &cam).unwrap();
    assert_eq!(
        device_flags(&sg, n),
        [0, 0, sel, 0],
        "the queued table was dropped"
    );
    assert_clean(&gpu);
}

/// A section-plane drag: every step rebuilds the TLAS (cut instances leave it) into the same storage with the
/// same scratch, so a drag allocates nothing after its first step. Fails with a new `AccelStruct` per build.
#[test]
fn a_section_drag_reuses_the_tlas_storage() {
    let gpu = gpu();
    let scene = row_of_blocks(floor(), 8, 3.0);
    let mut sg = SceneGpu::new(&gpu, &scene).unwrap();
    let plane = |d: f32| Sections::new(vec![SectionPlane::new([1.0, 0.0, 0.0], d).unwrap()]).unwrap();
    sg.set_sections(&scene, &plane(-20.0), u32::MAX).unwrap();
    let (raw, bytes, generation) = (sg.tlas.raw, gpu.device_memory_bytes(), sg.tlas_generation());
    let mut kept = Vec::new();
    for step in 0..16 {
        sg.set_sections(&scene, &plane(-12.0 + 1.5 * step as f32), u32::MAX)
            .unwrap();
        kept.push(sg.section_sides[0] + sg.section_sides[1]);
        assert_eq!(sg.tlas.raw, raw, "step {step}: the same TLAS");
        assert_eq!(gpu.device_memory_bytes(), bytes, "step {step}: nothing allocated");
    }
    assert!(
        sg.tlas_generation() >= generation + 16,
        "every step is a new build"
    );
    assert_ne!(kept.first(), kept.last(), "the plane cut blocks away as it moved");
    assert_clean(&gpu);
}
