//! Shading normals: a coarse cylinder with vertex normals shades like a fine one (no facets), with both
//! primary-visibility paths, also as a mirrored or non-uniformly scaled instance; face normals where a mesh has
//! none.
mod common;
#[path = "../../scene/tests/common/mod.rs"]
mod scene_common;
use common::*;
use hrtao_core::gpu::NO_INSTANCE;
use hrtao_core::{Camera, Mode, Primary, SceneGpu};
use hrtao_scene::glam::{Mat4, Vec3};
use hrtao_scene::{Instance, Mesh, Primitive, Scene};

const W: u32 = 640;
const H: u32 = 360;

/// The shared capped cylinder (the scene tests' `cylinder`: the curve (a cos θ, b sin θ)); with `normals`, the
/// side's vertices carry the curve's normals and the caps ±z (their own vertices), without, the mesh has none
/// (face normals).
fn cylinder(segments: u32, a: f32, b: f32, normals: bool) -> Primitive {
    let (positions, ns, indices) = scene_common::cylinder(segments, a, b);
    Primitive::new(positions, indices, [0.8, 0.8, 0.8, 1.0])
        .with_double_sided(false)
        .with_normals(if normals { ns } else { Vec::new() })
}

fn scene_with(prim: Primitive, transform: Mat4) -> Scene {
    let mut s = Scene::new("cylinder");
    s.meshes.push(Mesh {
        name: "cylinder".into(),
        primitives: vec![prim],
    });
    s.instances.push(Instance {
        mesh: 0,
        transform,
        name: "cylinder".into(),
        visible: true,
    });
    s
}

/// From the side and a little above, so the top cap shows too.
fn camera() -> Camera {
    z_up_camera_fov([0.5, -6.0, 2.5], [0.0; 3], 40.0, (W, H))
}

/// The shaded image without AO or edges (sRGB luminance in 0..1) and which pixels show the cylinder.
fn shade(gpu: &std::sync::Arc<hrtao_core::Gpu>, scene: &Scene, primary: Primary) -> (Vec<f32>, Vec<bool>) {
    let sg = SceneGpu::new(gpu, scene).unwrap();
    let mut settings = hrtao(1, 1.0);
    settings.display.mode = Mode::NoAo;
    settings.display.edges = false;
    let mut r = Headless::new(gpu, W, H, settings).unwrap();
    r.set_primary(primary);
    r.render(&sg, scene.f(), &camera()).unwrap();
    let rgba = r.read_rgba().unwrap();
    let gb = r.read_gbuffer().unwrap();
    let lum = rgba
        .chunks(4)
        .map(|c| (0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32) / 255.0)
        .collect();
    let hit = gb.iter().map(|p| p.instance != NO_INSTANCE).collect();
    assert_clean(gpu);
    (lum, hit)
}

/// The measure of facets: 12 segments with normals shade within MAE 0.01 of 384 segments and have no
/// facet steps (p99 of the horizontal step ≤ 0.015); the same 12 segments with face normals are ≥ 3x further
/// off. Both primary-visibility paths (ray queries and the rasteriser) interpolate the same normals.
#[test]
fn a_coarse_cylinder_with_normals_shades_like_a_fine_one() {
    let gpu = gpu();
    for primary in [Primary::RayQuery, Primary::Raster] {
        let (fine, fine_hit) = shade(
            &gpu,
            &scene_with(cylinder(384, 1.0, 1.0, true), Mat4::IDENTITY),
            primary,
        );
        let (smooth, smooth_hit) = shade(
            &gpu,
            &scene_with(cylinder(12, 1.0, 1.0, true), Mat4::IDENTITY),
            primary,
        );
        let (flat, flat_hit) = shade(
            &gpu,
            &scene_with(cylinder(12, 1.0, 1.0, false), Mat4::IDENTITY),
            primary,
        );
        let what = format!("{primary:?}");
        let p_flat = scene_common::facet_measure(
            &what,
            &(fine, fine_hit),
            &(smooth, smooth_hit),
            &(flat, flat_hit),
            W as usize,
        );
        assert!(
            p_flat > 0.03,
            "{primary:?}: face normals show their facets ({p_flat})"
        );
    }
}

/// Normals go to world space by the cofactor (inverse transpose) of the instance's transform: a circular
/// cylinder scaled 2x along x shades like an elliptic one built with its own normals, and a mirrored instance
/// (its triangles wind the other way) like the unmirrored one.
#[test]
fn normals_follow_scaled_and_mirrored_instances() {
    let gpu = gpu();
    let primary = Primary::RayQuery;
    let (ellipse, ellipse_hit) = shade(
        &gpu,
        &scene_with(cylinder(384, 2.0, 1.0, true), Mat4::IDENTITY),
        primary,
    );
    let scaled = Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
    let (stretched, stretched_hit) = shade(&gpu, &scene_with(cylinder(384, 1.0, 1.0, true), scaled), primary);
    let mask = scene_common::interior(&[&ellipse_hit, &stretched_hit], W as usize);
    let e = scene_common::mae(&ellipse, &stretched, &mask);
    assert!(e < 0.004, "scaled instance: {e}");

    let (plain, plain_hit) = shade(
        &gpu,
        &scene_with(cylinder(384, 1.0, 1.0, true), Mat4::IDENTITY),
        primary,
    );
    let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let (mirrored, mirrored_hit) = shade(&gpu, &scene_with(cylinder(384, 1.0, 1.0, true), mirror), primary);
    let mask = scene_common::interior(&[&plain_hit, &mirrored_hit], W as usize);
    let e = scene_common::mae(&plain, &mirrored, &mask);
    assert!(e < 0.004, "mirrored instance: {e}");
}
