//! Reloading the open file (F5, Ctrl+R, the panel's Reload, or a change on disk seen by `watch.rs`): the
//! camera, the section planes and the selection are kept where the parts still exist (matched by their path
//! of names in the model tree); a failed reload keeps the old model on screen and says why. Also what follows
//! every opened file: the recent list (`recent.rs`) and the watch on it.
use hrtao_scene::{NodeTree, Scene};

use super::nav::Nav;
use super::sections::SectionState;
use super::{recent, tree, watch};
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

/// The reloads' state: the view a running reload keeps, and the watch on the open file.
#[derive(Default)]
pub(super) struct Reload {
    keep: Option<Keep>,
    watch: Option<watch::FileWatch>,
}

/// What a reload gives back once the new scene is installed.
pub(super) struct Restored {
    pub nav: Nav,
    pub home: Camera,
    pub sections: SectionState,
    pub selection: tree::Selection,
    /// The toast.
    pub message: String,
}

impl Reload {
    /// A reload of `spec` starts, keeping the view (`Keep::of`).
    pub fn start(&mut self, keep: Keep) {
        log::info!("reloading {}", keep.spec);
        self.keep = Some(keep);
    }

    /// A load finished: the view kept by a reload of the same file (None when it was not a reload).
    pub fn take(&mut self, spec: &str) -> Option<Keep> {
        self.keep.take().filter(|k| k.spec == spec)
    }

    /// A scene was opened from `spec`: a file is watched for changes (a change repaints through `ctx`).
    pub fn watch(&mut self, spec: &str, ctx: &egui::Context) {
        let Some(path) = recent::entry_for(spec) else {
            self.watch = None;
            return;
        };
        if self.watch.as_ref().is_some_and(|w| w.path == path) {
            return;
        }
        let ctx = ctx.clone();
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

    /// The open file changed and the change has settled (taken once).
    pub fn changed(&self) -> bool {
        self.watch.as_ref().is_some_and(|w| w.take_change())
    }
}

/// A scene was opened from `spec`: a file (not the bundled scene) joins the recent list; whether it did (the
/// preferences are saved then).
pub(super) fn remember_opened(spec: &str, recent_files: &mut Vec<std::path::PathBuf>) -> bool {
    match recent::entry_for(spec) {
        Some(path) if spec != super::default_spec() => {
            recent::push(recent_files, path, recent::CAP);
            true
        }
        _ => false,
    }
}

impl Keep {
    /// What a reload of the open file `spec` keeps of the view; the user's message when it is not a file.
    pub fn of(
        spec: &str,
        scene: &Scene,
        (nav, home): (Nav, Camera),
        sections: &SectionState,
        selection: &tree::Selection,
    ) -> Result<Keep, String> {
        if !std::path::Path::new(spec).is_file() {
            return Err(format!("nothing to reload: {spec} is not a file on disk"));
        }
        Ok(Keep {
            spec: spec.to_string(),
            nav,
            home,
            sections: sections.clone(),
            node: selection.node.map(|n| names(&scene.tree, n)),
            instances: selection
                .instances
                .iter()
                .map(|&i| instance_key(scene, i))
                .collect(),
        })
    }

    /// After a reload installed the new scene: the old camera, sections and selection, and the toast.
    pub fn restore(self, scene: &Scene) -> Restored {
        let parts = scene.instances.len();
        let selection = carry_selection(scene, &self.node, &self.instances);
        let mut sections = self.sections;
        sections.bounds = scene.bounds();
        let name = std::path::Path::new(&self.spec)
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or(self.spec);
        Restored {
            nav: self.nav,
            home: self.home,
            sections,
            selection,
            message: format!("Reloaded {name} ({parts} parts)"),
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
