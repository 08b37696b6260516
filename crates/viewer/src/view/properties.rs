//! The "Properties" section: what the selection is (its name, its path in the model tree, its instances and
//! triangles, its world bounding box and size in the file's unit) and what the open file says about itself
//! (`Scene::metadata`: glTF asset, PLY comments, STL solid name). Read only: it returns no commands.
use glam::DVec3;
use hrtao_scene::{Aabb, Scene};

use super::command::{Command, ViewState};
use super::measure::{format_len, Unit};
use super::tree::Selection;
use super::ui::{kv_grid, kv_row};
use super::ui_probe;

/// What the panel shows of a selection.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    pub name: String,
    /// Node names from a root of the model tree down to the selection's node (empty if it has none).
    pub path: Vec<String>,
    pub instances: usize,
    /// Triangles of the selected instances, summed (an instanced mesh counts once per instance).
    pub triangles: u64,
    /// World bounds in the file's coordinates (`Scene::origin` added back); None when empty.
    pub bounds: Option<(DVec3, DVec3)>,
}

/// The selection's summary; None when nothing is selected.
pub fn summarize(scene: &Scene, selection: &Selection) -> Option<Summary> {
    let instances: Vec<u32> = selection
        .instances
        .iter()
        .copied()
        .filter(|&i| (i as usize) < scene.instances.len())
        .collect();
    if instances.is_empty() {
        return None;
    }
    let node = selection
        .node
        .filter(|&n| (n as usize) < scene.tree.len())
        .or_else(|| scene.tree.owner_of(instances[0]));
    let node_name = |n: u32| scene.tree.nodes[n as usize].name.clone();
    let path: Vec<String> = node
        .map(|n| scene.tree.path(n).into_iter().map(node_name).collect())
        .unwrap_or_default();
    let name = match (instances.as_slice(), selection.node) {
        ([one], _) => {
            let inst = &scene.instances[*one as usize];
            if inst.name.is_empty() {
                format!("#{one} (unnamed)")
            } else {
                inst.name.clone()
            }
        }
        (_, Some(n)) if (n as usize) < scene.tree.len() => node_name(n),
        (many, _) => format!("{} instances", many.len()),
    };
    let triangles = instances
        .iter()
        .filter_map(|&i| scene.meshes.get(scene.instances[i as usize].mesh as usize))
        .map(|m| m.triangle_count())
        .sum();
    let b = instances
        .iter()
        .map(|&i| scene.instance_bounds(i))
        .fold(Aabb::empty(), |a, b| a.union(&b));
    let bounds = (!b.is_empty()).then(|| (scene.to_file(b.min), scene.to_file(b.max)));
    Some(Summary {
        name,
        path,
        instances: instances.len(),
        triangles,
        bounds,
    })
}

/// The file's unit as the panel names it: the one the file declares (or the viewer knows), else the format's
/// usual one; a declared unit that is none of ours is written in metres.
pub fn unit_text(scene: &Scene, known: Option<Unit>, spec: &str) -> (Option<Unit>, String) {
    if let Some(u) = known.or_else(|| scene.unit_m.and_then(Unit::from_metres)) {
        return (Some(u), u.label().to_string());
    }
    match scene.unit_m {
        Some(m) => (None, format!("{m} m")),
        None => {
            let u = Unit::of_file(spec);
            (Some(u), format!("{} (assumed: the file gives none)", u.label()))
        }
    }
}

/// Three lengths in the file's unit (`unit` None: a unit of ours it is not, bare numbers), with the decimals
/// a 4-5 significant digit reading of `scale` needs (the box's size: a zero coordinate is not written 0.00000).
fn triple(v: DVec3, scale: f64, unit: Option<Unit>) -> String {
    let decimals = format_len(scale, Unit::M)
        .split_whitespace()
        .next()
        .and_then(|n| n.split_once('.'))
        .map_or(0, |(_, d)| d.len());
    let text = [v.x, v.y, v.z].map(|c| format!("{c:.decimals$}")).join(", ");
    match unit {
        Some(u) => format!("{text} {}", u.label()),
        None => text,
    }
}

/// The "Properties" section.
#[derive(Default)]
pub struct PropertiesPanel {
    /// The unit the open file declares (or the viewer knows, as for the bundled scene).
    pub unit: Option<Unit>,
}

impl PropertiesPanel {
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let Some(scene) = state.scene else {
            ui.label("no scene");
            return Vec::new();
        };
        let (unit, unit_name) = unit_text(scene, self.unit, state.spec);
        let ppp = ui.ctx().pixels_per_point();
        match summarize(scene, state.selection) {
            None => {
                ui.label("nothing selected");
                ui_probe::note_text("properties: triangles", "");
            }
            Some(s) => {
                let triangles = s.triangles.to_string();
                ui_probe::note_text("properties: triangles", &triangles);
                let grid = kv_grid("properties").show(ui, |ui| {
                    let mut row = |k: &str, v: String| kv_row(ui, k, v);
                    row("name", s.name.clone());
                    if !s.path.is_empty() {
                        row("path", s.path.join(" / "));
                    }
                    row("instances", s.instances.to_string());
                    row("triangles", triangles);
                    row("unit", unit_name);
                    if let Some((min, max)) = s.bounds {
                        let scale = (max - min).max_element();
                        row("min", triple(min, scale, unit));
                        row("max", triple(max, scale, unit));
                        row("size", triple(max - min, scale, unit));
                    }
                });
                ui_probe::note("properties", grid.response.rect, ppp);
            }
        }
        if !scene.metadata.is_empty() {
            ui.label(egui::RichText::new("file").strong());
            kv_grid("file metadata").show(ui, |ui| {
                for (k, v) in &scene.metadata {
                    kv_row(ui, k, v);
                }
            });
        }
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Vec3};
    use hrtao_scene::{Instance, Mesh, NodeTree, Primitive};

    /// Two instances of a 2-triangle square and one of a triangle, under "asm / left" and "asm / right".
    fn scene() -> Scene {
        let mut s = Scene::new("asm");
        let prim = |positions: Vec<[f32; 3]>, indices: Vec<u32>| Primitive::new(positions, indices, [1.0; 4]);
        s.meshes.push(Mesh {
            name: "square".into(),
            primitives: vec![prim(
                vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
                vec![0, 1, 2, 0, 2, 3],
            )],
        });
        s.meshes.push(Mesh {
            name: "tri".into(),
            primitives: vec![prim(
                vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.0, 2.0]],
                vec![0, 1, 2],
            )],
        });
        for (mesh, x, name) in [(0, 0.0, "a"), (0, 5.0, "b"), (1, 10.0, "c")] {
            s.instances.push(Instance {
                mesh,
                transform: Mat4::from_translation(Vec3::new(x, 0.0, 0.0)),
                name: name.into(),
                visible: true,
            });
        }
        let mut t = NodeTree::default();
        let root = t.add("asm", None);
        let left = t.add("left", Some(root));
        let right = t.add("right", Some(root));
        t.nodes[left as usize].instances = vec![0, 1];
        t.nodes[right as usize].instances = vec![2];
        s.tree = t;
        s.origin = [1000.0, 0.0, 0.0];
        s
    }

    #[test]
    fn one_instance_a_node_and_nothing() {
        let s = scene();
        let one = summarize(&s, &Selection::of_instance(&s.tree, 2)).unwrap();
        assert_eq!(one.name, "c");
        assert_eq!(one.path, ["asm", "right"]);
        assert_eq!((one.instances, one.triangles), (1, 1));
        // File coordinates: the origin added back.
        let (min, max) = one.bounds.unwrap();
        assert_eq!(min, DVec3::new(1010.0, 0.0, 0.0));
        assert_eq!(max, DVec3::new(1011.0, 0.0, 2.0));
        // The root node: every instance, triangles summed per instance.
        let all = summarize(&s, &Selection::of_node(&s.tree, 0)).unwrap();
        assert_eq!(all.name, "asm");
        assert_eq!(all.path, ["asm"]);
        assert_eq!((all.instances, all.triangles), (3, 2 + 2 + 1));
        let (min, max) = all.bounds.unwrap();
        assert_eq!(max - min, DVec3::new(11.0, 1.0, 2.0));
        // A toggled set without a node.
        let set = Selection {
            node: None,
            instances: vec![0, 2],
        };
        let two = summarize(&s, &set).unwrap();
        assert_eq!((two.name.as_str(), two.triangles), ("2 instances", 3));
        assert_eq!(summarize(&s, &Selection::default()), None);
    }

    #[test]
    fn units() {
        let mut s = scene();
        assert_eq!(
            unit_text(&s, None, "part.stl").1,
            "mm (assumed: the file gives none)"
        );
        assert_eq!(unit_text(&s, Some(Unit::Mm), "gearbox.glb").1, "mm");
        s.unit_m = Some(0.0254);
        assert_eq!(
            unit_text(&s, None, "part.step"),
            (Some(Unit::In), "in".to_string())
        );
        s.unit_m = Some(0.1);
        assert_eq!(unit_text(&s, None, "part.step"), (None, "0.1 m".to_string()));
        assert_eq!(
            triple(DVec3::new(40.0, 0.0, 10.0), 40.0, Some(Unit::Mm)),
            "40.00, 0.00, 10.00 mm"
        );
        assert_eq!(
            triple(DVec3::new(0.5, 0.0, 1e-3), 0.5, None),
            "0.500, 0.000, 0.001"
        );
    }
}
