//! The real-world test scenes (testdata/README.md) load with the facts counted by independent loaders (trimesh,
//! pygltflib and the `gltf` crate): triangles, meshes, instances, bounds; as GLB and as .gltf + external .bin.

mod common;

use common::{no_progress, split_glb, temp_dir, test_scene};
use hrtao_scene::{glam::Vec3, load, Scene};

struct Expected {
    key: &'static str,
    unique: u64,
    instanced: u64,
    meshes: usize,
    instances: usize,
    min: [f32; 3],
    max: [f32; 3],
    /// Rounding step of the bounds printed in SOURCES.md.
    step: f32,
}

fn check(e: &Expected) -> Scene {
    let glb = check_file(e, &test_scene(e.key));
    // The same scene with its buffer in a separate file (uri resolution, external reads).
    let dir = temp_dir(&format!("split-{}", e.key));
    let gltf = check_file(e, &split_glb(&test_scene(e.key), &dir, e.key));
    assert_eq!(gltf.meshes.len(), glb.meshes.len());
    for (a, b) in gltf.meshes.iter().zip(&glb.meshes) {
        assert_eq!(a.primitives.len(), b.primitives.len(), "{}", e.key);
        for (p, q) in a.primitives.iter().zip(&b.primitives) {
            assert_eq!(p.positions, q.positions, "{}: positions", e.key);
            assert_eq!(p.indices, q.indices, "{}: indices", e.key);
            assert_eq!(p.base_color, q.base_color, "{}: colour", e.key);
        }
    }
    let _ = std::fs::remove_dir_all(dir);
    glb
}

fn check_file(e: &Expected, path: &std::path::Path) -> Scene {
    let file = path.display();
    let mut stages = Vec::new();
    let scene = load(path.to_str().unwrap(), &mut |p| stages.push(p)).unwrap_or_else(|err| {
        panic!("{}: {err}", path.display());
    });
    assert_eq!(scene.unique_triangle_count(), e.unique, "{}: unique tris", file);
    assert_eq!(
        scene.instanced_triangle_count(),
        e.instanced,
        "{}: instanced tris",
        file
    );
    assert_eq!(scene.meshes.len(), e.meshes, "{}: meshes", file);
    assert_eq!(scene.instances.len(), e.instances, "{}: nodes with mesh", file);
    scene.validate().unwrap();

    let b = scene.bounds();
    let (min, max) = (Vec3::from(e.min), Vec3::from(e.max));
    let diag = (max - min).length();
    for (got, want, what) in [(b.min, min, "min"), (b.max, max, "max")] {
        // ~1e-2 relative to the scene size, and in fact within the printed rounding.
        assert!(
            (got - want).length() <= 1e-2 * diag,
            "{}: {what} {got} vs {want}",
            file
        );
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() <= e.step * 0.5 + 1e-4 * want[k].abs() + 1e-5,
                "{}: {what}[{k}] {} vs {}",
                file,
                got[k],
                want[k]
            );
        }
    }

    let last_mesh = stages.iter().rfind(|p| p.stage == "meshes").unwrap();
    assert_eq!(last_mesh.done, last_mesh.total);
    assert_eq!(last_mesh.total, e.meshes as u64);
    assert_eq!(scene.f(), 0);
    assert!(scene.instances.iter().all(|i| i.visible));
    scene
}

#[test]
fn cycloidal_gearbox() {
    let s = check(&Expected {
        key: "cycloidal",
        unique: 61_442,
        instanced: 376_520,
        meshes: 13,
        instances: 72,
        min: [-53.886, -53.873, -28.275],
        max: [53.814, 53.860, 3.650],
        step: 0.001,
    });
    assert!(s.instances.len() > s.meshes.len());
    // No materials, only COLOR_0: colours come from the vertex colours, not the default.
    assert!(s
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .any(|p| p.base_color != hrtao_scene::DEFAULT_BASE_COLOR));
    // Max refs 20.
    let mut refs = vec![0usize; s.meshes.len()];
    for i in &s.instances {
        refs[i.mesh as usize] += 1;
    }
    assert_eq!(refs.iter().max(), Some(&20));
}

#[test]
fn rod_assembly() {
    let s = check(&Expected {
        key: "rod",
        unique: 5_412,
        instanced: 57_036,
        meshes: 3,
        instances: 29,
        min: [-21.134, -9.384, -103.784],
        max: [55.066, 66.783, 63.960],
        step: 0.001,
    });
    let mut refs = vec![0usize; s.meshes.len()];
    for i in &s.instances {
        refs[i.mesh as usize] += 1;
    }
    assert!(refs.iter().all(|&r| r > 1), "all 3 meshes reused: {refs:?}");
    assert_eq!(refs.iter().max(), Some(&13));
}

#[test]
fn hiding_an_instance_changes_counts_and_frame() {
    let mut s = hrtao_scene::load_gltf(&test_scene("rod"), &mut no_progress()).unwrap();
    let before = s.instanced_triangle_count();
    let tris = s.meshes[s.instances[0].mesh as usize].triangle_count();
    s.set_visible(0, false).unwrap();
    assert_eq!(s.instanced_triangle_count(), before - tris);
    assert_eq!(s.unique_triangle_count(), 5_412);
    assert_eq!(s.f(), 1);
}
