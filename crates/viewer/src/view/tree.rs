//! The model tree: the selection it shares with the 3D view (a node selects its subtree's instances, a pick
//! selects one instance and reveals its node), the hide / isolate / show-all edits (one undo step each, through
//! the edit stack, so F increments and the AO follows). The panel that shows it is `tree_panel.rs`.
use hrtao_scene::{NodeTree, Scene};

use super::command::{Command, ViewState};
use super::edits::Edit;

/// What is selected and highlighted.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Selection {
    /// The tree node selected (clicked in the tree) or revealed (owner of the picked instance).
    pub node: Option<u32>,
    /// The highlighted instances, sorted.
    pub instances: Vec<u32>,
}

impl Selection {
    /// A tree node: every instance of its subtree.
    pub fn of_node(tree: &NodeTree, node: u32) -> Self {
        Self {
            node: Some(node).filter(|&n| (n as usize) < tree.len()),
            instances: tree.subtree_instances(node),
        }
    }

    /// A picked instance (u32::MAX: nothing) and the node that owns it.
    pub fn of_instance(tree: &NodeTree, instance: u32) -> Self {
        if instance == u32::MAX {
            return Self::default();
        }
        Self {
            node: tree.owner_of(instance),
            instances: vec![instance],
        }
    }

    /// Shift/Ctrl+click on an instance (u32::MAX: the background, which changes nothing): adds it to the
    /// selection, or removes it when it is selected.
    /// A pick's selection, logged: `instance` alone (u32::MAX: nothing), with its node's path in the tree.
    pub fn picked(tree: &NodeTree, instance: u32) -> Self {
        let selection = Self::of_instance(tree, instance);
        if let Some(node) = selection.node {
            let path: Vec<&str> = tree
                .path(node)
                .iter()
                .map(|&n| tree.nodes[n as usize].name.as_str())
                .collect();
            log::info!("selected instance {instance} (tree: {})", path.join(" / "));
        }
        selection
    }

    /// Shift/Ctrl+click's selection, logged: `toggled`.
    pub fn toggled_logged(&self, tree: &NodeTree, instance: u32) -> Self {
        let selection = self.toggled(tree, instance);
        log::info!(
            "selection: {} instances {:?}",
            selection.instances.len(),
            selection.instances
        );
        selection
    }

    pub fn toggled(&self, tree: &NodeTree, instance: u32) -> Self {
        if instance == u32::MAX {
            return self.clone();
        }
        self.with(tree, &[instance], !self.instances.contains(&instance))
    }

    /// Shift/Ctrl+click on a tree node: adds its subtree's instances, or removes them when all are selected.
    pub fn toggled_node(&self, tree: &NodeTree, node: u32) -> Self {
        if self.instances.is_empty() {
            return Self::of_node(tree, node);
        }
        let ids = tree.subtree_instances(node);
        let all = ids.iter().all(|i| self.instances.binary_search(i).is_ok());
        self.with(tree, &ids, !all)
    }

    /// The selection with `ids` added (or removed). The node is kept only while it still names the selection
    /// (one instance: its owner).
    fn with(&self, tree: &NodeTree, ids: &[u32], add: bool) -> Self {
        let mut instances = self.instances.clone();
        if add {
            instances.extend_from_slice(ids);
            instances.sort_unstable();
            instances.dedup();
        } else {
            instances.retain(|i| !ids.contains(i));
        }
        let node = match instances.as_slice() {
            [one] => tree.owner_of(*one),
            _ => None,
        };
        Self { node, instances }
    }

    /// The single selected instance (what move and delete act on), u32::MAX when none or several.
    pub fn primary(&self) -> u32 {
        match self.instances.as_slice() {
            [one] => *one,
            _ => u32::MAX,
        }
    }
}

/// An edit setting each instance's visibility to `want(instance)` (None: unchanged); None if nothing changes.
fn visibility_edit(scene: &Scene, label: String, want: impl Fn(u32) -> Option<bool>) -> Option<Edit> {
    let changes: Vec<(u32, bool)> = scene
        .instances
        .iter()
        .enumerate()
        .filter_map(|(i, inst)| {
            let v = want(i as u32)?;
            (v != inst.visible).then_some((i as u32, v))
        })
        .collect();
    (!changes.is_empty()).then_some(Edit::Visibilities { label, changes })
}

fn node_name(scene: &Scene, node: u32) -> String {
    scene
        .tree
        .nodes
        .get(node as usize)
        .map(|n| n.name.clone())
        .unwrap_or_default()
}

/// Shows (`visible`) or hides a node's subtree.
pub fn set_node_visible(scene: &Scene, node: u32, visible: bool) -> Option<Edit> {
    let ids = scene.tree.subtree_instances(node);
    let verb = if visible { "show" } else { "hide" };
    visibility_edit(scene, format!("{verb} {}", node_name(scene, node)), |i| {
        ids.binary_search(&i).is_ok().then_some(visible)
    })
}

/// Shows the given instances (sorted) and hides every other one.
pub fn isolate(scene: &Scene, instances: &[u32], what: String) -> Option<Edit> {
    visibility_edit(scene, format!("isolate {what}"), |i| {
        Some(instances.binary_search(&i).is_ok())
    })
}

/// Sets every instance's visibility to `visible` (one per instance; an edit named `label`).
pub fn set_visibility(scene: &Scene, label: String, visible: &[bool]) -> Option<Edit> {
    visibility_edit(scene, label, |i| visible.get(i as usize).copied())
}

/// Shows every instance.
pub fn show_all(scene: &Scene) -> Option<Edit> {
    visibility_edit(scene, "show all".into(), |_| Some(true))
}

/// A line naming a multi-instance selection (a tree node, or instances added with Shift/Ctrl+click) and a
/// Delete button for all of it; None when there is none.
pub fn selection_summary(ui: &mut egui::Ui, state: &ViewState) -> Option<Vec<Command>> {
    let scene = state.scene?;
    let selection = state.selection;
    let n = selection.instances.len();
    if n < 2 {
        return None;
    }
    let what = match selection.node {
        Some(node) => format!("{}: {n} instances", node_name(scene, node)),
        None => format!("{n} instances selected"),
    };
    ui.label(format!("{what} (H hide, I isolate, Delete)"));
    Some(if ui.button("Delete").clicked() {
        vec![Command::DeleteSelection]
    } else {
        Vec::new()
    })
}

/// Hide the selection (a node: its subtree; else the picked instance) or show it if all of it is hidden.
pub fn hide_selection_edit(scene: &Scene, selection: &Selection) -> Option<Edit> {
    let all_hidden = selection
        .instances
        .iter()
        .all(|&i| scene.instances.get(i as usize).is_some_and(|x| !x.visible));
    match selection.node {
        Some(n) if selection.instances.len() > 1 => set_node_visible(scene, n, all_hidden),
        _ => visibility_edit(scene, if all_hidden { "show" } else { "hide" }.into(), |i| {
            selection
                .instances
                .binary_search(&i)
                .is_ok()
                .then_some(all_hidden)
        }),
    }
}

/// Show only the selection (a node: named after it; else after its first instance).
pub fn isolate_edit(scene: &Scene, selection: &Selection) -> Option<Edit> {
    if selection.instances.is_empty() {
        return None;
    }
    let what = match (selection.node, selection.instances.len()) {
        (Some(n), k) if k > 1 => node_name(scene, n),
        _ => selection
            .instances
            .first()
            .and_then(|&i| scene.instances.get(i as usize))
            .map(|i| i.name.clone())
            .unwrap_or_default(),
    };
    isolate(scene, &selection.instances, what)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::edits::EditStack;

    /// assembly(0) ─ left(1) [0, 1] ; right(2) [2] ; lone(3) [3]
    fn scene() -> Scene {
        let mut s = hrtao_scene::load("gen:slab", &mut |_| {}).unwrap();
        let inst = s.instances[0].clone();
        while s.instances.len() < 4 {
            s.add_instance(inst.clone()).unwrap();
        }
        let mut t = NodeTree::default();
        let a = t.add("assembly", None);
        let l = t.add("left", Some(a));
        let r = t.add("right", Some(a));
        let lone = t.add("lone", None);
        t.nodes[l as usize].instances = vec![0, 1];
        t.nodes[r as usize].instances = vec![2];
        t.nodes[lone as usize].instances = vec![3];
        s.tree = t;
        s.validate().unwrap();
        s
    }

    fn visible(s: &Scene) -> Vec<bool> {
        s.instances.iter().map(|i| i.visible).collect()
    }

    #[test]
    fn node_selects_its_instances_and_picks_reveal_the_node() {
        let s = scene();
        let sel = Selection::of_node(&s.tree, 0);
        assert_eq!(sel.instances, vec![0, 1, 2]);
        assert_eq!(sel.primary(), u32::MAX, "several instances: nothing to move");
        let right = Selection::of_node(&s.tree, 2);
        assert_eq!((right.node, right.primary()), (Some(2), 2));
        let pick = Selection::of_instance(&s.tree, 1);
        assert_eq!(pick.node, Some(1));
        assert_eq!(
            s.tree.path(pick.node.unwrap()),
            vec![0, 1],
            "the path the panel opens"
        );
        assert_eq!(pick.primary(), 1);
        assert_eq!(Selection::of_instance(&s.tree, u32::MAX), Selection::default());
    }

    #[test]
    fn shift_click_adds_and_removes_instances_and_nodes() {
        let s = scene();
        let t = &s.tree;
        let two = Selection::of_instance(t, 0).toggled(t, 3);
        assert_eq!((two.instances.clone(), two.node), (vec![0, 3], None));
        assert_eq!(two.primary(), u32::MAX, "several: no single instance");
        assert_eq!(
            two.toggled(t, u32::MAX),
            two,
            "shift+click on the background keeps it"
        );
        let back = two.toggled(t, 0);
        assert_eq!(back, Selection::of_instance(t, 3), "one left: its node again");
        assert_eq!(back.toggled(t, 3), Selection::default());
        // Tree nodes: a node's subtree is added, or removed when all of it is selected.
        let left = Selection::default().toggled_node(t, 1);
        assert_eq!(left, Selection::of_node(t, 1));
        let more = left.toggled_node(t, 3);
        assert_eq!((more.instances.clone(), more.node), (vec![0, 1, 3], None));
        assert_eq!(more.toggled_node(t, 1), Selection::of_instance(t, 3));
        let partly = Selection::of_instance(t, 0).toggled_node(t, 0);
        assert_eq!(
            partly.instances,
            vec![0, 1, 2],
            "a partly selected node is completed"
        );
        // Hide and delete act on all of it as one edit.
        let mut s = scene();
        let mut stack = EditStack::default();
        let del = Edit::delete_all(&more.instances).unwrap();
        stack.apply(&mut s, del).unwrap();
        assert_eq!(s.instances.len(), 1);
        assert_eq!(s.tree.nodes[2].instances, vec![0], "instance 2 is now 0");
        stack.undo(&mut s).unwrap();
        let original = scene();
        assert_eq!(s.instances, original.instances, "one undo restores all three");
        assert_eq!(s.tree, original.tree, "and their nodes");
    }

    #[test]
    fn hide_isolate_show_all_are_edits_with_undo() {
        let mut s = scene();
        let mut stack = EditStack::default();
        let f0 = s.f();
        let hide = set_node_visible(&s, 1, false).unwrap();
        stack.apply(&mut s, hide).unwrap();
        assert_eq!(visible(&s), [false, false, true, true]);
        assert!(s.f() > f0, "hiding bumps F");
        assert!(
            set_node_visible(&s, 1, false).is_none(),
            "already hidden: no edit"
        );
        let sel = Selection::of_node(&s.tree, 2);
        let iso = isolate(&s, &sel.instances, "right".into()).unwrap();
        stack.apply(&mut s, iso).unwrap();
        assert_eq!(visible(&s), [false, false, true, false]);
        let all = show_all(&s).unwrap();
        stack.apply(&mut s, all).unwrap();
        assert_eq!(visible(&s), [true; 4]);
        stack.undo(&mut s).unwrap();
        assert_eq!(visible(&s), [false, false, true, false], "undo show all");
        stack.undo(&mut s).unwrap();
        assert_eq!(visible(&s), [false, false, true, true], "undo isolate");
        stack.undo(&mut s).unwrap();
        assert_eq!(visible(&s), [true; 4]);
    }

    #[test]
    fn delete_undo_restores_tree_ownership() {
        let mut s = scene();
        let tree = s.tree.clone();
        let mut stack = EditStack::default();
        stack
            .apply(
                &mut s,
                Edit::Delete {
                    instance: 1,
                    removed: None,
                },
            )
            .unwrap();
        assert_eq!(s.tree.nodes[1].instances, vec![0]);
        assert_eq!(s.tree.nodes[2].instances, vec![1], "later ids shift down");
        stack.undo(&mut s).unwrap();
        assert_eq!(s.tree, tree);
    }
}

#[cfg(test)]
mod gpu_tests {
    use super::*;
    use crate::view::edits::{run_action, Action, EditStack};
    use hrtao_core::{AoSettings, Camera, ContextOptions, Gpu, Renderer, SceneGpu};

    /// Hiding a tree node through the UI's edit path rebuilds the TLAS: its instances vanish from the next
    /// frame (with the node's instances highlighted), and undo brings them back.
    #[test]
    fn hiding_a_node_removes_its_instances_from_the_image() {
        let gpu = Gpu::new(&ContextOptions::from_env()).expect("Vulkan device (lavapipe)");
        let mut scene = hrtao_scene::load("gen:slab", &mut |_| {}).unwrap();
        // gen:slab: ground (0) and slab (1); make the slab its own node under the root.
        let mut t = NodeTree::default();
        let root = t.add("site", None);
        let slab = t.add("slab", Some(root));
        t.nodes[root as usize].instances = vec![0];
        t.nodes[slab as usize].instances = vec![1];
        scene.tree = t;
        let mut sg = SceneGpu::new(&gpu, &scene).unwrap();
        let b = scene.bounds();
        let cam = Camera::fit(b.min, b.max, hrtao_core::camera::UpAxis::Z, 40.0, 64, 48);
        let settings = {
            let mut s = AoSettings::default();
            s.map.ao_radius = 2.0;
            s.map.hash_capacity = 1 << 12;
            s
        };
        let mut r = Renderer::new(&gpu).unwrap();
        let ids = |r: &mut Renderer, sg: &SceneGpu, f: u32| {
            r.render(&hrtao_core::FrameDesc::new(sg, f, cam, &settings))
                .unwrap();
            let mut v: Vec<u32> = r.read_gbuffer().unwrap().iter().map(|p| p.instance).collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let before = ids(&mut r, &sg, scene.f());
        assert!(before.contains(&0) && before.contains(&1), "{before:?}");
        let sel = Selection::of_node(&scene.tree, slab);
        let mut stack = EditStack::default();
        let hide = set_node_visible(&scene, slab, false).unwrap();
        run_action(
            &mut stack,
            &mut scene,
            &mut sg,
            sel.instances.as_slice(),
            Action::Apply(hide),
        )
        .unwrap();
        let hidden = ids(&mut r, &sg, scene.f());
        assert!(!hidden.contains(&1) && hidden.contains(&0), "{hidden:?}");
        run_action(
            &mut stack,
            &mut scene,
            &mut sg,
            sel.instances.as_slice(),
            Action::Undo,
        )
        .unwrap();
        assert_eq!(ids(&mut r, &sg, scene.f()), before);
        drop(r);
        drop(sg);
        assert_eq!(gpu.validation_messages(), 0);
    }
}
