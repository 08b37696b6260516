//! Reloading the open file (F5, Ctrl+R, the panel's Reload, or a change on disk seen by `watch.rs`): the
//! camera, the section planes and the selection are kept where the parts still exist (matched by their path
//! of names in the model tree); a failed reload keeps the old model on screen and says why. Also what follows
//! every opened file: the recent list (`recent.rs`) and the watch on it.
use hrtao_scene::{NodeTree, Scene};

use super::nav::Nav;
use super::sections::SectionState;
use super::{recent, tree, watch, Viewer};
use hrtao_core::Camera;

/// What a reload keeps of the view.
pub(super) struct Keep {
    pub spec: String,
    nav: Nav,
    home: Camera,
    sections: SectionState,
    /// The selected node's path of names.
    node: Option<Vec<String>>,
    /// The selected instances: their owner's path of names and their own name.
    instances: Vec<(Vec<String>, String)>,
}

/// The names from the root down to `node`.
fn names(tree: &NodeTree, node: u32) -> Vec<String> {
    tree.path(node)
        .iter()
        .map(|&n| tree.nodes[n as usize].name.clone())
        .collect()
}

/// The node whose path of names is `path`.
fn find_node(tree: &NodeTree, path: &[String]) -> Option<u32> {
    (0..tree.len() as u32).find(|&n| names(tree, n) == path)
}

/// An instance's key: its owner's path of names and its name.
fn instance_key(scene: &Scene, i: u32) -> (Vec<String>, String) {
    let owner = scene
        .tree
        .owner_of(i)
        .map(|n| names(&scene.tree, n))
        .unwrap_or_default();
    (owner, scene.instances[i as usize].name.clone())
}

/// The selection of the old scene in the new one: the same node if its path is there, the instances whose
/// keys are there (each key matched once, in order).
pub(super) fn carry_selection(
    scene: &Scene,
    node: &Option<Vec<String>>,
    keys: &[(Vec<String>, String)],
) -> tree::Selection {
    if let Some(n) = node.as_deref().and_then(|p| find_node(&scene.tree, p)) {
        if keys.len() != 1 {
            return tree::Selection::of_node(&scene.tree, n);
        }
    }
    let mut used = vec![false; scene.instances.len()];
    let mut instances = Vec::new();
    for key in keys {
        let found =
            (0..scene.instances.len() as u32).find(|&i| !used[i as usize] && instance_key(scene, i) == *key);
        if let Some(i) = found {
            used[i as usize] = true;
            instances.push(i);
        }
    }
    instances.sort_unstable();
    match instances.as_slice() {
        [] => tree::Selection::default(),
        [one] => tree::Selection::of_instance(&scene.tree, *one),
        _ => tree::Selection {
            node: None,
            instances,
        },
    }
}

impl Viewer {
    /// Reloads the open file in the background, keeping the view (nothing when no file is open or a load runs).
    pub(super) fn reload(&mut self) {
        if self.loader.is_loading() {
            return;
        }
        let spec = self.scene_spec.clone();
        let Some(scene) = &self.scene else {
            return;
        };
        if !std::path::Path::new(&spec).is_file() {
            self.toast(format!("nothing to reload: {spec} is not a file on disk"), true);
            return;
        }
        let keep = Keep {
            spec: spec.clone(),
            nav: self.nav,
            home: self.home,
            sections: self.panels.sections.clone(),
            node: self.selection.node.map(|n| names(&scene.tree, n)),
            instances: self
                .selection
                .instances
                .iter()
                .map(|&i| instance_key(scene, i))
                .collect(),
        };
        log::info!("reloading {spec}");
        self.reloading = Some(keep);
        self.start_loading(spec);
    }

    /// A load finished: the view kept by a reload of the same file (None when it was not a reload).
    pub(super) fn take_reload(&mut self, spec: &str) -> Option<Keep> {
        self.reloading.take().filter(|k| k.spec == spec)
    }

    /// After a reload installed the new scene: the old camera, sections and selection, and the toast.
    pub(super) fn reloaded(&mut self, keep: Keep) {
        self.nav = keep.nav;
        self.home = keep.home;
        let Some(scene) = &self.scene else {
            return;
        };
        let parts = scene.instances.len();
        let selection = carry_selection(scene, &keep.node, &keep.instances);
        let mut sections = keep.sections;
        sections.bounds = scene.bounds();
        let planes = sections.sections();
        self.panels.sections = sections;
        self.apply_sections(planes);
        self.panels.tree.reveal(selection.node);
        self.apply_selection(selection);
        let name = std::path::Path::new(&keep.spec)
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or(keep.spec);
        self.toast(format!("Reloaded {name} ({parts} parts)"), false);
    }

    /// A reload failed: the old model stays, the toast says why.
    pub(super) fn reload_failed(&mut self, error: &str) {
        self.toast(format!("reload failed, the previous model stays: {error}"), true);
    }

    /// A scene was opened from `spec`: a file joins the recent list (saved now) and is watched for changes.
    pub(super) fn opened_file(&mut self, spec: &str) {
        let Some(path) = recent::entry_for(spec) else {
            self.watch = None;
            return;
        };
        if spec != super::default_spec() {
            recent::push(&mut self.prefs.recent, path.clone(), recent::CAP);
            self.maybe_save_prefs(true);
        }
        if self.watch.as_ref().is_some_and(|w| w.path == path) {
            return;
        }
        let ctx = self.egui_ctx.clone();
        self.watch = match watch::FileWatch::start(path.clone(), move || ctx.request_repaint()) {
            Ok(w) => Some(w),
            Err(e) => {
                log::warn!(
                    "cannot watch {} for changes ({e}): reload it with F5",
                    path.display()
                );
                None
            }
        };
    }

    /// The UI pass: a settled change of the open file reloads it (with auto-reload on, once no load runs).
    pub(super) fn poll_watch(&mut self) {
        if !self.prefs.auto_reload || self.loader.is_loading() {
            return;
        }
        if self.watch.as_ref().is_some_and(|w| w.take_change()) {
            self.reload();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_selection_follows_the_parts_by_name() {
        let obj = |names: &[&str]| {
            let mut s = String::new();
            for (k, n) in names.iter().enumerate() {
                s += &format!("o {n}\nv 0 0 {k}\nv 1 0 {k}\nv 0 1 {k}\nf -3 -2 -1\n");
            }
            s
        };
        let dir = std::env::temp_dir().join(format!("hrtao-reload-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let load = |names: &[&str]| {
            let p = dir.join("m.obj");
            std::fs::write(&p, obj(names)).unwrap();
            hrtao_scene::load(p.to_str().unwrap(), &mut |_| {}).unwrap()
        };
        let old = load(&["a", "b", "c"]);
        let keys: Vec<_> = [1u32, 2].iter().map(|&i| instance_key(&old, i)).collect();
        // "b" and "c" selected; the new file drops "b" and puts "c" first.
        let new = load(&["c", "a", "d"]);
        let sel = carry_selection(&new, &None, &keys);
        assert_eq!(sel.instances, vec![0], "only c is left, at its new index");
        assert_eq!(instance_key(&new, 0), keys[1]);
        // Nothing of the selection is left: nothing selected.
        let gone = load(&["x"]);
        assert_eq!(carry_selection(&gone, &None, &keys), tree::Selection::default());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
