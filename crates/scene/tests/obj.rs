//! OBJ loading: triangulation, one mesh per model, .mtl colours, missing .mtl tolerated.

mod common;

use common::{no_progress, temp_dir};
use hrtao_scene::{load, load_obj, DEFAULT_BASE_COLOR};

const OBJ: &str = "mtllib tiny.mtl
o quad
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
usemtl red
f 1 2 3 4
o tri
v 0 0 1
v 1 0 1
v 0 1 1
usemtl blue
f 5 6 7
";

const MTL: &str = "newmtl red
Kd 0.9 0.1 0.1
newmtl blue
Kd 0.1 0.2 0.8
";

#[test]
fn obj_with_mtl() {
    let dir = temp_dir("obj_mtl");
    std::fs::write(dir.join("tiny.obj"), OBJ).unwrap();
    std::fs::write(dir.join("tiny.mtl"), MTL).unwrap();
    let s = load(dir.join("tiny.obj").to_str().unwrap(), &mut no_progress()).unwrap();
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.instances.len(), 2);
    assert_eq!(s.unique_triangle_count(), 3);
    assert_eq!(s.instanced_triangle_count(), 3);
    let quad = s.meshes.iter().find(|m| m.name == "quad").unwrap();
    assert_eq!(quad.triangle_count(), 2);
    assert_eq!(quad.primitives[0].base_color, [0.9, 0.1, 0.1, 1.0]);
    let tri = s.meshes.iter().find(|m| m.name == "tri").unwrap();
    assert_eq!(tri.primitives[0].base_color, [0.1, 0.2, 0.8, 1.0]);
    let b = s.bounds();
    assert_eq!(b.min.to_array(), [0.0, 0.0, 0.0]);
    assert_eq!(b.max.to_array(), [1.0, 1.0, 1.0]);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn obj_without_mtl_uses_default_colour() {
    let dir = temp_dir("obj_nomtl");
    std::fs::write(dir.join("tiny.obj"), OBJ).unwrap();
    let s = load_obj(&dir.join("tiny.obj"), &mut no_progress()).unwrap();
    assert_eq!(s.unique_triangle_count(), 3);
    for m in &s.meshes {
        assert_eq!(m.primitives[0].base_color, DEFAULT_BASE_COLOR);
    }
    let _ = std::fs::remove_dir_all(dir);
}
