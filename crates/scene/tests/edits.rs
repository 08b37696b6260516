//! Every edit bumps the frame identifier F; rejected edits leave the scene and F untouched.

mod common;

use common::{no_progress, test_scene};
use hrtao_scene::glam::{Mat4, Vec3};
use hrtao_scene::{load, load_gltf, Instance, Scene, SceneError};

fn rod() -> Scene {
    load_gltf(&test_scene("rod"), &mut no_progress()).unwrap()
}

#[test]
fn set_transform_bumps_frame_and_moves_bounds() {
    let mut s = rod();
    let b0 = s.bounds();
    let t = Mat4::from_translation(Vec3::new(1000.0, 0.0, 0.0)) * s.instances[3].transform;
    s.set_transform(3, t).unwrap();
    assert_eq!(s.f(), 1);
    assert_eq!(s.instances[3].transform, t);
    assert!(s.bounds().max.x > b0.max.x + 900.0);
}

#[test]
fn set_transform_rejects_bad_matrices_without_bumping() {
    let mut s = rod();
    let before = s.instances[0].transform;
    for m in [
        Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
        Mat4::from_scale(Vec3::new(f32::INFINITY, 1.0, 1.0)),
        Mat4::ZERO,
    ] {
        let e = s.set_transform(0, m).unwrap_err();
        assert!(matches!(e, SceneError::Invalid(_)), "{e:?}");
    }
    assert_eq!(s.f(), 0);
    assert_eq!(s.instances[0].transform, before);
}

#[test]
fn set_visible_bumps_frame() {
    let mut s = rod();
    s.set_visible(0, false).unwrap();
    assert!(!s.instances[0].visible);
    s.set_visible(0, true).unwrap();
    assert_eq!(s.f(), 2);
}

#[test]
fn remove_then_insert_is_undo() {
    let mut s = rod();
    let n = s.instances.len();
    let tris = s.instanced_triangle_count();
    let original = s.instances.clone();
    let removed = s.remove_instance(5).unwrap();
    assert_eq!(s.f(), 1);
    assert_eq!(s.instances.len(), n - 1);
    assert!(s.instanced_triangle_count() < tris);
    s.insert_instance(5, removed).unwrap();
    assert_eq!(s.f(), 2);
    assert_eq!(s.instances, original);
    assert_eq!(s.instanced_triangle_count(), tris);
}

#[test]
fn add_instance_returns_new_id() {
    let mut s = rod();
    let n = s.instances.len() as u32;
    let id = s
        .add_instance(Instance {
            mesh: 0,
            transform: Mat4::from_translation(Vec3::splat(5.0)),
            name: "copy".into(),
            visible: true,
        })
        .unwrap();
    assert_eq!(id, n);
    assert_eq!(s.f(), 1);
    assert_eq!(s.instances[id as usize].name, "copy");
}

#[test]
fn out_of_range_ids_are_errors_without_bump() {
    let mut s = rod();
    let n = s.instances.len() as u32;
    let snapshot = s.instances.clone();
    let ok = |e: SceneError| matches!(e, SceneError::OutOfRange { .. });
    assert!(ok(s.set_transform(n, Mat4::IDENTITY).unwrap_err()));
    assert!(ok(s.set_visible(n, false).unwrap_err()));
    assert!(ok(s.set_visible(u32::MAX, false).unwrap_err()));
    assert!(ok(s.remove_instance(n).unwrap_err()));
    let inst = s.instances[0].clone();
    assert!(ok(s.insert_instance(n + 1, inst.clone()).unwrap_err()));
    let bad_mesh = Instance {
        mesh: s.meshes.len() as u32,
        ..inst.clone()
    };
    assert!(ok(s.add_instance(bad_mesh.clone()).unwrap_err()));
    assert!(ok(s.insert_instance(0, bad_mesh).unwrap_err()));
    let bad_tf = Instance {
        transform: Mat4::ZERO,
        ..inst
    };
    assert!(matches!(
        s.add_instance(bad_tf).unwrap_err(),
        SceneError::Invalid(_)
    ));
    assert_eq!(s.f(), 0);
    assert_eq!(s.instances, snapshot);
    s.validate().unwrap();
}

#[test]
fn bump_f_is_explicit_and_wrapping() {
    let mut s = load("gen:plane", &mut no_progress()).unwrap();
    assert_eq!(s.f(), 0);
    s.bump_f();
    s.bump_f();
    assert_eq!(s.f(), 2);
    // Insert at the end is an append.
    let inst = s.instances[0].clone();
    s.insert_instance(1, inst).unwrap();
    assert_eq!(s.instances.len(), 2);
    assert_eq!(s.f(), 3);
}
