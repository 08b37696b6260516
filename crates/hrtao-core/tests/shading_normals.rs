//! Shading normals: a coarse cylinder with vertex normals shades like a fine one (no facets), with both
//! primary-visibility paths, also as a mirrored or non-uniformly scaled instance; face normals where a mesh has
//! none.
mod common;
use common::*;
use hrtao_core::gpu::NO_INSTANCE;
use hrtao_core::{Camera, Mode, Primary, SceneGpu};
use hrtao_scene::glam::{Mat4, Vec3};
use hrtao_scene::{Instance, Mesh, Primitive, Scene};

const W: u32 = 640;
const H: u32 = 360;

/// A capped cylinder along z (z from -1 to 1) whose side is the curve (a cos θ, b sin θ) over `segments`
/// steps; with `normals`, the side's vertices carry the curve's normals and the caps ±z (their own vertices),
/// without, the mesh has none (face normals).
fn cylinder(segments: u32, a: f32, b: f32, normals: bool) -> Primitive {
    let mut positions = Vec::new();
    let mut ns = Vec::new();
    let mut indices = Vec::new();
    let ring = |k: u32| {
        let t = std::f32::consts::TAU * k as f32 / segments as f32;
        (
            a * t.cos(),
            b * t.sin(),
            Vec3::new(t.cos() / a, t.sin() / b, 0.0).normalize(),
        )
    };
    // Side: two vertices per step.
    for k in 0..segments {
        let (x, y, n) = ring(k);
        positions.push([x, y, -1.0]);
        positions.push([x, y, 1.0]);
        ns.push(n.to_array());
        ns.push(n.to_array());
    }
    for k in 0..segments {
        let (i, j) = (2 * k, 2 * ((k + 1) % segments));
        indices.extend_from_slice(&[i, j, j + 1, i, j + 1, i + 1]);
    }
    // Caps: a centre and a ring each.
    for (z, nz) in [(-1.0f32, -1.0f32), (1.0, 1.0)] {
        let centre = positions.len() as u32;
        positions.push([0.0, 0.0, z]);
        ns.push([0.0, 0.0, nz]);
        for k in 0..segments {
            let (x, y, _) = ring(k);
            positions.push([x, y, z]);
            ns.push([0.0, 0.0, nz]);
        }
        for k in 0..segments {
            let (i, j) = (centre + 1 + k, centre + 1 + (k + 1) % segments);
            if nz > 0.0 {
                indices.extend_from_slice(&[centre, i, j]);
            } else {
                indices.extend_from_slice(&[centre, j, i]);
            }
        }
    }
    Primitive {
        positions,
        indices,
        base_color: [0.8, 0.8, 0.8, 1.0],
        double_sided: false,
        normals: if normals { ns } else { Vec::new() },
    }
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
    Camera {
        eye: [0.5, -6.0, 2.5],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        fov_y_deg: 40.0,
        width: W,
        height: H,
        ..Default::default()
    }
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

/// Pixels at least 3 pixels from every silhouette of all the masks given (covered in all of them).
fn interior(masks: &[&[bool]]) -> Vec<bool> {
    let (w, h) = (W as i32, H as i32);
    let covered =
        |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h && masks.iter().all(|m| m[(y * w + x) as usize]);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| (-3..=3).all(|dy| (-3..=3).all(|dx| covered(x + dx, y + dy))))
        .collect()
}

fn mae(a: &[f32], b: &[f32], mask: &[bool]) -> f32 {
    let (sum, n) = a
        .iter()
        .zip(b)
        .zip(mask)
        .filter(|(_, &m)| m)
        .fold((0.0f64, 0usize), |(s, n), ((x, y), _)| {
            (s + (x - y).abs() as f64, n + 1)
        });
    assert!(n > 10_000, "only {n} pixels to compare");
    (sum / n as f64) as f32
}

/// The 99th percentile of the luminance step between horizontal neighbours inside `mask`.
fn step_p99(lum: &[f32], mask: &[bool]) -> f32 {
    let w = W as usize;
    let mut steps: Vec<f32> = (0..lum.len() - 1)
        .filter(|&i| (i + 1) % w != 0 && mask[i] && mask[i + 1])
        .map(|i| (lum[i + 1] - lum[i]).abs())
        .collect();
    steps.sort_by(f32::total_cmp);
    steps[steps.len() * 99 / 100]
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
        let mask = interior(&[&fine_hit, &smooth_hit, &flat_hit]);
        let (e_smooth, e_flat) = (mae(&smooth, &fine, &mask), mae(&flat, &fine, &mask));
        let (p_smooth, p_fine, p_flat) = (
            step_p99(&smooth, &mask),
            step_p99(&fine, &mask),
            step_p99(&flat, &mask),
        );
        eprintln!(
            "{primary:?}: MAE to 384 segments: normals {e_smooth:.4}, face normals {e_flat:.4}; \
             p99 step: normals {p_smooth:.4}, 384 segments {p_fine:.4}, face normals {p_flat:.4}"
        );
        assert!(e_smooth <= 0.01, "{primary:?}: {e_smooth}");
        assert!(e_flat >= 3.0 * e_smooth, "{primary:?}: {e_flat} vs {e_smooth}");
        assert!(p_smooth <= 0.015, "{primary:?}: facet steps {p_smooth}");
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
    let mask = interior(&[&ellipse_hit, &stretched_hit]);
    let e = mae(&ellipse, &stretched, &mask);
    assert!(e < 0.004, "scaled instance: {e}");

    let (plain, plain_hit) = shade(
        &gpu,
        &scene_with(cylinder(384, 1.0, 1.0, true), Mat4::IDENTITY),
        primary,
    );
    let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let (mirrored, mirrored_hit) = shade(&gpu, &scene_with(cylinder(384, 1.0, 1.0, true), mirror), primary);
    let mask = interior(&[&plain_hit, &mirrored_hit]);
    let e = mae(&plain, &mirrored, &mask);
    assert!(e < 0.004, "mirrored instance: {e}");
}
