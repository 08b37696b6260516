//! 3MF: assimp's box.3mf (fetched from Debian's assimp-testmodels by scripts/fetch-assimp-models.sh) opens with
//! its unit; rod.glb written as 3MF (one object per mesh, one build item per instance) loads back to rod's
//! instances and geometry; broken archives are clear errors.
mod common;

use std::path::PathBuf;

use glam::Vec3;

#[path = "common/threemf.rs"]
mod threemf_writer;

fn assimp_models() -> PathBuf {
    common::fetched_data("fetch-assimp-models.sh", "apt-get and Debian's assimp-testmodels")
}

/// assimp's box: one 10 × 20 × 30 mm box of 12 triangles, in millimetres. Fails with the unit dropped.
#[test]
fn assimps_box_opens_with_its_unit() {
    let path = assimp_models().join("3MF/box.3mf");
    let s = hrtao_scene::load(path.to_str().unwrap(), &mut |_| {}).unwrap();
    assert_eq!(s.unit_m, Some(1e-3));
    assert_eq!((s.unique_triangle_count(), s.instances.len()), (12, 1));
    let b = s.bounds();
    assert!(
        (b.max - b.min - Vec3::new(10.0, 20.0, 30.0)).abs().max_element() < 1e-4,
        "{b:?}"
    );
}

/// Per instance, the area-weighted centroid of its world-space triangles and their area (what smoothing, which
/// welds and splits vertices, leaves alone).
fn instance_moments(s: &hrtao_scene::Scene) -> Vec<(Vec3, f32)> {
    s.instances
        .iter()
        .map(|i| {
            let (mut c, mut area) = (Vec3::ZERO, 0.0);
            for p in &s.meshes[i.mesh as usize].primitives {
                let at = |k: u32| i.transform.transform_point3(Vec3::from(p.positions[k as usize]));
                for t in p.indices.chunks_exact(3) {
                    let (a, b, d) = (at(t[0]), at(t[1]), at(t[2]));
                    let w = (b - a).cross(d - a).length() / 2.0;
                    c += w * (a + b + d) / 3.0;
                    area += w;
                }
            }
            (c / area.max(1e-30), area)
        })
        .collect()
}

/// rod.glb as 3MF: 29 build items of 3 objects load as 29 instances of 3 meshes, each where rod.glb has it
/// (transforms composed in the 3MF's row-vector order), in rod.glb's colours (base materials). Fails with
/// the transform read transposed (vertices move), with one mesh per build item (instancing lost) and without
/// `threemf_colors` (the default grey).
#[test]
fn rod_as_3mf_loads_to_rods_instances_and_geometry() {
    let rod = hrtao_scene::load(common::test_scene("rod").to_str().unwrap(), &mut |_| {}).unwrap();
    let dir = common::temp_dir("threemf");
    let path = dir.join("rod.3mf");
    threemf_writer::write_3mf(&rod, &path, "millimeter");
    let s = hrtao_scene::load(path.to_str().unwrap(), &mut |_| {}).unwrap();
    assert_eq!(s.instances.len(), 29);
    assert_eq!(
        s.meshes.len(),
        rod.meshes.len(),
        "one mesh per object: instancing kept"
    );
    assert_eq!(s.unique_triangle_count(), rod.unique_triangle_count());
    assert_eq!(s.unit_m, Some(1e-3));
    for (k, ((c, a), (d, b))) in instance_moments(&s)
        .into_iter()
        .zip(instance_moments(&rod))
        .enumerate()
    {
        assert!(
            (c - d).length() < 1e-3,
            "instance {k} moved by {}",
            (c - d).length()
        );
        assert!((a / b - 1.0).abs() < 1e-4, "instance {k}: area {a} against {b}");
    }
    for m in &s.meshes {
        assert_eq!(
            m.primitives[0].normals.len(),
            m.primitives[0].positions.len(),
            "smoothed normals"
        );
    }
    assert_eq!(s.tree.len(), 30, "the file's node and its 29 build items");
    // Each object's base material (its sRGB display colour) is its mesh's colour.
    for m in &s.meshes {
        let want = rod
            .meshes
            .iter()
            .find(|r| r.name == m.name)
            .unwrap_or_else(|| panic!("mesh {} of rod.glb", m.name))
            .primitives[0]
            .base_color;
        let got = m.primitives[0].base_color;
        assert!(
            (0..4).all(|c| (got[c] - want[c]).abs() < 0.005),
            "{}: colour {got:?}, rod.glb's {want:?}",
            m.name
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Not a zip, a zip without a model part, a truncated archive and a triangle naming a missing vertex are
/// errors that say so, never panics.
#[test]
fn broken_3mf_files_are_clear_errors() {
    let dir = common::temp_dir("threemf-bad");
    let rod = hrtao_scene::load(common::test_scene("rod").to_str().unwrap(), &mut |_| {}).unwrap();
    let good = dir.join("good.3mf");
    threemf_writer::write_3mf(&rod, &good, "millimeter");
    let bytes = std::fs::read(&good).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("text.3mf", b"solid not a zip".to_vec(), "not a 3MF archive"),
        ("truncated.3mf", bytes[..bytes.len() / 2].to_vec(), "3MF"),
    ];
    for (name, data, needle) in cases {
        let p = dir.join(name);
        std::fs::write(&p, data).unwrap();
        let e = hrtao_scene::load(p.to_str().unwrap(), &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "{name}: {e}");
    }
    // A triangle naming vertex 999999.
    let mut one = hrtao_scene::Scene::new("one");
    one.meshes = vec![rod.meshes[0].clone()];
    one.meshes[0].primitives.truncate(1);
    one.meshes[0].primitives[0].indices[0] = 999_999;
    one.instances = vec![rod.instances[0].clone()];
    one.instances[0].mesh = 0;
    let p = dir.join("index.3mf");
    threemf_writer::write_3mf(&one, &p, "millimeter");
    let e = hrtao_scene::load(p.to_str().unwrap(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 999999"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
