//! Scene edits with undo/redo. Every edit (and every undo/redo) goes through the scene's edit API, which
//! increments the frame identifier F (paper eq. 6); the viewer then rebuilds the TLAS.
use anyhow::{anyhow, Result};
use glam::Mat4;
use hrtao_scene::{Instance, Scene};

#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// Replace an instance's transform.
    Transform {
        instance: u32,
        before: Mat4,
        after: Mat4,
    },
    /// Show or hide an instance.
    Visibility { instance: u32, visible: bool },
    /// Remove an instance (`removed` is filled in when applied, for undo: the instance and its tree node).
    Delete {
        instance: u32,
        removed: Option<(Instance, Option<u32>)>,
    },
    /// Set the visibility of several instances as one step (hide, isolate, show all in the model tree).
    /// Only instances whose visibility changes are listed, so undo flips each back.
    Visibilities {
        label: String,
        changes: Vec<(u32, bool)>,
    },
    /// Several edits as one step (a move or delete of a multi-selection): applied in order, reverted in reverse
    /// order, one undo step, and one TLAS rebuild (so one local invalidation covering all their boxes).
    Group { label: String, edits: Vec<Edit> },
}

impl Edit {
    pub fn label(&self) -> String {
        match self {
            Edit::Transform { instance, .. } => format!("move #{instance}"),
            Edit::Visibility { instance, visible } => {
                format!("{} #{instance}", if *visible { "show" } else { "hide" })
            }
            Edit::Delete { instance, .. } => format!("delete #{instance}"),
            Edit::Visibilities { label, changes } => format!("{label} ({} instances)", changes.len()),
            Edit::Group { label, edits } => format!("{label} ({} instances)", edits.len()),
        }
    }

    /// `edits` as one step: None when empty, the edit itself when alone, else a group.
    fn group(label: &str, mut edits: Vec<Edit>) -> Option<Edit> {
        match edits.len() {
            0 => None,
            1 => edits.pop(),
            _ => Some(Edit::Group {
                label: label.into(),
                edits,
            }),
        }
    }

    /// Moves each of `instances` by the world offset `d` (ids out of range are skipped).
    pub fn move_all(scene: &Scene, instances: &[u32], d: glam::Vec3) -> Option<Edit> {
        let moves = instances
            .iter()
            .filter_map(|&i| {
                let before = scene.instances.get(i as usize)?.transform;
                Some(Edit::Transform {
                    instance: i,
                    before,
                    after: Mat4::from_translation(d) * before,
                })
            })
            .collect();
        Self::group("move", moves)
    }

    /// Deletes every one of `instances`: highest id first, so that each removal leaves the lower ids in place
    /// (and undo, reinserting lowest first, restores every id).
    pub fn delete_all(instances: &[u32]) -> Option<Edit> {
        let mut ids = instances.to_vec();
        ids.sort_unstable_by(|a, b| b.cmp(a));
        ids.dedup();
        let deletes = ids
            .into_iter()
            .map(|instance| Edit::Delete {
                instance,
                removed: None,
            })
            .collect();
        Self::group("delete", deletes)
    }

    /// The instances a transform (or a group of transforms) moves, in order; None for other edits.
    fn moved(&self) -> Option<Vec<u32>> {
        match self {
            Edit::Transform { instance, .. } => Some(vec![*instance]),
            Edit::Group { edits, .. } => edits
                .iter()
                .map(|e| match e {
                    Edit::Transform { instance, .. } => Some(*instance),
                    _ => None,
                })
                .collect(),
            _ => None,
        }
    }

    /// Folds a later move of the same instances into this one (a drag is one undo step).
    fn merge_move(&mut self, later: &Edit) -> bool {
        if self.moved().is_none() || self.moved() != later.moved() {
            return false;
        }
        let mine: Vec<&mut Edit> = match self {
            Edit::Group { edits, .. } => edits.iter_mut().collect(),
            one => vec![one],
        };
        let theirs: Vec<&Edit> = match later {
            Edit::Group { edits, .. } => edits.iter().collect(),
            one => vec![one],
        };
        for (a, b) in mine.into_iter().zip(theirs) {
            if let (Edit::Transform { after: last, .. }, Edit::Transform { after, .. }) = (a, b) {
                *last = *after;
            }
        }
        true
    }
}

/// The undo and redo stacks.
#[derive(Default, Debug)]
pub struct EditStack {
    undo: Vec<Edit>,
    redo: Vec<Edit>,
}

fn apply(scene: &mut Scene, edit: &mut Edit) -> Result<()> {
    match edit {
        Edit::Transform { instance, after, .. } => scene.set_transform(*instance, *after)?,
        Edit::Visibility { instance, visible } => scene.set_visible(*instance, *visible)?,
        Edit::Delete { instance, removed } => {
            let owner = scene.tree.owner_of(*instance);
            *removed = Some((scene.remove_instance(*instance)?, owner));
        }
        Edit::Visibilities { changes, .. } => scene.set_visibility(changes)?,
        Edit::Group { edits, .. } => {
            for i in 0..edits.len() {
                if let Err(e) = apply(scene, &mut edits[i]) {
                    // All or nothing: undo the part already applied.
                    for done in edits[..i].iter().rev() {
                        revert(scene, done)?;
                    }
                    return Err(e);
                }
            }
        }
    }
    Ok(())
}

fn revert(scene: &mut Scene, edit: &Edit) -> Result<()> {
    match edit {
        Edit::Transform { instance, before, .. } => scene.set_transform(*instance, *before)?,
        Edit::Visibility { instance, visible } => scene.set_visible(*instance, !*visible)?,
        Edit::Delete { instance, removed } => {
            let (inst, owner) = removed.clone().ok_or_else(|| anyhow!("nothing to restore"))?;
            scene.insert_instance_in(*instance, inst, owner)?
        }
        Edit::Visibilities { changes, .. } => {
            let back: Vec<(u32, bool)> = changes.iter().map(|&(i, v)| (i, !v)).collect();
            scene.set_visibility(&back)?
        }
        Edit::Group { edits, .. } => {
            for e in edits.iter().rev() {
                revert(scene, e)?;
            }
        }
    }
    Ok(())
}

impl EditStack {
    /// Applies `edit` to `scene` and records it (clears the redo stack). Consecutive moves of the same
    /// instances merge into one undo step.
    pub fn apply(&mut self, scene: &mut Scene, mut edit: Edit) -> Result<()> {
        apply(scene, &mut edit)?;
        self.redo.clear();
        if let Some(last) = self.undo.last_mut() {
            if last.merge_move(&edit) {
                return Ok(());
            }
        }
        self.undo.push(edit);
        Ok(())
    }

    /// Reverts the last edit; returns it (None when there is nothing to undo).
    pub fn undo(&mut self, scene: &mut Scene) -> Result<Option<Edit>> {
        let Some(edit) = self.undo.pop() else {
            return Ok(None);
        };
        if let Err(e) = revert(scene, &edit) {
            self.undo.push(edit);
            return Err(e);
        }
        self.redo.push(edit.clone());
        Ok(Some(edit))
    }

    /// Re-applies the last undone edit.
    pub fn redo(&mut self, scene: &mut Scene) -> Result<Option<Edit>> {
        let Some(mut edit) = self.redo.pop() else {
            return Ok(None);
        };
        apply(scene, &mut edit)?;
        self.undo.push(edit.clone());
        Ok(Some(edit))
    }

    /// Forgets everything (a new scene was loaded).
    pub fn clear(&mut self) {
        self.undo.clear();
        self.redo.clear();
    }

    #[cfg(test)]
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }
    #[cfg(test)]
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
    pub fn undo_label(&self) -> Option<String> {
        self.undo.last().map(Edit::label)
    }
    pub fn redo_label(&self) -> Option<String> {
        self.redo.last().map(Edit::label)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn scene() -> Scene {
        hrtao_scene::load("gen:slab", &mut |_| {}).unwrap()
    }

    #[test]
    fn edit_bumps_f_undo_restores_redo_reapplies() {
        let mut s = scene();
        let mut stack = EditStack::default();
        let f0 = s.f();
        let before = s.instances[1].transform;
        let after = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)) * before;
        stack
            .apply(
                &mut s,
                Edit::Transform {
                    instance: 1,
                    before,
                    after,
                },
            )
            .unwrap();
        assert_eq!(s.instances[1].transform, after);
        assert!(s.f() > f0, "an edit increments F");
        let f1 = s.f();
        assert!(stack.undo(&mut s).unwrap().is_some());
        assert_eq!(s.instances[1].transform, before, "undo restores the instance");
        assert!(s.f() > f1, "undo is an edit too: F increments");
        stack.redo(&mut s).unwrap();
        assert_eq!(s.instances[1].transform, after);
        assert!(stack.redo(&mut s).unwrap().is_none());
    }

    #[test]
    fn delete_and_hide_undo() {
        let mut s = scene();
        let n = s.instances.len();
        let original = s.instances.clone();
        let mut stack = EditStack::default();
        stack
            .apply(
                &mut s,
                Edit::Visibility {
                    instance: 0,
                    visible: false,
                },
            )
            .unwrap();
        assert!(!s.instances[0].visible);
        stack
            .apply(
                &mut s,
                Edit::Delete {
                    instance: 0,
                    removed: None,
                },
            )
            .unwrap();
        assert_eq!(s.instances.len(), n - 1);
        stack.undo(&mut s).unwrap();
        stack.undo(&mut s).unwrap();
        assert_eq!(
            s.instances, original,
            "undo restores the deleted instance in place"
        );
        assert!(!stack.can_undo() && stack.can_redo());
        // A new edit clears the redo stack.
        stack
            .apply(
                &mut s,
                Edit::Visibility {
                    instance: 1,
                    visible: false,
                },
            )
            .unwrap();
        assert!(!stack.can_redo());
    }

    /// gen:slab's two instances and two more copies: ids 0..4.
    fn four() -> Scene {
        let mut s = scene();
        for i in 0..2 {
            let mut inst = s.instances[i].clone();
            inst.name = format!("copy {i}");
            s.add_instance(inst).unwrap();
        }
        s
    }

    #[test]
    fn deleting_several_instances_is_one_step() {
        let mut s = four();
        let original = s.instances.clone();
        let mut stack = EditStack::default();
        let edit = Edit::delete_all(&[0, 2]).unwrap();
        assert_eq!(edit.label(), "delete (2 instances)");
        let f0 = s.f();
        stack.apply(&mut s, edit).unwrap();
        assert_eq!(s.instances, vec![original[1].clone(), original[3].clone()]);
        // One step, whose changes are both instances' boxes (one local invalidation).
        let changed = s.changes_since(f0).unwrap();
        assert_eq!(changed.len(), 2);
        assert!(changed.contains(&original_bounds(&original, 0)));
        assert!(changed.contains(&original_bounds(&original, 2)));
        stack.undo(&mut s).unwrap();
        assert_eq!(s.instances, original, "one undo brings both back, in place");
        assert!(!stack.can_undo());
        stack.redo(&mut s).unwrap();
        assert_eq!(s.instances.len(), 2);
        // One instance: a plain delete; none: no edit.
        assert!(matches!(
            Edit::delete_all(&[1]),
            Some(Edit::Delete { instance: 1, .. })
        ));
        assert!(Edit::delete_all(&[]).is_none());
    }

    fn original_bounds(instances: &[Instance], i: usize) -> hrtao_scene::Aabb {
        let mut s = scene();
        s.instances = instances.to_vec();
        s.instance_bounds(i as u32)
    }

    #[test]
    fn moving_several_instances_merges_a_drag_and_fails_as_a_whole() {
        let mut s = four();
        let original = s.instances.clone();
        let mut stack = EditStack::default();
        for _ in 0..3 {
            let m = Edit::move_all(&s, &[1, 3], Vec3::X).unwrap();
            stack.apply(&mut s, m).unwrap();
        }
        let moved = |s: &Scene, i: usize| s.instances[i].transform.w_axis.x - original[i].transform.w_axis.x;
        assert_eq!((moved(&s, 1), moved(&s, 3), moved(&s, 0)), (3.0, 3.0, 0.0));
        stack.undo(&mut s).unwrap();
        assert_eq!(s.instances, original, "one undo reverts the whole drag of both");
        assert!(!stack.can_undo());
        // A move of another set is its own step.
        for ids in [&[1, 3][..], &[1]] {
            let m = Edit::move_all(&s, ids, Vec3::Y).unwrap();
            stack.apply(&mut s, m).unwrap();
        }
        stack.undo(&mut s).unwrap();
        assert!(stack.can_undo());
        stack.undo(&mut s).unwrap();
        assert_eq!(s.instances, original);
        // A group whose second part fails changes nothing.
        let bad = Edit::Group {
            label: "delete".into(),
            edits: vec![
                Edit::Delete {
                    instance: 2,
                    removed: None,
                },
                Edit::Delete {
                    instance: 99,
                    removed: None,
                },
            ],
        };
        assert!(stack.apply(&mut s, bad).is_err());
        assert_eq!(s.instances, original);
    }

    #[test]
    fn consecutive_moves_merge_and_bad_edits_fail_cleanly() {
        let mut s = scene();
        let mut stack = EditStack::default();
        let t0 = s.instances[0].transform;
        for i in 1..=3 {
            let before = s.instances[0].transform;
            let after = Mat4::from_translation(Vec3::X * i as f32) * t0;
            stack
                .apply(
                    &mut s,
                    Edit::Transform {
                        instance: 0,
                        before,
                        after,
                    },
                )
                .unwrap();
        }
        stack.undo(&mut s).unwrap();
        assert_eq!(s.instances[0].transform, t0, "one undo reverts the whole drag");
        let f = s.f();
        let bad = Edit::Transform {
            instance: 99,
            before: t0,
            after: t0,
        };
        assert!(stack.apply(&mut s, bad).is_err());
        let singular = Edit::Transform {
            instance: 0,
            before: t0,
            after: Mat4::ZERO,
        };
        assert!(stack.apply(&mut s, singular).is_err());
        assert_eq!(s.f(), f, "a rejected edit changes nothing");
    }
}

/// What the UI calls: applies an edit (or undo/redo) and rebuilds the TLAS so the next frame sees it.
pub enum Action {
    Apply(Edit),
    Undo,
    Redo,
}

/// Runs `action` on the scene and rebuilds the TLAS (with `selected` highlighted). Returns a status line.
pub fn run_action(
    stack: &mut EditStack,
    scene: &mut Scene,
    scene_gpu: &mut hrtao_core::SceneGpu,
    selected: impl hrtao_core::accel::Highlight,
    action: Action,
) -> Result<Option<String>> {
    let done = match action {
        Action::Apply(e) => {
            let label = e.label();
            stack.apply(scene, e)?;
            Some(label)
        }
        Action::Undo => stack.undo(scene)?.map(|e| format!("undo {}", e.label())),
        Action::Redo => stack.redo(scene)?.map(|e| format!("redo {}", e.label())),
    };
    if done.is_some() {
        scene_gpu.update_instances(scene, selected)?;
    }
    Ok(done)
}

/// Runs `action` as the viewer does (`run_action`, with the selection highlighted), logging it: the selection
/// to make when the edit changed the number of instances (deletes and their undo shift later ids: the node
/// selected again, or nothing), or the user's message when it failed.
pub fn run_logged(
    stack: &mut EditStack,
    scene: &mut Scene,
    scene_gpu: &mut hrtao_core::SceneGpu,
    selection: &super::tree::Selection,
    action: Action,
) -> Result<Option<super::tree::Selection>, String> {
    use super::tree::Selection;
    let count = scene.instances.len();
    let result = run_action(stack, scene, scene_gpu, selection.instances.as_slice(), action);
    match result {
        Ok(Some(label)) => {
            log::info!(
                "edit: {label}: F = {}, {} instances",
                scene.f(),
                scene.instances.len()
            );
            Ok((scene.instances.len() != count).then(|| match selection.node {
                Some(n) if selection.instances.len() > 1 => Selection::of_node(&scene.tree, n),
                _ => Selection::default(),
            }))
        }
        Ok(None) => Ok(None),
        Err(e) => Err(format!("edit failed: {e:#}")),
    }
}

#[cfg(test)]
mod gpu_tests {
    use super::*;
    use hrtao_core::{AoSettings, Camera, ContextOptions, Gpu, Renderer, SceneGpu};

    /// The same path the UI takes: an edit bumps F, rebuilds the TLAS and changes the rendered image; undo
    /// restores both the instance and the image.
    #[test]
    fn ui_edit_rebuilds_tlas_and_undo_restores() {
        let gpu = Gpu::new(&ContextOptions::from_env()).expect("Vulkan device (lavapipe)");
        let mut scene = hrtao_scene::load("gen:slab", &mut |_| {}).unwrap();
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
        let render = |r: &mut Renderer, sg: &SceneGpu, f: u32| {
            r.render(&hrtao_core::FrameDesc::new(sg, f, cam, &settings))
                .unwrap();
            r.read_gbuffer()
                .unwrap()
                .iter()
                .map(|p| p.instance)
                .collect::<Vec<u32>>()
        };
        let before_img = render(&mut r, &sg, scene.f());
        let mut stack = EditStack::default();
        let f0 = scene.f();
        let slab = 1;
        let before = scene.instances[slab].transform;
        let after = glam::Mat4::from_translation(glam::Vec3::new(1000.0, 0.0, 0.0)) * before;
        let edit = Edit::Transform {
            instance: slab as u32,
            before,
            after,
        };
        run_action(&mut stack, &mut scene, &mut sg, u32::MAX, Action::Apply(edit)).unwrap();
        assert!(scene.f() > f0);
        let moved_img = render(&mut r, &sg, scene.f());
        assert_ne!(
            before_img, moved_img,
            "the TLAS was rebuilt: the slab moved out of view"
        );
        run_action(&mut stack, &mut scene, &mut sg, u32::MAX, Action::Undo).unwrap();
        assert_eq!(scene.instances[slab].transform, before);
        assert_eq!(render(&mut r, &sg, scene.f()), before_img);
        drop(r);
        drop(sg);
        assert_eq!(gpu.validation_messages(), 0);
    }
}
