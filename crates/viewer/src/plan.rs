//! A storey's plan view, as BIM viewers draw a floor plan: only that storey's elements (those of its node in the
//! model tree that are shown), cut by a horizontal section plane at the storey's elevation plus the cut height
//! (default 1.2 m, in the file's unit), seen from the top in an orthographic view framing the storey. Pure: the
//! viewer's panel (view/storeys.rs) and `hrtao render --plan` apply it.
use hrtao_core::{SectionPlane, Sections};
use hrtao_scene::{Aabb, Scene};

/// The default cut height above a storey's elevation, in metres.
pub const CUT_HEIGHT_M: f32 = 1.2;

/// What the plan view of a storey shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub storey: usize,
    /// Per instance: shown in the plan (the storey's, where shown now).
    pub visible: Vec<bool>,
    /// The cut: one plane, cutting away what lies above `cut` (scene coordinates, along Z).
    pub sections: Sections,
    pub cut: f32,
    /// The storey's shown elements' bounds (what the view frames).
    pub bounds: Aabb,
}

/// The storey `name` names: its name, or its tree label ("Name (IfcBuildingStorey)"), any case; else its index.
pub fn find_storey(scene: &Scene, name: &str) -> Result<usize, String> {
    let want = name.trim().to_lowercase();
    scene
        .storeys
        .iter()
        .position(|s| {
            s.name.to_lowercase() == want
                || scene
                    .tree
                    .nodes
                    .get(s.node as usize)
                    .is_some_and(|n| n.name.to_lowercase() == want)
        })
        .or_else(|| want.parse::<usize>().ok().filter(|&i| i < scene.storeys.len()))
        .ok_or_else(|| {
            let names: Vec<&str> = scene.storeys.iter().map(|s| s.name.as_str()).collect();
            if names.is_empty() {
                "the model has no storeys (IfcBuildingStorey)".to_string()
            } else {
                format!("no storey `{name}`: the storeys are {}", names.join(", "))
            }
        })
}

/// The plan view of storey `storey`, cut `cut_height` scene units above its elevation.
pub fn plan(scene: &Scene, storey: usize, cut_height: f32) -> Result<Plan, String> {
    let s = scene
        .storeys
        .get(storey)
        .ok_or_else(|| format!("no storey {storey}"))?;
    let mine = scene.tree.subtree_instances(s.node);
    let visible: Vec<bool> = (0..scene.instances.len() as u32)
        .map(|i| mine.binary_search(&i).is_ok() && scene.instances[i as usize].visible)
        .collect();
    let bounds = visible
        .iter()
        .enumerate()
        .filter(|(_, v)| **v)
        .map(|(i, _)| scene.instance_bounds(i as u32))
        .fold(Aabb::empty(), |a, b| a.union(&b));
    if bounds.is_empty() {
        return Err(format!("storey `{}` shows no element", s.name));
    }
    let cut = s.elevation + cut_height;
    let sections = Sections::new(vec![SectionPlane::new([0.0, 0.0, 1.0], cut)?])?;
    Ok(Plan {
        storey,
        visible,
        sections,
        cut,
        bounds,
    })
}

/// `render --plan STOREY`: the scene shows the plan's elements, and the prepared view is its section and its
/// top view at the prepared camera's size.
pub fn apply(scene: &mut Scene, prepared: &mut crate::setup::Prepared, storey: &str) -> anyhow::Result<()> {
    let k = find_storey(scene, storey).map_err(|e| anyhow::anyhow!("--plan: {e}"))?;
    let metres = crate::setup::metres_per_unit(scene, false);
    let p = plan(scene, k, CUT_HEIGHT_M / metres).map_err(|e| anyhow::anyhow!("--plan: {e}"))?;
    for (inst, v) in scene.instances.iter_mut().zip(&p.visible) {
        inst.visible = *v;
    }
    prepared.camera = top_view(&prepared.camera, &p.bounds);
    prepared.sections = p.sections.clone();
    log::info!(
        "plan view of storey `{}`: section at z = {} (file), {} of {} instances shown",
        scene.storeys[k].name,
        p.cut as f64 + scene.origin[2],
        p.visible.iter().filter(|v| **v).count(),
        p.visible.len()
    );
    Ok(())
}

/// The orthographic top view (down the file's Z, Y up in the image) framing `b`, at `cam`'s size and lens.
pub fn top_view(cam: &hrtao_core::Camera, b: &Aabb) -> hrtao_core::Camera {
    crate::view::nav::std_view(
        cam,
        crate::view::nav::StdView::Top,
        hrtao_core::camera::UpAxis::Z,
        b.min,
        b.max,
    )
    .0
}

#[cfg(test)]
mod tests {
    use super::*;
    use hrtao_scene::glam::{Mat4, Vec3};
    use hrtao_scene::{Instance, Mesh, Primitive, Storey};

    /// Two storeys of one slab each, at z 0 and 3, and a roof outside both.
    fn building() -> Scene {
        let mut s = Scene::new("b");
        s.meshes.push(Mesh {
            name: "slab".into(),
            primitives: vec![Primitive::new(
                vec![
                    [0.0, 0.0, 0.0],
                    [10.0, 0.0, 0.0],
                    [10.0, 8.0, 0.2],
                    [0.0, 8.0, 0.2],
                ],
                vec![0, 1, 2, 0, 2, 3],
                [1.0; 4],
            )],
        });
        let project = s.tree.add("Project (IfcProject)", None);
        for (k, z) in [0.0f32, 3.0, 6.0].into_iter().enumerate() {
            let parent = if k < 2 {
                let node = s
                    .tree
                    .add(format!("Level {k} (IfcBuildingStorey)"), Some(project));
                s.storeys.push(Storey {
                    name: format!("Level {k}"),
                    node,
                    elevation: z,
                });
                node
            } else {
                project
            };
            let leaf = s.tree.add(format!("Slab {k} (IfcSlab)"), Some(parent));
            s.tree.nodes[leaf as usize]
                .instances
                .push(s.instances.len() as u32);
            s.instances.push(Instance {
                mesh: 0,
                transform: Mat4::from_translation(Vec3::new(0.0, 0.0, z)),
                name: format!("Slab {k}"),
                visible: true,
            });
        }
        s
    }

    #[test]
    fn a_plan_shows_its_storey_cut_above_its_elevation() {
        let mut s = building();
        assert_eq!(find_storey(&s, "level 1"), Ok(1));
        assert_eq!(find_storey(&s, "Level 0 (IfcBuildingStorey)"), Ok(0));
        assert!(find_storey(&s, "Roof").unwrap_err().contains("Level 0, Level 1"));
        let p = plan(&s, 1, 1.2).unwrap();
        assert_eq!(p.visible, [false, true, false]);
        assert!((p.cut - 4.2).abs() < 1e-6);
        assert_eq!(p.sections.planes[0].normal, [0.0, 0.0, 1.0]);
        assert!((p.sections.planes[0].offset - 4.2).abs() < 1e-6);
        assert!((p.bounds.min.z - 3.0).abs() < 1e-6);
        // A hidden element of the storey stays hidden; a storey with nothing shown has no plan.
        s.instances[1].visible = false;
        assert!(plan(&s, 1, 1.2).unwrap_err().contains("no element"));
    }
}
