//! Scene data model (meshes shared by instances), counts, bounds, validation and edits.
//!
//! Every successful edit bumps the animation frame identifier `F` (paper eq. 6) so the
//! renderer can tell that cached per-frame data (TLAS, AO history) is stale.

use glam::{DMat4, DVec3, Mat4, Vec3};

use crate::aabb::Aabb;
use crate::error::SceneError;
use crate::tree::NodeTree;

/// Default colour for geometry without material or vertex colours.
pub const DEFAULT_BASE_COLOR: [f32; 4] = [0.8, 0.8, 0.8, 1.0];

/// One triangle list with a flat colour (one BLAS geometry).
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    pub positions: Vec<[f32; 3]>,
    /// Triangle list: `indices.len()` is a multiple of 3.
    pub indices: Vec<u32>,
    /// Linear RGBA.
    pub base_color: [f32; 4],
    /// Both faces are seen (glTF `doubleSided`). False promises closed, consistently wound geometry whose back
    /// faces never show (glTF's default), so a rasteriser may cull them; formats that say nothing (OBJ, STL, PLY)
    /// are double-sided.
    pub double_sided: bool,
    /// Shading normals, one per position, in the primitive's space (unit length, pointing out of the surface's
    /// front), interpolated across each triangle; empty: the triangles shade flat (their face normals).
    /// [`Primitive::check_normals`] empties a set that is unusable.
    pub normals: Vec<[f32; 3]>,
}

impl Primitive {
    /// A triangle list of one colour, double-sided and flat-shaded (no shading normals): what a format that says
    /// nothing else (OBJ, STL, PLY, generated scenes) builds. The other fields come from `with_…`, so that a new
    /// field changes this constructor and the loaders that set it, not every place a primitive is built.
    pub fn new(positions: Vec<[f32; 3]>, indices: Vec<u32>, base_color: [f32; 4]) -> Primitive {
        Primitive {
            positions,
            indices,
            base_color,
            double_sided: true,
            normals: Vec::new(),
        }
    }

    /// Whether both faces are seen (glTF's `doubleSided`; false lets a rasteriser cull back faces).
    pub fn with_double_sided(self, double_sided: bool) -> Primitive {
        Primitive { double_sided, ..self }
    }

    /// Shading normals, one per position (empty: flat shading; see [`Primitive::check_normals`]).
    pub fn with_normals(self, normals: Vec<[f32; 3]>) -> Primitive {
        Primitive { normals, ..self }
    }

    pub fn triangle_count(&self) -> u64 {
        (self.indices.len() / 3) as u64
    }

    /// Why the shading normals cannot be used (a count other than one per position, a non-finite or
    /// zero-length normal), or None when they can (or there are none). Normals of length other than 1 are
    /// made unit length.
    pub fn check_normals(&mut self) -> Option<String> {
        if self.normals.is_empty() {
            return None;
        }
        let why = if self.normals.len() != self.positions.len() {
            Some(format!(
                "{} normals for {} vertices",
                self.normals.len(),
                self.positions.len()
            ))
        } else {
            self.normals.iter_mut().enumerate().find_map(|(k, n)| {
                let v = Vec3::from(*n);
                let len = v.length();
                if !len.is_finite() || len < 1e-12 {
                    return Some(format!("normal {k} is {n:?}"));
                }
                *n = (v / len).to_array();
                None
            })
        };
        if why.is_some() {
            self.normals.clear();
        }
        why
    }

    /// Bounds of all vertex positions (also unreferenced ones).
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().map(|&p| Vec3::from(p)))
    }
}

/// One shared mesh (one BLAS with one geometry per primitive).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
}

impl Mesh {
    pub fn triangle_count(&self) -> u64 {
        self.primitives.iter().map(Primitive::triangle_count).sum()
    }

    /// Object-space bounds of all primitives.
    pub fn local_bounds(&self) -> Aabb {
        self.primitives
            .iter()
            .fold(Aabb::empty(), |b, p| b.union(&p.bounds()))
    }
}

/// A placement of a mesh in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`Scene::meshes`].
    pub mesh: u32,
    /// Object-to-world matrix.
    pub transform: Mat4,
    pub name: String,
    pub visible: bool,
}

/// Progress report passed to the `progress` callback of the loaders/generators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadProgress {
    pub stage: &'static str,
    pub done: u64,
    pub total: u64,
}

/// Meshes plus instances referencing them.
#[derive(Clone)]
pub struct Scene {
    pub meshes: Vec<Mesh>,
    pub instances: Vec<Instance>,
    pub name: String,
    /// Where the scene's coordinates start in the file's own coordinates: a point p of the scene is
    /// `origin + p` in the file. Zero unless the file's geometry lies far from its origin (BIM and GIS models
    /// sit 10^5-10^7 units away): loaders then compose transforms in f64 and re-centre (`recentre`), so the
    /// GPU works near zero in f32. Cameras, picks and reported positions convert with it.
    pub origin: [f64; 3],
    /// The file's node hierarchy and which instances each node owns (see [`NodeTree`]).
    pub tree: NodeTree,
    /// Metres per scene unit when the file says (STEP, IGES); `None` when the format carries no unit.
    pub unit_m: Option<f64>,
    /// What the file says about itself, as (field, value) pairs, where the loader reads it cheaply: glTF's
    /// `asset` (generator, copyright, version), PLY's comments then its obj_info lines, an ASCII STL's solid name
    /// or a binary STL's header text, a STEP file's HEADER section, an IGES file's global section. Empty when the
    /// format carries nothing (OBJ).
    pub metadata: Vec<(String, String)>,
    /// The up axis the format implies: IFC and 3MF +Z (their specifications), glTF +Y; `None` where the
    /// format says nothing (STEP, IGES, STL, OBJ, PLY, generated scenes).
    pub up: Option<crate::UpAxis>,
    /// What the loader could not read and assumed instead (an IFC file with no length unit): shown to the
    /// user and logged, never silent.
    pub warnings: Vec<String>,
    /// The building storeys of an IFC file (`IfcBuildingStorey`), in the file's order.
    pub storeys: Vec<Storey>,
    /// Animation frame identifier `F` (paper eq. 6); bumped by every edit.
    f: u32,
    /// The world bounds each recent edit changed, with the F it produced (newest last, at most
    /// `CHANGE_LOG_LEN`): what a renderer needs to invalidate only the AO near an edit.
    changes: std::collections::VecDeque<(u32, Vec<Aabb>)>,
}

/// A building storey: its node of the model tree (its elements are the node's subtree) and its elevation, the
/// height of its placement along the file's Z axis in the scene's coordinates (the file's is
/// `elevation + origin[2]`).
#[derive(Clone, Debug, PartialEq)]
pub struct Storey {
    pub name: String,
    pub node: u32,
    pub elevation: f32,
}

/// Edits remembered by [`Scene::changes_since`].
pub const CHANGE_LOG_LEN: usize = 256;

/// Geometry whose centre lies farther than this from the file's origin is re-centred (see [`Scene::origin`]).
pub const RECENTRE_DISTANCE: f64 = 1.0e4;
/// The re-centring origin is rounded to a multiple of this power of two, so hash cells up to this size keep
/// their boundaries in the file's coordinates.
pub const ORIGIN_GRID: f64 = 1024.0;

/// The origin for geometry centred at `centre` (file coordinates): zero near the file's origin, else the
/// centre rounded to [`ORIGIN_GRID`].
pub fn recentre_origin(centre: DVec3) -> DVec3 {
    if !centre.is_finite() || centre.abs().max_element() <= RECENTRE_DISTANCE {
        return DVec3::ZERO;
    }
    (centre / ORIGIN_GRID).round() * ORIGIN_GRID
}

/// World transforms composed in f64 (file coordinates) made relative to `origin`, in f32.
pub fn relative_transform(world: &DMat4, origin: DVec3) -> Mat4 {
    (DMat4::from_translation(-origin) * *world).as_mat4()
}

impl std::fmt::Debug for Scene {
    // Summary only: a derived Debug would print millions of vertices.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("name", &self.name)
            .field("meshes", &self.meshes.len())
            .field("instances", &self.instances.len())
            .field("unique_triangles", &self.unique_triangle_count())
            .field("f", &self.f)
            .finish()
    }
}

/// Vertex budget of the exact path of [`Scene::bounds`].
pub const EXACT_BOUNDS_VERTEX_BUDGET: u64 = 64_000_000;

/// True if the linear part maps axes to axes (each column has one non-negligible entry),
/// in which case transforming a box's corners gives the exact box of the transformed mesh.
fn is_axis_aligned(m: &Mat4) -> bool {
    [m.x_axis, m.y_axis, m.z_axis].iter().all(|c| {
        let c = c.truncate().abs();
        let eps = c.max_element() * 1e-6;
        (c.x > eps) as u8 + (c.y > eps) as u8 + (c.z > eps) as u8 <= 1
    })
}

/// True if every entry is finite and the determinant is finite and non-zero.
pub(crate) fn transform_ok(m: &Mat4) -> bool {
    let det = m.determinant();
    m.is_finite() && det.is_finite() && det != 0.0
}

impl Scene {
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            meshes: Vec::new(),
            instances: Vec::new(),
            name: name.into(),
            origin: [0.0; 3],
            tree: NodeTree::default(),
            unit_m: None,
            metadata: Vec::new(),
            up: None,
            warnings: Vec::new(),
            storeys: Vec::new(),
            f: 0,
            changes: Default::default(),
        }
    }

    /// A scene of one mesh with one identity instance, both named after the file (STL, PLY: one triangle
    /// soup, coordinates as in the file).
    pub fn single_mesh(path: &std::path::Path, positions: Vec<[f32; 3]>, indices: Vec<u32>) -> Scene {
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut scene = Scene::new(name.clone());
        scene.meshes.push(Mesh {
            name: name.clone(),
            primitives: vec![Primitive::new(positions, indices, DEFAULT_BASE_COLOR)],
        });
        scene.instances.push(Instance {
            mesh: 0,
            transform: Mat4::IDENTITY,
            name: name.clone(),
            visible: true,
        });
        scene.tree = NodeTree::single(name, 1);
        scene
    }

    /// A point of the scene in the file's own coordinates.
    pub fn to_file(&self, p: Vec3) -> DVec3 {
        DVec3::from(self.origin) + p.as_dvec3()
    }

    /// A point in the file's own coordinates in the scene's (GPU) coordinates.
    pub fn from_file(&self, p: DVec3) -> Vec3 {
        (p - DVec3::from(self.origin)).as_vec3()
    }

    /// The animation frame identifier `F`.
    pub fn f(&self) -> u32 {
        self.f
    }

    /// Explicit `F` increment (wrapping). The change is not located: a renderer invalidates all its AO.
    pub fn bump_f(&mut self) {
        self.f = self.f.wrapping_add(1);
    }

    /// Bumps F for an edit that changed the geometry within `changed` (world bounds; empty boxes skipped).
    fn edited(&mut self, changed: Vec<Aabb>) {
        self.bump_f();
        if self.changes.len() == CHANGE_LOG_LEN {
            self.changes.pop_front();
        }
        let changed = changed.into_iter().filter(|b| !b.is_empty()).collect();
        self.changes.push_back((self.f, changed));
    }

    /// The world bounds changed by the edits since F was `f0`, or None when they are not all known (an
    /// explicit `bump_f`, or more edits than the log keeps): then anything may have changed.
    pub fn changes_since(&self, f0: u32) -> Option<Vec<Aabb>> {
        let n = self.f.wrapping_sub(f0) as usize;
        if n > self.changes.len() {
            return None;
        }
        let recent = self.changes.iter().skip(self.changes.len() - n);
        let mut out = Vec::new();
        for (i, (f, boxes)) in recent.enumerate() {
            // Each of the last n bumps must be a logged edit, in order.
            if *f != f0.wrapping_add(i as u32 + 1) {
                return None;
            }
            out.extend(boxes.iter().copied());
        }
        Some(out)
    }

    /// World bounds of one instance (empty when out of range).
    pub fn instance_bounds(&self, instance: u32) -> Aabb {
        self.instances
            .get(instance as usize)
            .map(|i| self.mesh_bounds(i.mesh).transformed(&i.transform))
            .unwrap_or_else(Aabb::empty)
    }

    /// Triangles of every mesh counted once (unreferenced meshes included).
    pub fn unique_triangle_count(&self) -> u64 {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// Triangles summed over visible instances (what the renderer traces).
    pub fn instanced_triangle_count(&self) -> u64 {
        let per_mesh: Vec<u64> = self.meshes.iter().map(Mesh::triangle_count).collect();
        self.instances
            .iter()
            .filter(|i| i.visible)
            .map(|i| per_mesh.get(i.mesh as usize).copied().unwrap_or(0))
            .sum()
    }

    /// Object-space bounds of one mesh (empty if the id is out of range).
    pub fn mesh_bounds(&self, mesh: u32) -> Aabb {
        self.meshes
            .get(mesh as usize)
            .map(Mesh::local_bounds)
            .unwrap_or_else(Aabb::empty)
    }

    /// World bounds of all visible instances.
    ///
    /// Exact (every vertex transformed) for rotated instances as long as the total number
    /// of transformed vertices stays below [`EXACT_BOUNDS_VERTEX_BUDGET`]; axis-aligned
    /// transforms (translation, scale, 90° rotations) use the exact transformed mesh box.
    /// Beyond the budget the transformed mesh box (conservative) is used.
    pub fn bounds(&self) -> Aabb {
        let mut local: Vec<Option<Aabb>> = vec![None; self.meshes.len()];
        let mut budget = EXACT_BOUNDS_VERTEX_BUDGET;
        let mut out = Aabb::empty();
        for inst in self.instances.iter().filter(|i| i.visible) {
            let Some(mesh) = self.meshes.get(inst.mesh as usize) else {
                continue;
            };
            let m = &inst.transform;
            let verts: u64 = mesh.primitives.iter().map(|p| p.positions.len() as u64).sum();
            let b = if !is_axis_aligned(m) && verts <= budget {
                budget -= verts;
                let mut b = Aabb::empty();
                for p in mesh.primitives.iter().flat_map(|p| &p.positions) {
                    b.extend(m.transform_point3(Vec3::from(*p)));
                }
                b
            } else {
                local[inst.mesh as usize]
                    .get_or_insert_with(|| mesh.local_bounds())
                    .transformed(m)
            };
            out = out.union(&b);
        }
        out
    }

    /// Conservative world bounds: each visible instance's mesh box, transformed.
    pub fn bounds_conservative(&self) -> Aabb {
        let local: Vec<Aabb> = self.meshes.iter().map(Mesh::local_bounds).collect();
        self.instances
            .iter()
            .filter(|i| i.visible)
            .filter_map(|i| local.get(i.mesh as usize).map(|b| b.transformed(&i.transform)))
            .fold(Aabb::empty(), |a, b| a.union(&b))
    }

    /// Checks indices, positions, transforms and mesh references.
    pub fn validate(&self) -> Result<(), SceneError> {
        let n = |s: &str| {
            if s.is_empty() {
                String::new()
            } else {
                format!(" ({s:?})")
            }
        };
        for (mi, mesh) in self.meshes.iter().enumerate() {
            for (pi, prim) in mesh.primitives.iter().enumerate() {
                let at = format!("mesh {mi}{} primitive {pi}", n(&mesh.name));
                if prim.indices.len() % 3 != 0 {
                    return Err(SceneError::Invalid(format!(
                        "{at}: index count {} is not a multiple of 3",
                        prim.indices.len()
                    )));
                }
                let nv = prim.positions.len();
                if let Some((k, &i)) = prim.indices.iter().enumerate().find(|(_, &i)| i as usize >= nv) {
                    return Err(SceneError::Invalid(format!(
                        "{at}: index {k} is {i} but there are only {nv} vertices"
                    )));
                }
                if let Some((k, p)) = prim
                    .positions
                    .iter()
                    .enumerate()
                    .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
                {
                    return Err(SceneError::Invalid(format!(
                        "{at}: vertex {k} has a non-finite position {p:?}"
                    )));
                }
                if !prim.base_color.iter().all(|c| c.is_finite()) {
                    return Err(SceneError::Invalid(format!(
                        "{at}: non-finite base colour {:?}",
                        prim.base_color
                    )));
                }
            }
        }
        for (ii, inst) in self.instances.iter().enumerate() {
            if inst.mesh as usize >= self.meshes.len() {
                return Err(SceneError::Invalid(format!(
                    "instance {ii}{} references mesh {} but there are only {} meshes",
                    n(&inst.name),
                    inst.mesh,
                    self.meshes.len()
                )));
            }
            if !transform_ok(&inst.transform) {
                return Err(SceneError::Invalid(format!(
                    "instance {ii}{} has a non-finite or singular transform {:?}",
                    n(&inst.name),
                    inst.transform.to_cols_array()
                )));
            }
        }
        self.tree.validate(self.instances.len())
    }

    fn check_instance(&self, instance: u32) -> Result<usize, SceneError> {
        if (instance as usize) < self.instances.len() {
            Ok(instance as usize)
        } else {
            Err(SceneError::OutOfRange {
                what: "instance",
                index: instance as u64,
                len: self.instances.len() as u64,
            })
        }
    }

    fn check_new_instance(&self, inst: &Instance) -> Result<(), SceneError> {
        if inst.mesh as usize >= self.meshes.len() {
            return Err(SceneError::OutOfRange {
                what: "mesh",
                index: inst.mesh as u64,
                len: self.meshes.len() as u64,
            });
        }
        check_transform(&inst.transform)
    }

    /// Replaces an instance's object-to-world matrix. Rejects non-finite or singular matrices.
    pub fn set_transform(&mut self, instance: u32, m: Mat4) -> Result<(), SceneError> {
        let i = self.check_instance(instance)?;
        check_transform(&m)?;
        let before = self.instance_bounds(instance);
        self.instances[i].transform = m;
        let after = self.instance_bounds(instance);
        self.edited(vec![before, after]);
        Ok(())
    }

    /// Shows or hides an instance.
    pub fn set_visible(&mut self, instance: u32, visible: bool) -> Result<(), SceneError> {
        let i = self.check_instance(instance)?;
        self.instances[i].visible = visible;
        self.edited(vec![self.instance_bounds(instance)]);
        Ok(())
    }

    /// Sets the visibility of several instances as one edit (F increments once). All ids are checked
    /// before anything changes.
    pub fn set_visibility(&mut self, changes: &[(u32, bool)]) -> Result<(), SceneError> {
        for &(i, _) in changes {
            self.check_instance(i)?;
        }
        for &(i, v) in changes {
            self.instances[i as usize].visible = v;
        }
        let changed = changes.iter().map(|&(i, _)| self.instance_bounds(i)).collect();
        self.edited(changed);
        Ok(())
    }

    /// Removes an instance (later ids shift down by one) and returns it for undo.
    pub fn remove_instance(&mut self, instance: u32) -> Result<Instance, SceneError> {
        let i = self.check_instance(instance)?;
        let bounds = self.instance_bounds(instance);
        let inst = self.instances.remove(i);
        self.tree.instance_removed(instance);
        self.edited(vec![bounds]);
        Ok(inst)
    }

    /// Inserts an instance at position `at` (`at == instances.len()` appends), owned by no tree node.
    pub fn insert_instance(&mut self, at: u32, inst: Instance) -> Result<(), SceneError> {
        self.insert_instance_in(at, inst, None)
    }

    /// Inserts an instance at position `at` owned by tree node `owner` (undo of remove; see
    /// [`NodeTree::owner_of`]).
    pub fn insert_instance_in(
        &mut self,
        at: u32,
        inst: Instance,
        owner: Option<u32>,
    ) -> Result<(), SceneError> {
        if at as usize > self.instances.len() {
            return Err(SceneError::OutOfRange {
                what: "insert position",
                index: at as u64,
                len: self.instances.len() as u64,
            });
        }
        self.check_new_instance(&inst)?;
        self.instances.insert(at as usize, inst);
        self.tree.instance_inserted(at, owner);
        self.edited(vec![self.instance_bounds(at)]);
        Ok(())
    }

    /// Appends an instance and returns its id.
    pub fn add_instance(&mut self, inst: Instance) -> Result<u32, SceneError> {
        let id = u32::try_from(self.instances.len())
            .map_err(|_| SceneError::TooLarge(format!("scene {} has too many instances", self.name)))?;
        self.check_new_instance(&inst)?;
        self.instances.push(inst);
        self.edited(vec![self.instance_bounds(id)]);
        Ok(id)
    }
}

fn check_transform(m: &Mat4) -> Result<(), SceneError> {
    if transform_ok(m) {
        Ok(())
    } else {
        Err(SceneError::Invalid(format!(
            "transform must be finite and invertible, got {:?}",
            m.to_cols_array()
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Usable normals come out unit length; a wrong count, a NaN or a zero normal empties the set (face
    /// normals) and says why.
    #[test]
    fn unusable_normals_fall_back_to_face_normals() {
        let prim = |normals: Vec<[f32; 3]>| {
            Primitive::new(
                vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                vec![0, 1, 2],
                DEFAULT_BASE_COLOR,
            )
            .with_normals(normals)
        };
        let mut ok = prim(vec![[0.0, 0.0, 2.0], [0.0, 3.0, 4.0], [0.0, 0.0, -0.5]]);
        assert_eq!(ok.check_normals(), None);
        assert_eq!(
            ok.normals,
            vec![[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.0, 0.0, -1.0]]
        );
        for (bad, why) in [
            (vec![[0.0, 0.0, 1.0]; 2], "2 normals for 3 vertices"),
            (
                vec![[0.0, 0.0, 1.0], [f32::NAN, 0.0, 1.0], [0.0, 0.0, 1.0]],
                "normal 1",
            ),
            (vec![[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0; 3]], "normal 2"),
        ] {
            let mut p = prim(bad);
            let msg = p.check_normals().expect("unusable");
            assert!(msg.contains(why), "{msg}");
            assert!(p.normals.is_empty());
        }
        let mut none = prim(Vec::new());
        assert_eq!(none.check_normals(), None);
    }

    fn tri_scene() -> Scene {
        let mut s = Scene::new("t");
        s.meshes.push(Mesh {
            name: "tri".into(),
            primitives: vec![Primitive::new(
                vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                vec![0, 1, 2],
                DEFAULT_BASE_COLOR,
            )],
        });
        for x in 0..3 {
            s.instances.push(Instance {
                mesh: 0,
                transform: Mat4::from_translation(Vec3::new(x as f32 * 10.0, 0.0, 0.0)),
                name: format!("i{x}"),
                visible: true,
            });
        }
        s
    }

    #[test]
    fn counts_and_bounds() {
        let mut s = tri_scene();
        assert_eq!(s.unique_triangle_count(), 1);
        assert_eq!(s.instanced_triangle_count(), 3);
        let b = s.bounds();
        assert_eq!(b.min, Vec3::ZERO);
        assert_eq!(b.max, Vec3::new(21.0, 1.0, 0.0));
        s.set_visible(2, false).unwrap();
        assert_eq!(s.instanced_triangle_count(), 2);
        assert_eq!(s.bounds().max, Vec3::new(11.0, 1.0, 0.0));
        assert_eq!(s.mesh_bounds(0).max, Vec3::new(1.0, 1.0, 0.0));
        assert!(s.mesh_bounds(7).is_empty());
        s.validate().unwrap();
    }

    #[test]
    fn validate_names_the_culprit() {
        let mut s = tri_scene();
        s.meshes[0].primitives[0].indices[2] = 3;
        let e = s.validate().unwrap_err().to_string();
        assert!(
            e.contains("mesh 0") && e.contains("primitive 0") && e.contains("index 2"),
            "{e}"
        );

        let mut s = tri_scene();
        s.meshes[0].primitives[0].positions[1][1] = f32::NAN;
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("vertex 1") && e.contains("non-finite"), "{e}");

        let mut s = tri_scene();
        s.instances[1].transform = Mat4::ZERO;
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("instance 1"), "{e}");

        let mut s = tri_scene();
        s.instances[2].mesh = 5;
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("instance 2") && e.contains("mesh 5"), "{e}");
    }

    #[test]
    fn bounds_are_exact_for_rotated_instances() {
        let mut s = tri_scene();
        s.instances.truncate(1);
        s.instances[0].transform = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4);
        let exact = s.bounds();
        let loose = s.bounds_conservative();
        let r = std::f32::consts::FRAC_1_SQRT_2;
        assert!((exact.max.y - r).abs() < 1e-6, "{exact:?}");
        assert!((exact.min.x + r).abs() < 1e-6, "{exact:?}");
        assert!(loose.max.y > exact.max.y + 0.5, "{loose:?}");
        // Axis-aligned transforms take the box path, which is exact there.
        s.instances[0].transform = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let b = s.bounds();
        assert!(
            (b.min.x + 1.0).abs() < 1e-6 && (b.max.y - 1.0).abs() < 1e-6,
            "{b:?}"
        );
    }

    #[test]
    fn frame_wraps() {
        let mut s = tri_scene();
        s.f = u32::MAX;
        s.bump_f();
        assert_eq!(s.f(), 0);
    }
}
