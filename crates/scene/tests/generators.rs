//! Procedural scenes: counts, sharing, bounds and the 10^9-triangle instancing scale.

mod common;

use common::no_progress;
use hrtao_scene::{generate, load, LoadProgress};

#[test]
fn racks_reach_a_billion_instanced_triangles_cheaply() {
    // 50*50*40 = 100,000 servers with a 10,000-triangle server mesh: only three unique
    // meshes are built, the rest is 102,501 transforms.
    let mut stages: Vec<LoadProgress> = Vec::new();
    let s = load("gen:racks?rows=50&cols=50&units=40&detail=10000", &mut |p| {
        stages.push(p)
    })
    .unwrap();
    assert_eq!(s.meshes.len(), 3);
    assert_eq!(s.instances.len(), 50 * 50 * 41 + 1);
    assert!(
        s.instanced_triangle_count() >= 1_000_000_000,
        "{}",
        s.instanced_triangle_count()
    );
    assert!(s.unique_triangle_count() < 20_000);
    let server = s.meshes[0].triangle_count();
    assert_eq!(server, 10_000);
    assert!(stages.iter().any(|p| p.stage == "instances" && p.done == p.total));
    assert!(stages.iter().any(|p| p.stage == "meshes" && p.done == p.total));
    s.validate().unwrap();
}

#[test]
fn racks_paper_scale_example() {
    let s = generate(
        "gen:racks?rows=100&cols=100&units=40&detail=2500",
        &mut no_progress(),
    )
    .unwrap();
    assert!(s.instanced_triangle_count() >= 1_000_000_000);
    assert_eq!(s.instances.len(), 100 * 100 * 41 + 1);
}

#[test]
fn racks_defaults_and_layout() {
    let s = load("gen:racks", &mut no_progress()).unwrap();
    assert_eq!(s.instances.len(), 25 * 100 * 41 + 1);
    assert!(s.instances.len() > s.meshes.len());
    let b = s.bounds();
    // Z-up, on the floor, 40U rack about 2 m tall.
    assert!(b.min.z >= -0.11 && b.min.z < 0.0, "{b:?}");
    assert!(b.max.z > 1.8 && b.max.z < 2.5, "{b:?}");
    assert!(b.diagonal().x > 50.0 && b.diagonal().y > 50.0);
    // Server meshes stay inside their racks: the small scene's servers are within bounds.
    let small = load("gen:racks?rows=2&cols=1&units=2&detail=24", &mut no_progress()).unwrap();
    assert_eq!(small.instances.len(), 2 * 3 + 1);
    assert_eq!(small.meshes[0].triangle_count(), 24);
}

#[test]
fn city_blocks() {
    let s = load("gen:city?blocks=3&per_block=2&variants=4", &mut no_progress()).unwrap();
    assert_eq!(s.meshes.len(), 4 + 2);
    assert_eq!(s.instances.len(), 3 * 3 * (4 + 1) + 1);
    assert!(s.instanced_triangle_count() > s.unique_triangle_count());
    let b = s.bounds();
    assert!(b.min.z >= -1e-6 && b.max.z > 10.0, "{b:?}");
    assert!(b.diagonal().x >= 300.0);
    // Deterministic for the same seed, different for another seed.
    let again = load("gen:city?blocks=3&per_block=2&variants=4", &mut no_progress()).unwrap();
    assert_eq!(again.instances, s.instances);
    let other = load(
        "gen:city?blocks=3&per_block=2&variants=4&seed=7",
        &mut no_progress(),
    )
    .unwrap();
    assert_ne!(other.instances, s.instances);
}

#[test]
fn box_plane_slab() {
    let b = load("gen:box", &mut no_progress()).unwrap();
    assert_eq!(b.unique_triangle_count(), 10);
    let bb = b.bounds();
    assert_eq!(bb.min.to_array(), [-1.0, -1.0, 0.0]);
    assert_eq!(bb.max.to_array(), [1.0, 1.0, 2.0]);

    let p = load("gen:plane?size=50", &mut no_progress()).unwrap();
    assert_eq!(p.unique_triangle_count(), 2);
    assert_eq!(p.bounds().max.to_array(), [25.0, 25.0, 0.0]);

    let s = load("gen:slab?h=2.5", &mut no_progress()).unwrap();
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.instances.len(), 2);
    let slab = s
        .mesh_bounds(s.instances[1].mesh)
        .transformed(&s.instances[1].transform);
    assert!((slab.min.z - 2.5).abs() < 1e-6);
    assert_eq!(s.bounds().min.z, 0.0);
    assert_eq!(s.name, "gen:slab?h=2.5");
}
