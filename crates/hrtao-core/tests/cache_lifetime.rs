//! The cache lifetime on the GPU (issue #49, item 3): a region revisited within `cache_lifetime_s` seconds finds
//! its cells at any frame rate, and while the table has room a region revisited after it finds them too.
//!
//! Both tests look at a few blocks on a large floor (view A), pan over the bare floor far from them (view B: new
//! cells every frame), and come back to A, in a 4096-cell table at 64x36 pixels with simulated frame times
//! (`FrameDesc::at`, `Headless::fps`). They compare A's cells (slot and key of every cell A's pixels use) before
//! and after the detour.
mod common;

use common::*;
use hrtao_core::gpu::{self, HashCell};
use hrtao_core::{AoSettings, Camera, SceneGpu};
use hrtao_scene::glam::Vec3;

const CAPACITY: u32 = 1 << 12;
/// The finest cells are 2 units (a quarter of the radius: `cell_cap`), about 3 pixels.
const RADIUS: f32 = 8.0;

/// Three blocks on a 2000 x 2000 floor.
fn blocks_on_a_large_floor() -> hrtao_scene::Scene {
    row_of_blocks(quad(Vec3::ZERO, Vec3::X * 1000.0, Vec3::Y * 1000.0), 3, 6.0)
}

/// A top-down 64x36 view from 20 units up, centred on x.
fn view_at(x: f32) -> Camera {
    Camera {
        eye: [x, 0.0, 20.0],
        target: [x, 0.0, 0.0],
        ..top_down_camera(20.0, 64, 36)
    }
}

fn settings(lifetime_s: f32) -> AoSettings {
    let mut s = hrtao(2, RADIUS);
    s.map.hash_capacity = CAPACITY;
    s.map.cache_lifetime_s = lifetime_s;
    // The AO the cells give, not each pixel's own refinement: the revisit compares cells.
    s.still.refine = false;
    s
}

/// The (slot, cell) of every cell the last frame's pixels use.
fn cells_in_use(r: &Headless) -> Vec<(u32, HashCell)> {
    let cells = r.read_hash_cells().unwrap();
    let mut used: Vec<u32> = r
        .read_pixel_cells()
        .unwrap()
        .iter()
        .flat_map(|pc| pc.cells)
        .filter(|&c| c != gpu::INVALID_CELL)
        .collect();
    used.sort_unstable();
    used.dedup();
    used.into_iter().map(|c| (c, cells[c as usize])).collect()
}

/// What a detour did to view A: cells of A that lost their key, and the cells A's first frame back claimed.
struct Revisit {
    a_cells: usize,
    lost: usize,
    claimed: u32,
    /// Failed inserts of each frame of the detour.
    failed_during_b: Vec<u32>,
    /// Cells the detour's frames after the 240th claimed (inserted or reclaimed).
    claimed_after_240: u64,
    /// Slots taken at the end of the detour.
    occupied: u32,
    ao_change: f32,
}

/// View A for 3 frames, `b_frames` frames panning over the floor from x = 60 (`step` units a frame), then A
/// again, at `fps` simulated frames per second.
fn detour(fps: f64, lifetime_s: f32, b_frames: u32, step: f32) -> Revisit {
    let gpu = gpu();
    let scene = blocks_on_a_large_floor();
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    let mut r = Headless::new(&gpu, 64, 36, settings(lifetime_s)).unwrap();
    r.fps = Some(fps);
    let a = view_at(0.0);
    for _ in 0..3 {
        r.render(&sg, scene.f(), &a).unwrap();
    }
    let before = cells_in_use(&r);
    let ao_before = r.read_ao().unwrap();
    let (mut failed_during_b, mut claimed_after_240, mut occupied) = (Vec::new(), 0u64, 0);
    for i in 0..b_frames {
        let rep = r
            .render(&sg, scene.f(), &view_at(60.0 + step * i as f32))
            .unwrap();
        failed_during_b.push(rep.failed_inserts);
        occupied = rep.occupied_cells;
        if i >= 240 {
            claimed_after_240 += (rep.cells_inserted + rep.reclaimed) as u64;
        }
    }
    let back = r.render(&sg, scene.f(), &a).unwrap();
    let cells = r.read_hash_cells().unwrap();
    let lost = before
        .iter()
        .filter(|(slot, c)| cells[*slot as usize].checksum() != c.checksum())
        .count();
    let ao_change = mae(&r.read_ao().unwrap(), &ao_before);
    check_map(&r, &sg, &a, scene.f(), None);
    assert_clean(&gpu);
    Revisit {
        a_cells: before.len(),
        lost,
        claimed: back.cells_inserted + back.reclaimed,
        failed_during_b,
        claimed_after_240,
        occupied,
        ao_change,
    }
}

/// View A, then 300 frames (2.1 s) of view B at a simulated 144 fps, then A again: within the default 30 s
/// lifetime, A's cells are all found, none claimed again, and A's AO is what it was. B pans slowly enough for
/// the table to hold everything (no failed insert, so the lifetime holds whole) but takes it past its room
/// (stale slots are recycled first), and claims cells after its 240th frame. Fails on the frame-counted rule
/// (A's cells stale after 240 frames, recycled by B's inserts): mutation `FrameClock::lifetime_frames`
/// returning 240 (72 of A's cells lost); with `take_free = free_slot != INVALID_CELL && stale == INVALID_CELL`
/// in hash_map.glsl too (the code before this change) it fails as well.
#[test]
fn a_view_revisited_within_the_lifetime_at_144_fps_is_found_not_retraced() {
    let v = detour(144.0, AoSettings::default().map.cache_lifetime_s, 300, 0.75);
    let failed: u32 = v.failed_during_b.iter().sum();
    println!(
        "144 fps, 300 frames away: {} cells of A, {} lost, {} claimed on return, {} claimed by B after its 240th \
         frame, {failed} failed inserts during B, {} of {CAPACITY} slots taken, AO change {:.4}",
        v.a_cells, v.lost, v.claimed, v.claimed_after_240, v.occupied, v.ao_change
    );
    assert!(v.a_cells > 200, "A uses {} cells", v.a_cells);
    assert_eq!(failed, 0, "the table holds the detour");
    assert!(
        v.occupied > CAPACITY / 2,
        "past its room: only the lifetime keeps A's cells"
    );
    assert!(v.claimed_after_240 > 100, "B claims cells after its 240th frame");
    assert_eq!(v.lost, 0, "A's cells were reclaimed");
    assert_eq!(v.claimed, 0, "A's return claimed cells");
    assert!(v.ao_change < 0.02, "A's AO changed by {}", v.ao_change);
}

/// A detour that overflows the table (a fast pan at 144 fps: the table fills with cells used within the 30 s
/// lifetime): the lifetime yields (`TableLoad::lifetime_fraction`), the least recently used cells are recycled,
/// and the view's inserts stop failing: over the 300 frames fewer inserts fail than one frame has pixels.
/// Fails when the lifetime never yields (`self.halvings = ...` removed from `TableLoad::finish_frame`: every
/// frame after the table fills fails about half its inserts).
#[test]
fn a_detour_that_overflows_the_table_recycles_its_oldest_cells() {
    let v = detour(144.0, AoSettings::default().map.cache_lifetime_s, 300, 2.0);
    let first_full = v
        .failed_during_b
        .iter()
        .position(|&f| f > 0)
        .expect("the table overflows");
    let total: u32 = v.failed_during_b.iter().sum();
    let last: u32 = v.failed_during_b[200..].iter().sum();
    println!(
        "144 fps, fast pan: table full at frame {first_full}, {total} failed inserts in all, {last} in the last \
         100 frames; {} of A's {} cells recycled",
        v.lost, v.a_cells
    );
    assert!(total < 64 * 36, "inserts keep failing: {total}");
    assert!(last < 100, "inserts keep failing: {last} in the last 100 frames");
}

/// Past the lifetime, while the table has room: a 1 s lifetime, view A, then 3 s of view B at a simulated
/// 10 fps (30 frames, panning 1 unit a frame: A's cells are stale for the last 20), then A again. B's inserts
/// take the free slots that end their runs, so A's stale cells keep their keys and AO. Fails when inserts take
/// the first stale slot whatever the room (`take_free = free_slot != INVALID_CELL && stale == INVALID_CELL` in
/// hash_map.glsl `find_or_insert`, the rule before FLAG_MAP_HAS_ROOM).
#[test]
fn a_view_revisited_after_the_lifetime_is_found_while_the_table_has_room() {
    let v = detour(10.0, 1.0, 30, 1.0);
    println!(
        "10 fps, 1 s lifetime, 3 s away: {} cells of A, {} lost, {} claimed on return, AO change {:.4}",
        v.a_cells, v.lost, v.claimed, v.ao_change
    );
    assert!(v.a_cells > 200, "A uses {} cells", v.a_cells);
    assert_eq!(v.failed_during_b.iter().sum::<u32>(), 0);
    assert_eq!(
        v.lost, 0,
        "A's stale cells were reclaimed although the table had room"
    );
    assert_eq!(v.claimed, 0, "A's return claimed cells");
}
