//! The model tree: glTF node hierarchies and OBJ objects/groups are kept (names, parents, instances per
//! node), generated/STL scenes get one node, and edits keep the tree consistent.

mod common;

use common::{no_progress, temp_dir, write_gltf, TRI};
use hrtao_scene::{load, NodeTree};

/// (name, parent name, own instance count) of every node.
fn shape(t: &NodeTree) -> Vec<(String, Option<String>, usize)> {
    t.nodes
        .iter()
        .map(|n| {
            (
                n.name.clone(),
                n.parent.map(|p| t.nodes[p as usize].name.clone()),
                n.instances.len(),
            )
        })
        .collect()
}

fn s(v: &str) -> String {
    v.to_string()
}

#[test]
fn gltf_hierarchy_keeps_names_parents_and_instance_counts() {
    let dir = temp_dir("tree_gltf");
    // assembly ─ left (mesh) ─ bolt (mesh) ; right ─ bolt2 (mesh) ; camera (no mesh, dropped) ; lone (mesh, root)
    let nodes = r#"[
        {"name":"assembly","children":[1,3,5]},
        {"name":"left","mesh":0,"children":[2]},
        {"name":"bolt","mesh":0,"translation":[0,0,1]},
        {"name":"right","children":[4],"translation":[5,0,0]},
        {"name":"bolt2","mesh":0},
        {"name":"camera"},
        {"name":"lone","mesh":0}
    ]"#;
    let path = write_gltf(
        &dir,
        "tree.gltf",
        &TRI,
        None,
        nodes,
        r#""scenes":[{"nodes":[0,6]}],"scene":0,"#,
    );
    let scene = load(path.to_str().unwrap(), &mut no_progress()).unwrap();
    let t = &scene.tree;
    assert_eq!(
        shape(t),
        vec![
            (s("assembly"), None, 0),
            (s("left"), Some(s("assembly")), 1),
            (s("bolt"), Some(s("left")), 1),
            (s("right"), Some(s("assembly")), 0),
            (s("bolt2"), Some(s("right")), 1),
            (s("lone"), None, 1),
        ]
    );
    assert_eq!(t.instance_counts(), vec![3, 2, 1, 1, 1, 1]);
    // Each node owns the instance placed at its own world transform.
    let bolt2 = t.nodes[4].instances[0] as usize;
    assert_eq!(scene.instances[bolt2].name, "bolt2");
    assert_eq!(scene.instances[bolt2].transform.w_axis.x, 5.0);
    assert_eq!(t.subtree_instances(1).len(), 2);
    assert_eq!(t.path(4), vec![0, 3, 4]);
    assert_eq!(t.search("BOLT"), vec![2, 4]);
}

#[test]
fn obj_objects_and_groups_become_nodes() {
    let dir = temp_dir("tree_obj");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n\
               o Housing\ng top\nf 1 2 3\ng bottom\nf 1 2 3\nf 1 3 2\n\
               o Shaft\nf 1 2 3\n";
    let path = dir.join("groups.obj");
    std::fs::write(&path, obj).unwrap();
    let scene = load(path.to_str().unwrap(), &mut no_progress()).unwrap();
    assert_eq!(
        shape(&scene.tree),
        vec![
            (s("Housing"), None, 0),
            (s("top"), Some(s("Housing")), 1),
            (s("bottom"), Some(s("Housing")), 1),
            (s("Shaft"), None, 1),
        ]
    );
    let names: Vec<&str> = scene.instances.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(names, ["top", "bottom", "Shaft"]);
    assert_eq!(scene.meshes[1].triangle_count(), 2);
}

#[test]
fn generated_scenes_get_one_node_and_edits_keep_the_tree() {
    let mut scene = load("gen:slab", &mut no_progress()).unwrap();
    let n = scene.instances.len();
    assert_eq!(scene.tree.len(), 1);
    assert_eq!(scene.tree.instance_counts(), vec![n as u64]);
    let owner = scene.tree.owner_of(0);
    let inst = scene.remove_instance(0).unwrap();
    assert_eq!(scene.tree.instance_counts(), vec![n as u64 - 1]);
    scene.validate().unwrap();
    scene.insert_instance_in(0, inst, owner).unwrap();
    assert_eq!(scene.tree, NodeTree::single(scene.name.clone(), n));
    let f = scene.f();
    scene.set_visibility(&[(0, false), (1, false)]).unwrap();
    assert_eq!(scene.f(), f + 1, "one batch, one F bump");
    assert!(scene.instances.iter().take(2).all(|i| !i.visible));
    assert!(scene.set_visibility(&[(0, true), (99, true)]).is_err());
    assert!(!scene.instances[0].visible, "a rejected batch changes nothing");
}
