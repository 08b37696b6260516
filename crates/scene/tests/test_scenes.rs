//! The six shared real-world scenes must match /work/shared/scenes/SOURCES.md exactly.

mod common;

use common::{no_progress, shared_scenes};
use hrtao_scene::{glam::Vec3, load, Scene};

struct Expected {
    file: &'static str,
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
    let path = shared_scenes().join(e.file);
    let mut stages = Vec::new();
    let scene = load(path.to_str().unwrap(), &mut |p| stages.push(p)).unwrap_or_else(|err| {
        panic!("{}: {err}", path.display());
    });
    assert_eq!(scene.unique_triangle_count(), e.unique, "{}: unique tris", e.file);
    assert_eq!(
        scene.instanced_triangle_count(),
        e.instanced,
        "{}: instanced tris",
        e.file
    );
    assert_eq!(scene.meshes.len(), e.meshes, "{}: meshes", e.file);
    assert_eq!(scene.instances.len(), e.instances, "{}: nodes with mesh", e.file);
    scene.validate().unwrap();

    let b = scene.bounds();
    let (min, max) = (Vec3::from(e.min), Vec3::from(e.max));
    let diag = (max - min).length();
    for (got, want, what) in [(b.min, min, "min"), (b.max, max, "max")] {
        // ~1e-2 relative to the scene size, and in fact within the printed rounding.
        assert!(
            (got - want).length() <= 1e-2 * diag,
            "{}: {what} {got} vs {want}",
            e.file
        );
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() <= e.step * 0.5 + 1e-4 * want[k].abs() + 1e-5,
                "{}: {what}[{k}] {} vs {}",
                e.file,
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
fn two_cylinder_engine() {
    let s = check(&Expected {
        file: "2CylinderEngine/2CylinderEngine.gltf",
        unique: 75_730,
        instanced: 121_496,
        meshes: 29,
        instances: 67,
        min: [-371.692, -180.972, -140.0],
        max: [371.692, 92.042, 128.0],
        step: 0.001,
    });
    let prims: usize = s.meshes.iter().map(|m| m.primitives.len()).sum();
    assert_eq!(prims, 34);
    assert!(s.instances.len() > s.meshes.len());
}

#[test]
fn cycloidal_gearbox() {
    let s = check(&Expected {
        file: "cycloidal_gearbox/cycloidal.glb",
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
        file: "rod_assembly/rod.glb",
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
fn duplex_apartment() {
    let s = check(&Expected {
        file: "duplex_apartment/duplex.glb",
        unique: 15_396,
        instanced: 26_348,
        meshes: 153,
        instances: 215,
        min: [-0.241, -1.550, -4.383],
        max: [9.041, 6.635, 22.183],
        step: 0.001,
    });
    let prims: usize = s.meshes.iter().map(|m| m.primitives.len()).sum();
    assert_eq!(prims, 170);
    assert!(s.instances.len() > s.meshes.len());
    // Glazing is translucent.
    assert!(s
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .any(|p| p.base_color[3] < 1.0));
}

#[test]
fn west_riverside_hospital_electrical() {
    let s = check(&Expected {
        file: "west_riverside_hospital_electrical/electrical.gltf",
        unique: 16_482,
        instanced: 153_990,
        meshes: 127,
        instances: 2_798,
        min: [-9.723, 164.622, -139.465],
        max: [87.083, 192.355, -47.216],
        step: 0.001,
    });
    let prims: usize = s.meshes.iter().map(|m| m.primitives.len()).sum();
    assert_eq!(prims, 147);
    let mut refs = vec![0usize; s.meshes.len()];
    for i in &s.instances {
        refs[i.mesh as usize] += 1;
    }
    assert_eq!(refs.iter().max(), Some(&1_111));
    assert_eq!(refs.iter().filter(|&&r| r > 1).count(), 27);
}

#[test]
fn san_francisco() {
    let s = check(&Expected {
        file: "san_francisco/san_francisco.glb",
        unique: 268_041,
        instanced: 268_041,
        meshes: 4_735,
        instances: 4_735,
        min: [-508.2, 0.0, -459.7],
        max: [713.5, 170.6, 468.0],
        step: 0.1,
    });
    let mut refs = vec![0usize; s.meshes.len()];
    for i in &s.instances {
        refs[i.mesh as usize] += 1;
    }
    assert!(refs.iter().all(|&r| r == 1), "each mesh used exactly once");
}

#[test]
fn hiding_an_instance_changes_counts_and_frame() {
    let path = shared_scenes().join("rod_assembly/rod.glb");
    let mut s = hrtao_scene::load_gltf(&path, &mut no_progress()).unwrap();
    let before = s.instanced_triangle_count();
    let tris = s.meshes[s.instances[0].mesh as usize].triangle_count();
    s.set_visible(0, false).unwrap();
    assert_eq!(s.instanced_triangle_count(), before - tris);
    assert_eq!(s.unique_triangle_count(), 5_412);
    assert_eq!(s.f(), 1);
}
