//! Edits that keep the AO they do not touch (ours, regions.rs): moving one small part invalidates only the
//! cells within reach of its old and new bounds; the paper's global F (eq. 6) is the comparison.
mod common;

use common::*;
use glam::{Mat4, Vec3};
use hrtao_core::{AoSettings, Camera, Renderer, SceneGpu};
use hrtao_scene::{Instance, Mesh, Primitive, Scene};

/// A closed axis-aligned box of half extents `h` centred at the origin.
fn cube(h: Vec3) -> Primitive {
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, Vec3::Y, Vec3::X),
    ];
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for (n, a, b) in faces {
        let base = positions.len() as u32;
        let q = quad(n * h, a * h, b * h);
        positions.extend(q.positions);
        indices.extend(q.indices.iter().map(|i| i + base));
    }
    Primitive {
        positions,
        indices,
        base_color: [0.8, 0.8, 0.8, 1.0],
    }
}

/// A floor (instance 0) with a row of 2 x 2 x 2 blocks (instances 1..) standing on it along x, 12 apart.
fn yard() -> Scene {
    let mut s = scene_of(vec![floor()]);
    s.meshes.push(Mesh {
        name: "block".into(),
        primitives: vec![cube(Vec3::ONE)],
    });
    for i in 0..7 {
        s.instances.push(Instance {
            mesh: 1,
            transform: Mat4::from_translation(Vec3::new(-36.0 + 12.0 * i as f32, 0.0, 1.0)),
            name: format!("block {i}"),
            visible: true,
        });
    }
    s
}

const RADIUS: f32 = 3.0;

fn camera() -> Camera {
    Camera {
        eye: [0.0, -30.0, 40.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        fov_y_deg: 60.0,
        width: 240,
        height: 135,
        ..Camera::default()
    }
}

/// Distance from `p` to the box (lo, hi) (0 inside).
fn box_distance(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    (lo - p).max(p - hi).max(Vec3::ZERO).length()
}

struct EditRun {
    /// Mean |ΔAO| over the pixels farther than 2R from the moved part's old and new bounds, and the largest,
    /// between the frame after the edit and the same frame of a control run without the edit (the still
    /// refinement keeps changing pixels from frame to frame: only the edit's effect is measured).
    far_mean: f32,
    far_max: f32,
    far_pixels: usize,
    /// Rays the cells took in the frame after the edit, and in a frame from an empty map.
    cell_rays_after: u64,
    cell_rays_empty: u64,
    /// MAE after 16 more frames near the part against a render of the edited scene from an empty map.
    near_mae: f32,
}

/// The edit: block 4 (in the middle of the row) moves by 3 units along y.
const PART: u32 = 4;
fn moved(scene: &Scene) -> Mat4 {
    Mat4::from_translation(Vec3::new(0.0, 3.0, 0.0)) * scene.instances[PART as usize].transform
}

fn run(settings: AoSettings) -> EditRun {
    let gpu = gpu();
    let cam = camera();
    let mut scene = yard();
    let control_scene = yard();
    let mut sg = SceneGpu::new(&gpu, &scene).unwrap();
    let control_sg = SceneGpu::new(&gpu, &control_scene).unwrap();
    let mut r = Renderer::new(&gpu, cam.width, cam.height, settings.clone()).unwrap();
    let mut control = Renderer::new(&gpu, cam.width, cam.height, settings.clone()).unwrap();
    let mut cell_rays_empty = 0;
    for f in 0..24 {
        let rep = r.render(&sg, scene.f(), &cam).unwrap();
        control.render(&control_sg, control_scene.f(), &cam).unwrap();
        if f == 0 {
            cell_rays_empty = rep.cell_rays;
        }
    }
    let old = scene.instance_bounds(PART);
    scene.set_transform(PART, moved(&scene)).unwrap();
    sg.update_instances(&scene, u32::MAX).unwrap();
    let new = scene.instance_bounds(PART);
    let rep = r.render(&sg, scene.f(), &cam).unwrap();
    control.render(&control_sg, control_scene.f(), &cam).unwrap();
    let (after, kept) = (r.read_ao().unwrap(), control.read_ao().unwrap());
    let (gbuf, gbuf_kept) = (r.read_gbuffer().unwrap(), control.read_gbuffer().unwrap());
    let near_part = |p: Vec3| box_distance(p, old.min, old.max).min(box_distance(p, new.min, new.max));
    let (mut sum, mut max, mut n) = (0.0f32, 0.0f32, 0usize);
    for i in 0..after.len() {
        let (p, q) = (&gbuf[i], &gbuf_kept[i]);
        if p.t < 0.0
            || q.t < 0.0
            || p.instance != q.instance
            || near_part(Vec3::from(p.position)) <= 2.0 * RADIUS
        {
            continue;
        }
        let delta = (after[i] - kept[i]).abs();
        sum += delta;
        max = max.max(delta);
        n += 1;
    }
    for _ in 0..16 {
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    let edited = r.read_ao().unwrap();
    // The edited scene from an empty map, same settings and frame count.
    let (fresh, _) = render(&gpu, &scene, &cam, settings, 17);
    let fresh = fresh.read_ao().unwrap();
    let near: Vec<usize> = (0..edited.len())
        .filter(|&i| gbuf[i].t >= 0.0 && near_part(Vec3::from(gbuf[i].position)) <= 2.0 * RADIUS)
        .collect();
    let pick = |img: &[f32]| near.iter().map(|&i| img[i]).collect::<Vec<f32>>();
    assert_clean(&gpu);
    EditRun {
        far_mean: sum / n.max(1) as f32,
        far_max: max,
        far_pixels: n,
        cell_rays_after: rep.cell_rays,
        cell_rays_empty,
        near_mae: mae(&pick(&edited), &pick(&fresh)),
    }
}

#[test]
fn moving_one_part_keeps_the_ao_far_from_it() {
    // Cells full after 16 rays per pixel, so that after 24 frames only new cells take rays.
    let settings = AoSettings {
        max_samples: 64,
        ..hrtao(4, RADIUS)
    };
    let ours = run(settings.clone());
    let paper = run(AoSettings {
        local_edits: false,
        ..settings
    });
    for (name, e) in [("local edits", &ours), ("global F (paper)", &paper)] {
        println!(
            "{name}: far pixels ({}) change by {:.4} on average, at most {:.4}; cell rays after the edit {} \
             ({:.1} % of an empty map's {}); near the part after 16 frames: MAE {:.4} against a fresh render",
            e.far_pixels,
            e.far_mean,
            e.far_max,
            e.cell_rays_after,
            100.0 * e.cell_rays_after as f64 / e.cell_rays_empty as f64,
            e.cell_rays_empty,
            e.near_mae
        );
    }
    assert!(ours.far_pixels > 10_000, "most of the image is far from the part");
    // (a) The AO far from the edit stays.
    assert!(ours.far_mean < 0.001, "far pixels changed by {}", ours.far_mean);
    assert!(ours.far_max < 0.01, "a far pixel changed by {}", ours.far_max);
    // (b) Near the part, the AO is that of the edited scene.
    assert!(ours.near_mae <= 0.02, "near the part: MAE {}", ours.near_mae);
    // (c) The frame after the edit traces at most a quarter of the rays of a frame from an empty map.
    assert!(
        4 * ours.cell_rays_after <= ours.cell_rays_empty,
        "{} cell rays after the edit, {} from an empty map",
        ours.cell_rays_after,
        ours.cell_rays_empty
    );
    // The paper's global F restarts everything: the comparison shows what the regions save.
    assert!(paper.cell_rays_after * 2 > paper.cell_rays_empty);
    assert!(paper.far_mean > ours.far_mean);
}
