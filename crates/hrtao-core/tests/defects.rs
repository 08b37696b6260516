//! Defects of the renderer found by a code read, each with a check that failed before its fix (the mutation or
//! the old behaviour it catches is named in each test).
mod common;

use common::*;
use hrtao_core::{AoSettings, Camera, SceneGpu};
use hrtao_scene::Scene;

/// A floor (instance 0) with three 2 x 2 x 2 blocks standing on it (instances 1..=3), 6 apart along x.
fn blocks() -> Scene {
    row_of_blocks(floor(), 3, 6.0)
}

fn camera() -> Camera {
    z_up_camera_fov([0.0, -12.0, 14.0], [0.0; 3], 60.0, (160, 90))
}

/// The paper's mode (refinement off) at 4 rays and R = 3, with `overrides`.
fn cells_only(overrides: &str) -> AoSettings {
    let mut s = hrtao(4, 3.0);
    s.still.refine = false;
    s.with_overrides(overrides).unwrap()
}

/// `min_samples = 0` (the panel allows it) resolves as 1 does: the finest cell with rays. Before the fix
/// `s >= min_samples` held for a cell without rays, which was then shown as open (AO 1): white holes wherever a
/// pixel's finest cell had no rays yet. Here a small trace fraction leaves many finest cells without rays.
#[test]
fn min_samples_zero_shows_no_white_holes() {
    let gpu = gpu();
    let scene = blocks();
    let cam = camera();
    let image = |min_samples: u32| {
        let s = cells_only(&format!(
            r#"{{"min_samples": {min_samples}, "filter_iterations": 0}}"#
        ));
        let sg = SceneGpu::new(&gpu, &scene).unwrap();
        let mut r = Headless::new(&gpu, cam.width, cam.height, s).unwrap();
        r.budget = Some(hrtao_core::RayBudget {
            rays_per_pixel: 4,
            trace_fraction: 0.05,
        });
        for _ in 0..2 {
            r.render(&sg, scene.f(), &cam).unwrap();
        }
        (r.read_ao().unwrap(), r.read_gbuffer().unwrap())
    };
    let (zero, gbuf) = image(0);
    let (one, _) = image(1);
    let surface: Vec<usize> = (0..zero.len()).filter(|&i| gbuf[i].t >= 0.0).collect();
    let holes = surface
        .iter()
        .filter(|&&i| zero[i] >= 0.999 && one[i] < 0.9)
        .count();
    let mean = |img: &[f32]| surface.iter().map(|&i| img[i]).sum::<f32>() / surface.len() as f32;
    eprintln!(
        "min_samples 0: {holes} white holes of {} pixels; mean AO {:.4} (min_samples 1: {:.4})",
        surface.len(),
        mean(&zero),
        mean(&one)
    );
    assert!(
        holes * 200 < surface.len(),
        "{holes} of {} pixels are white with min_samples = 0 and shaded with 1",
        surface.len()
    );
    assert!((mean(&zero) - mean(&one)).abs() < 0.01);
    assert_clean(&gpu);
}

/// The TLAS descriptor is written once for every TLAS build generation, whatever the handle values. Deleting a
/// part and selecting another rebuild the TLAS twice with no frame between them: the second build may get the
/// first's freed handle value back, and a comparison of handle values (the old `PassSet::bind_tlas`) then skips
/// the write and leaves the descriptor on a destroyed acceleration structure.
#[test]
fn the_tlas_descriptor_is_rewritten_after_every_rebuild() {
    let (gpu, mut scene, cam, mut sg) = on_gpu((blocks(), camera()));
    let mut r = Headless::new(&gpu, cam.width, cam.height, cells_only("{}")).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    let before = r.tlas_descriptor_writes();
    let mut handles = vec![sg.tlas.raw];
    for round in 0..3 {
        // Delete block 1, then select block 2 (two rebuilds), then a frame.
        scene.set_visible(1, round % 2 == 1).unwrap();
        sg.update_instances(&scene, u32::MAX).unwrap();
        handles.push(sg.tlas.raw);
        sg.update_instances(&scene, 2).unwrap();
        handles.push(sg.tlas.raw);
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    let writes = r.tlas_descriptor_writes() - before;
    eprintln!("TLAS handles {handles:?}: {writes} descriptor writes in 3 frames");
    assert_eq!(writes, 3, "one descriptor write per frame after a rebuild");
    // A frame without a rebuild writes nothing.
    r.render(&sg, scene.f(), &cam).unwrap();
    assert_eq!(r.tlas_descriptor_writes() - before, 3);
    assert_clean(&gpu);
}

/// The same at the descriptor set: a new build generation is written even when its handle value is the one
/// bound (a driver may hand a freed handle value out again; lavapipe does not, so the renderer-level test above
/// cannot catch the old comparison of handle values, and this one does).
#[test]
fn a_new_tlas_generation_is_written_even_with_the_same_handle_value() {
    let gpu = gpu();
    let scene = blocks();
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    let globals = hrtao_core::buffer::Buffer::new(
        &gpu,
        "globals",
        std::mem::size_of::<hrtao_core::gpu::FrameGlobals>() as u64,
        gpu_allocator::MemoryLocation::CpuToGpu,
        ash::vk::BufferUsageFlags::empty(),
    )
    .unwrap();
    let mut passes = hrtao_core::pass::PassSet::new(&gpu, &globals, &hrtao_core::passes::ALL).unwrap();
    let g = sg.tlas_generation();
    passes.bind_tlas(sg.tlas.raw, g);
    passes.bind_tlas(sg.tlas.raw, g);
    assert_eq!(passes.tlas_writes(), 1, "the same build is written once");
    passes.bind_tlas(sg.tlas.raw, g + 1);
    assert_eq!(
        passes.tlas_writes(),
        2,
        "a new build generation with the same handle value is written"
    );
    drop(passes);
    assert_clean(&gpu);
}

/// The paper's mode reports convergence only when no cell on screen takes rays any more. With a fractional
/// budget a frame may pick none of the pixels whose cells are still young: it traced no rays, and the old check
/// (`rays == 0`) called the image final although its cells were still filling.
#[test]
fn the_papers_mode_never_reports_convergence_with_young_cells_on_screen() {
    let (gpu, scene, cam, sg) = on_gpu((blocks(), camera()));
    // Cells that fill in a few frames of the full budget until some thousand pixels are left on young cells,
    // then a fractional budget that picks none of them in most frames.
    let s = cells_only(r#"{"max_samples": 256, "rays_per_pixel": 8}"#);
    let mut r = Headless::new(&gpu, cam.width, cam.height, s.clone()).unwrap();
    let mut counts = Vec::new();
    for _ in 0..64 {
        let young = r.render(&sg, scene.f(), &cam).unwrap().ray_pixels;
        counts.push(young);
        if young < 4000 {
            break;
        }
    }
    eprintln!("pixels on young cells, frame by frame: {counts:?}");
    assert!((1..4000).contains(counts.last().unwrap()));
    // The pixels on young cells, from the last frame's cells.
    let young_pixels = |r: &Headless, max_samples: u32| {
        let cells = r.read_hash_cells().unwrap();
        r.read_pixel_cells()
            .unwrap()
            .iter()
            .zip(r.read_gbuffer().unwrap())
            .filter(|(_, px)| px.t >= 0.0)
            .filter_map(|(pc, _)| pc.cells.iter().find(|&&c| c != hrtao_core::gpu::INVALID_CELL))
            .filter(|&&c| cells[c as usize].qmc_index < max_samples)
            .count()
    };
    let mut reported = Vec::new();
    for fraction in [0.0005, 1.0] {
        r.budget = Some(hrtao_core::RayBudget {
            rays_per_pixel: s.map.rays_per_pixel,
            trace_fraction: fraction,
        });
        for frame in 0..64 {
            if r.render(&sg, scene.f(), &cam).unwrap().converged {
                let young = young_pixels(&r, s.map.max_samples);
                eprintln!("trace fraction {fraction}: converged at frame {frame} with {young} pixels on young cells");
                reported.push((fraction, frame, young));
                break;
            }
        }
    }
    // Converged only with every cell on screen full, and it does converge once the cells fill.
    assert!(
        reported.iter().all(|&(_, _, young)| young == 0),
        "converged with pixels on young cells: {reported:?}"
    );
    assert!(
        reported.iter().any(|&(f, _, _)| f == 1.0),
        "never converged: {reported:?}"
    );
    assert_clean(&gpu);
}

/// Pre-edit AO never comes back. A block is deleted (a local edit: the regions around it get new epochs), then
/// the AO radius crosses a power of two, which changes the region grids (`Renderer::region_lod`). Before the
/// fix the grids' epochs were reset under the same F, so the cells got their pre-edit keys back and served
/// the removed block's contact shadow again. Here the floor where the shadow was matches a fresh render of
/// the edited scene.
#[test]
fn a_deleted_parts_contact_shadow_does_not_come_back_when_the_radius_crosses_a_power_of_two() {
    let (gpu, mut scene, cam, mut sg) = on_gpu((blocks(), camera()));
    let s = cells_only(r#"{"max_samples": 64}"#);
    let mut r = Headless::new(&gpu, cam.width, cam.height, s.clone()).unwrap();
    for _ in 0..24 {
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    let (ring, with_part) = remove_part(&r, &mut scene, &mut sg, 2);
    for _ in 0..8 {
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    let lod = r.region_lod();
    // R x max_cell_fraction: 0.75 -> 1.125, the largest finest cell crosses 1 (a power of two).
    let wider = {
        let mut s = s.clone();
        s.map.ao_radius = 4.5;
        s
    };
    r.set_settings(wider.clone()).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    assert_ne!(r.region_lod(), lod, "the region grids change");
    let (after, expected) = mean_against_fresh(&r, &gpu, (&scene, &cam), (wider, 1), &ring);
    let ao = (with_part, after, expected);
    check_contact_shadow(ring.len(), ao, "after the radius change", 50);
    assert!(
        (after - expected).abs() < 0.05,
        "the deleted block's contact shadow came back: AO {after:.3}, fresh {expected:.3}"
    );
    assert_clean(&gpu);
}

/// A local edit with refinement on does not show the old contact shadow for a frame. Pixels the edit restarts
/// have one frame of their own rays and pool their 3 x 3 neighbours' residuals of the previous frame, measured
/// before the edit, which still hold the removed block's contact shadow (AO 0.939 the frame after the edit
/// against 0.999 fresh). Fixed: `pooled_evidence` leaves out the neighbours the edit restarted (their residual is
/// of their pre-edit cells); the unedited neighbours' evidence stays (the frame after the edit: 0.999, fresh
/// 1.000).
#[test]
fn a_local_edit_with_refinement_shows_no_ghost_of_the_removed_part() {
    let (gpu, mut scene, cam, mut sg) = on_gpu((blocks(), camera()));
    // Cells wider than the contact shadow: the pixels' own rays find it darker than their cells, and their
    // residuals (pooled with the neighbours') hold it.
    let mut s = hrtao(4, 3.0);
    s.map.s_p = 16.0;
    assert!(s.still.refine && s.edits.local_edits);
    let mut r = Headless::new(&gpu, cam.width, cam.height, s.clone()).unwrap();
    for _ in 0..24 {
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    let (ring, with_part) = remove_part(&r, &mut scene, &mut sg, 2);
    let rep = r.render(&sg, scene.f(), &cam).unwrap();
    assert!(
        rep.accumulated_frames > 1,
        "a local edit keeps the still image elsewhere"
    );
    // The edited scene, still for as many frames: no trace of the block.
    let (after, expected) = mean_against_fresh(&r, &gpu, (&scene, &cam), (s, 25), &ring);
    let ao = (with_part, after, expected);
    check_contact_shadow(ring.len(), ao, "the frame after the edit", 50);
    assert!(
        after > expected - 0.05,
        "the removed block's contact shadow flashed: AO {after:.3}, fresh {expected:.3}"
    );
    assert_clean(&gpu);
}

/// The frame's counters live in device memory and reach the report through one copy at the end of the frame:
/// per-pixel RTAO reports exactly its rays (every surface pixel traces the budget), frame after frame (the
/// first thread of primary visibility empties the per-frame counters, the u64 ray counters included). Catches a missing end-of-frame
/// copy (the report would read zeros) and per-frame counters that are not cleared (they would add up).
#[test]
fn ray_counts_reach_the_report_exactly_each_frame() {
    let (gpu, scene, cam, sg) = on_gpu((blocks(), camera()));
    let s = {
        let mut s = hrtao(7, 3.0);
        s.display.mode = hrtao_core::Mode::Rtao;
        s
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, s).unwrap();
    for frame in 0..3 {
        let rep = r.render(&sg, scene.f(), &cam).unwrap();
        let surface = r.read_gbuffer().unwrap().iter().filter(|p| p.t >= 0.0).count() as u64;
        assert!(surface > 1000);
        assert_eq!(rep.rays, 7 * surface, "frame {frame}");
        assert_eq!((rep.refine_rays, rep.cell_rays), (0, 0));
    }
    assert_clean(&gpu);
}
