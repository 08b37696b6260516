//! HRTAO behaviour on lavapipe: quality against a converged per-pixel reference, navigation reuse, the frame
//! counter F after edits, and hash-map overload.
mod common;
use common::*;
use hrtao_core::{gpu, SceneGpu};
use hrtao_scene::glam::{Mat4, Vec3};

fn quality_on(key: &str) {
    let gpu = gpu();
    let (scene, cam, radius) = shared_scene(key, 320, 180);
    let reference = reference(&gpu, &scene, &cam, radius, 64, 6);
    let rays = 4;
    let (pp, _) = render(&gpu, &scene, &cam, rtao(rays, radius), 1);
    let pp_mae = mae(&pp.read_ao().unwrap(), &reference);

    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    let mut r = Headless::new(&gpu, cam.width, cam.height, hrtao(rays, radius)).unwrap();
    let mut errors = Vec::new();
    for _ in 0..4 {
        r.render(&sg, scene.f(), &cam).unwrap();
        errors.push(mae(&r.read_ao().unwrap(), &reference));
    }
    let ratio = errors[0] / pp_mae;
    println!(
        "{key}: MAE vs converged reference at {rays} rays/pixel, one frame: per-pixel RTAO {pp_mae:.4}, HRTAO {:.4} \
         (ratio {ratio:.2}); HRTAO over frames {errors:.4?}",
        errors[0]
    );
    assert!(
        ratio < 0.5,
        "{key}: HRTAO one-frame error {} is not well below per-pixel {pp_mae}",
        errors[0]
    );
    assert!(
        errors[3] < errors[0] * 0.95,
        "{key}: HRTAO error does not fall over frames: {errors:?}"
    );
    assert_clean(&gpu);
}

#[test]
fn quality_rod() {
    quality_on("rod");
}

#[test]
fn quality_cycloidal() {
    quality_on("cycloidal");
}

#[test]
fn navigation_reuses_capped_cells() {
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("cycloidal", 320, 180);
    let settings = {
        let mut s = hrtao(16, radius);
        s.map.max_samples = 64;
        s.still.refine = false;
        s
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
    let first = r.render(&sg, scene.f(), &cam).unwrap();
    // The paper's navigation runs on a warm map: the view rests for two more frames.
    for _ in 0..2 {
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    // A small orbit step: the eye moves ~1% of its distance.
    let mut moved = cam;
    moved.eye[0] += 1.0;
    moved.eye[1] += 0.5;
    let second = r.render(&sg, scene.f(), &moved).unwrap();
    println!(
        "rays: first frame {}, nearby camera {} ({:.1}%); cells {} -> {}",
        first.rays,
        second.rays,
        100.0 * second.rays as f64 / first.rays as f64,
        first.occupied_cells,
        second.occupied_cells
    );
    assert!(first.rays > 0);
    assert!(
        second.rays * 3 < first.rays,
        "the second frame traced {} of {} rays",
        second.rays,
        first.rays
    );
    assert_clean(&gpu);
}

/// The paper's global F (eq. 6), with local edits off: an edit re-keys every cell, and the old cells (the plate's
/// shadow) are never read again. Catches an edit that leaves the cells' F (`Renderer::scene_changed` not
/// setting `key_f` on a global change): the floor stays dark.
#[test]
fn edits_bump_f_and_old_cells_are_never_read() {
    let gpu = gpu();
    // A floor and, 1 unit above it, a 6 x 6 plate (its own mesh and instance, so it can move).
    let mut scene = floor_with_part(
        "plate",
        vec![quad(Vec3::ZERO, Vec3::X * 3.0, Vec3::Y * 3.0)],
        Vec3::new(0.0, 0.0, 1.0),
    );
    // Look at the floor from below the plate's height, slanted, so the shadowed floor is visible.
    let cam = z_up_camera([0.0, -9.0, 0.8], [0.0; 3], 160, 90);
    let mut sg = SceneGpu::new(&gpu, &scene).unwrap();
    let settings = {
        let mut s = hrtao(8, 4.0);
        s.edits.local_edits = false;
        s
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
    let mut map_f = 0;
    for _ in 0..3 {
        map_f = r.render(&sg, scene.f(), &cam).unwrap().map_f;
    }
    let gb = r.read_gbuffer().unwrap();
    let under: Vec<usize> = (0..gb.len())
        .filter(|&i| {
            let p = gb[i];
            p.t > 0.0
                && p.normal[2] > 0.99
                && p.position[0].abs() < 1.5
                && p.position[1].abs() < 1.5
                && p.position[2] < 0.01
        })
        .collect();
    assert!(under.len() > 50, "floor pixels under the plate: {}", under.len());
    let mean = |ao: &[f32]| under.iter().map(|&i| ao[i]).sum::<f32>() / under.len() as f32;
    let before = mean(&r.read_ao().unwrap());
    // Move the plate far away: F is bumped, the TLAS rebuilt.
    let f0 = scene.f();
    scene
        .set_transform(1, Mat4::from_translation(Vec3::new(500.0, 500.0, 1.0)))
        .unwrap();
    assert_eq!(scene.f(), f0.wrapping_add(1));
    sg.update_instances(&scene, u32::MAX).unwrap();
    let mut after = 0.0;
    for _ in 0..3 {
        let rep = r.render(&sg, scene.f(), &cam).unwrap();
        assert_eq!(rep.scene_f, scene.f());
        assert_eq!(
            rep.map_f,
            map_f.wrapping_add(1),
            "the edit re-keys every cell (global F)"
        );
        after = mean(&r.read_ao().unwrap());
    }
    println!("floor under the plate: AO {before:.3} before the edit, {after:.3} after moving the plate away");
    assert!(before < 0.6, "the plate darkens the floor ({before})");
    assert!(after > 0.97, "the freed floor is open again ({after})");
    // Every cell a pixel uses holds its key of the new F.
    check_map(&r, &sg, &cam, scene.f(), None);
    assert_clean(&gpu);
}

#[test]
fn overloaded_map_stays_finite_and_falls_back_to_coarser_levels() {
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("cycloidal", 320, 180);
    let reference = reference(&gpu, &scene, &cam, radius, 32, 4);
    // How many cells this view needs, with room to spare.
    // Small cells (s_p = 1.5) so the view needs many of them.
    let base = {
        let mut s = hrtao(4, radius);
        s.map.s_p = 1.5;
        s
    };
    let mut roomy = Headless::new(&gpu, cam.width, cam.height, base.clone()).unwrap();
    let need = roomy.render(&sg, scene.f(), &cam).unwrap().occupied_cells;
    let capacity = (need / 10 + 1).next_power_of_two() / 2;
    let overload = need as f32 / capacity as f32;
    let settings = {
        let mut s = base;
        s.map.hash_capacity = capacity;
        s
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
    let mut failed = 0;
    for _ in 0..4 {
        let before = r.read_hash_cells().unwrap();
        let rep = r.render(&sg, scene.f(), &cam).unwrap();
        failed += rep.failed_inserts;
        check_map(&r, &sg, &cam, scene.f(), Some(&before));
    }
    let ao = r.read_ao().unwrap();
    assert!(ao.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
    let lods = r.read_lod_used().unwrap();
    let coarse = lods.iter().filter(|&&l| l > 0 && l < gpu::LOD_COUNT).count();
    let err = mae(&ao, &reference);
    let roomy_err = mae(&roomy.read_ao().unwrap(), &reference);
    println!(
        "{need} cells needed, capacity {capacity} ({overload:.1}x overload): {failed} failed inserts over 4 frames, \
         {coarse} pixels on coarser levels, MAE {err:.4} (vs {roomy_err:.4} with room)"
    );
    assert!(overload >= 10.0);
    assert!(failed > 1000, "failures are counted");
    assert!(coarse > 1000, "pixels fall back to coarser levels");
    assert!(err < 0.1, "the overloaded image stays sane: MAE {err}");
    assert_clean(&gpu);
}

#[test]
fn debug_views_show_cells_lods_and_samples() {
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("cycloidal", 160, 90);
    let mut r = Headless::new(&gpu, cam.width, cam.height, hrtao(4, radius)).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    let mut colours = Vec::new();
    for mode in [
        hrtao_core::Mode::DebugCells,
        hrtao_core::Mode::DebugLod,
        hrtao_core::Mode::DebugSamples,
    ] {
        r.set_settings({
            let mut s = r.settings.clone();
            s.display.mode = mode;
            s
        })
        .unwrap();
        r.render(&sg, scene.f(), &cam).unwrap();
        let rgba = r.read_rgba().unwrap();
        let distinct: std::collections::HashSet<&[u8]> = rgba.chunks(4).collect();
        colours.push(distinct.len());
    }
    println!(
        "distinct colours: cells {}, LOD {}, samples {}",
        colours[0], colours[1], colours[2]
    );
    assert!(colours[0] > 200, "hash cells in false colours");
    assert!(colours[1] >= 2, "at least the background and one LOD");
    assert!(colours[2] > 5, "a samples heat map");
    // The cell view agrees with the cell finder: two pixels in the same cell share a colour.
    assert_clean(&gpu);
}

#[test]
fn stale_cells_are_reclaimed_so_the_map_never_fills() {
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("cycloidal", 160, 90);
    // A small map and a short cache lifetime (2 s, frames 1 s apart: 2 frames); the camera visits new places
    // every frame.
    let settings = {
        let mut s = hrtao(1, radius);
        s.map.hash_capacity = 8192;
        s.map.cache_lifetime_s = 2.0;
        s
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
    r.fps = Some(1.0);
    let (mut reclaimed, mut last_failed) = (0, 0);
    for i in 0..12 {
        let mut c = cam;
        let a = i as f32 * 0.5;
        c.eye = [
            cam.eye[0] * a.cos() - cam.eye[1] * a.sin(),
            cam.eye[0] * a.sin() + cam.eye[1] * a.cos(),
            cam.eye[2] * (1.0 + 0.2 * (i % 3) as f32),
        ];
        let before = r.read_hash_cells().unwrap();
        let rep = r.render(&sg, scene.f(), &c).unwrap();
        reclaimed += rep.reclaimed;
        last_failed = rep.failed_inserts;
        check_map(&r, &sg, &c, scene.f(), Some(&before));
    }
    println!("8192-cell map, 12 views: {reclaimed} cells reclaimed, {last_failed} failed inserts in the last frame");
    assert!(reclaimed > 1000, "stale cells must be reused");
    assert_clean(&gpu);
}

#[test]
fn map_stays_consistent_under_edits_stale_cells_and_overload() {
    // A 10x overloaded map, a short staleness window, a camera that moves and rests, and edits that bump F:
    // after every frame each pixel's cells hold its keys, no key is held twice, no live cell was reset and
    // every counter is within its bound.
    let gpu = gpu();
    let (mut scene, cam, radius) = shared_scene("rod", 320, 180);
    let mut sg = SceneGpu::new(&gpu, &scene).unwrap();
    let base = {
        let mut s = hrtao(4, radius);
        s.map.s_p = 1.0;
        s
    };
    let need = Headless::new(&gpu, cam.width, cam.height, base.clone())
        .unwrap()
        .render(&sg, scene.f(), &cam)
        .unwrap()
        .occupied_cells;
    // The largest power of two at most a tenth of the need (the map's smallest size is 1024).
    let capacity = (1u32 << (31 - (need / 10).max(1).leading_zeros())).max(1024);
    let mut r = Headless::new(&gpu, cam.width, cam.height, {
        let mut s = base;
        s.map.hash_capacity = capacity;
        // 3 s, frames 1 s apart: 3 frames.
        s.map.cache_lifetime_s = 3.0;
        s
    })
    .unwrap();
    r.fps = Some(1.0);
    let start = scene.instances[0].transform;
    let (mut failed, mut reclaimed, mut live) = (0u64, 0u64, 0usize);
    for i in 0..16u32 {
        if i % 5 == 4 {
            let lift = Mat4::from_translation(Vec3::new(0.0, 0.0, (i % 2) as f32 * 5.0));
            scene.set_transform(0, lift * start).unwrap();
            sg.update_instances(&scene, u32::MAX).unwrap();
        }
        let mut c = cam;
        if (i / 3) % 2 == 1 {
            c.eye[0] += i as f32 * 3.0;
        }
        let before = r.read_hash_cells().unwrap();
        let rep = r.render(&sg, scene.f(), &c).unwrap();
        failed += rep.failed_inserts as u64;
        reclaimed += rep.reclaimed as u64;
        live = check_map(&r, &sg, &c, scene.f(), Some(&before)).live_cells;
    }
    println!(
        "{need} cells needed, capacity {capacity}: {failed} failed inserts, {reclaimed} reclaimed, {live} live cells at the end"
    );
    assert!(
        need >= 10 * capacity,
        "the map is overloaded ({need} for {capacity})"
    );
    assert!(failed > 0 && reclaimed > 0, "overload and reclaims happened");
    assert_clean(&gpu);
}

#[test]
fn a_still_view_converges_and_then_reports_it() {
    // Refinement: converged once every pixel has still_samples rays of its own (own rays start at the second
    // still frame); the paper's behaviour: once no cell takes rays. A camera move starts over.
    let (gpu, scene, cam, radius, sg) = shared_scene_gpu("rod", 160, 90);
    let settings = {
        let mut s = hrtao(8, radius);
        s.still.still_samples = 32;
        s
    };
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings.clone()).unwrap();
    let done: Vec<bool> = (0..6)
        .map(|_| r.render(&sg, scene.f(), &cam).unwrap().converged)
        .collect();
    // Frames 1..=5 give 0, 8, 16, 24, 32 own rays per pixel.
    assert_eq!(done, [false, false, false, false, true, true]);
    // The final image can be shown again without rendering, until anything it depends on changes.
    assert!(r.shows_final(&sg, scene.f(), &cam));
    let mut moved = cam;
    moved.eye[2] += 1.0;
    assert!(!r.shows_final(&sg, scene.f(), &moved));
    let mut sg = sg;
    sg.update_instances(&scene, 0).unwrap(); // a selection: same F, other instance flags
    assert!(
        !r.shows_final(&sg, scene.f(), &cam),
        "instance updates invalidate the image"
    );
    assert!(!r.render(&sg, scene.f(), &moved).unwrap().converged);
    let mut paper = Headless::new(&gpu, cam.width, cam.height, {
        let mut s = settings;
        s.still.refine = false;
        s.map.max_samples = 64;
        s
    })
    .unwrap();
    let mut frames = 0;
    while !paper.render(&sg, scene.f(), &cam).unwrap().converged {
        frames += 1;
        assert!(frames < 64, "the paper's behaviour ends once every cell is full");
    }
    assert_eq!(paper.render(&sg, scene.f(), &cam).unwrap().rays, 0);
    assert_clean(&gpu);
}
