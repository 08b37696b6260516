//! Test helpers: a validated GPU context and small analytic scenes built in code.
#![allow(dead_code)]
use std::sync::Arc;

use hrtao_core::{
    AoSettings, Camera, ContextOptions, FrameDesc, FrameReport, Gpu, Mode, Output, RayBudget, Renderer,
    SceneGpu,
};
use hrtao_scene::glam::{Mat4, Vec3};
use hrtao_scene::{Instance, Mesh, Primitive, Scene};

/// A GPU context with the Khronos validation layer on where it is installed (tests fail on any message: see
/// `assert_clean`; without the layer the context says that validation is skipped and runs without it).
pub fn gpu() -> Arc<Gpu> {
    let _ = env_logger::builder().is_test(true).try_init();
    let opts = ContextOptions {
        validation: true,
        device: std::env::var("HRTAO_DEVICE").ok(),
        ..Default::default()
    };
    Gpu::new(&opts)
        .expect("a Vulkan device with ray queries or ray-tracing pipelines (run scripts/install-deps.sh)")
}

/// Whether the device the tests open (`HRTAO_DEVICE`) can trace with ray queries, judged as `Gpu::new` judges it
/// with the query backend forced: false on a GPU that traces with pipelines only, or under
/// `HRTAO_HIDE_RAY_QUERY=1`. Then prints why `test` (the test or the part of it that needs ray queries) is
/// skipped. A machine with no usable device at all is not a reason to skip: true, and the test fails as before.
pub fn ray_queries_or_skip(test: &str) -> bool {
    let device = std::env::var("HRTAO_DEVICE").ok();
    let listing = |ray_backend| {
        hrtao_core::context::list_devices(&ContextOptions {
            device: device.clone(),
            ray_backend,
            ..Default::default()
        })
        .unwrap_or_default()
    };
    let forced = listing(Some(hrtao_core::RayBackend::Query));
    if forced.iter().any(|d| d.chosen) || !listing(None).iter().any(|d| d.chosen) {
        return true;
    }
    let why: Vec<String> = forced
        .iter()
        .map(|d| format!("{}: {}", d.name, d.problem.as_deref().unwrap_or("usable")))
        .collect();
    eprintln!("skipped: {test}: no device with ray queries ({})", why.join("; "));
    false
}

/// Whether `gpu` runs with the validation layer; prints why `test` is skipped when it does not (asked for, but the
/// layer is not installed: the context runs without it, `hrtao_core::context::VALIDATION_SKIPPED`).
pub fn validation_or_skip(gpu: &Gpu, test: &str) -> bool {
    if !gpu.info.validation {
        eprintln!("skipped: {test}: the Khronos validation layer is not installed");
    }
    gpu.info.validation
}

pub fn assert_clean(gpu: &Gpu) {
    assert_eq!(
        gpu.validation_messages(),
        0,
        "the validation layer reported messages (see the log above)"
    );
}

/// An axis-aligned quad as a mesh: centre, two half-extent edge vectors.
pub fn quad(center: Vec3, a: Vec3, b: Vec3) -> Primitive {
    let p = [center - a - b, center + a - b, center + a + b, center - a + b];
    Primitive::new(
        p.iter().map(|v| v.to_array()).collect(),
        vec![0, 1, 2, 0, 2, 3],
        [0.8, 0.8, 0.8, 1.0],
    )
}

/// A closed axis-aligned box of half extents `h` centred at the origin.
pub fn cube(h: Vec3) -> Primitive {
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
    Primitive::new(positions, indices, [0.8, 0.8, 0.8, 1.0])
}

/// `floor` (instance 0) with `n` 2 x 2 x 2 blocks (instances 1..=n) standing on it in a row along x, `spacing`
/// apart and centred on the origin.
pub fn row_of_blocks(floor: Primitive, n: u32, spacing: f32) -> Scene {
    let mut s = scene_of(vec![floor]);
    s.meshes.push(Mesh {
        name: "block".into(),
        primitives: vec![cube(Vec3::ONE)],
    });
    let first = -spacing * (n as f32 - 1.0) / 2.0;
    for i in 0..n {
        s.instances.push(Instance {
            mesh: 1,
            transform: Mat4::from_translation(Vec3::new(first + spacing * i as f32, 0.0, 1.0)),
            name: format!("block {i}"),
            visible: true,
        });
    }
    s
}

/// `floor()` (instance 0) and a part on it (`add_part`).
pub fn floor_with_part(name: &str, primitives: Vec<Primitive>, at: Vec3) -> Scene {
    let mut scene = scene_of(vec![floor()]);
    add_part(&mut scene, name, primitives, at);
    scene
}

/// Adds a part to `scene`: a mesh `name` of `primitives` and one visible instance of it moved by `at`.
pub fn add_part(scene: &mut Scene, name: &str, primitives: Vec<Primitive>, at: Vec3) {
    scene.meshes.push(Mesh {
        name: name.into(),
        primitives,
    });
    scene.instances.push(Instance {
        mesh: scene.meshes.len() as u32 - 1,
        transform: Mat4::from_translation(at),
        name: name.into(),
        visible: true,
    });
}

pub fn scene_of(prims: Vec<Primitive>) -> Scene {
    let mut s = Scene::new("test");
    s.meshes.push(Mesh {
        name: "m".into(),
        primitives: prims,
    });
    s.instances.push(Instance {
        mesh: 0,
        transform: Mat4::IDENTITY,
        name: "i".into(),
        visible: true,
    });
    s
}

/// A 200 x 200 floor at z = 0.
pub fn floor() -> Primitive {
    quad(Vec3::ZERO, Vec3::X * 100.0, Vec3::Y * 100.0)
}

pub fn top_down_camera(height: f32, w: u32, h: u32) -> Camera {
    Camera::perspective([0.0, 0.0, height], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 60.0, (w, h))
}

pub fn rtao(rays: u32, radius: f32) -> AoSettings {
    let mut s = hrtao(rays, radius);
    s.display.mode = Mode::Rtao;
    s
}

/// A renderer and the frame description a test keeps from frame to frame, as a viewer would: the settings, the
/// render size (the camera's size is replaced by it), tile, jitter, view height and budget. Everything else of
/// the renderer is reached through `Deref`.
#[allow(dead_code)]
pub struct Headless {
    pub r: Renderer,
    pub settings: AoSettings,
    pub size: (u32, u32),
    pub jitter: bool,
    pub tile: Option<hrtao_core::tile::Tile>,
    pub view_height: u32,
    pub budget: Option<RayBudget>,
    pub output: Output,
    /// Slices: each frame draws every `lattice`-th pixel (`FrameDesc::lattice`).
    pub lattice: u32,
    /// Simulated frames per second: frame n starts at n / fps seconds (`FrameDesc::at`); None: the renderer's
    /// clock.
    pub fps: Option<f64>,
}

#[allow(dead_code)]
impl Headless {
    pub fn new(
        gpu: &Arc<Gpu>,
        width: u32,
        height: u32,
        settings: AoSettings,
    ) -> hrtao_core::Result<Headless> {
        settings.validate().map_err(hrtao_core::CoreError::Invalid)?;
        Ok(Headless {
            r: Renderer::new(gpu)?,
            settings,
            size: (width.max(1), height.max(1)),
            jitter: false,
            tile: None,
            view_height: 0,
            budget: None,
            output: Output::default(),
            lattice: 1,
            fps: None,
        })
    }

    pub fn set_settings(&mut self, settings: AoSettings) -> hrtao_core::Result<()> {
        settings.validate().map_err(hrtao_core::CoreError::Invalid)?;
        self.settings = settings;
        Ok(())
    }

    pub fn resize(&mut self, width: u32, height: u32) {
        self.size = (width.max(1), height.max(1));
    }

    pub fn set_primary(&mut self, primary: hrtao_core::Primary) {
        self.r.set_primary(primary);
    }

    /// The frame of `cam` (at this renderer's size) of `scene` at F = `scene_f` with `settings`.
    pub fn frame_with<'a>(
        &self,
        scene: &'a SceneGpu,
        scene_f: u32,
        cam: &Camera,
        settings: &'a AoSettings,
    ) -> FrameDesc<'a> {
        let camera = Camera {
            width: self.size.0,
            height: self.size.1,
            ..*cam
        };
        let frame = FrameDesc {
            view_height: self.view_height,
            budget: self.budget,
            tile: self.tile,
            jitter: self.jitter,
            output: self.output,
            lattice: self.lattice,
            ..FrameDesc::new(scene, scene_f, camera, settings)
        };
        match self.fps {
            Some(fps) => frame.at(std::time::Duration::from_secs_f64(
                self.r.frame_index() as f64 / fps,
            )),
            None => frame,
        }
    }

    pub fn render(
        &mut self,
        scene: &SceneGpu,
        scene_f: u32,
        cam: &Camera,
    ) -> hrtao_core::Result<FrameReport> {
        let settings = self.settings.clone();
        let frame = self.frame_with(scene, scene_f, cam, &settings);
        self.r.render(&frame)
    }

    pub fn pick_primary(
        &mut self,
        scene: &SceneGpu,
        scene_f: u32,
        cam: &Camera,
    ) -> hrtao_core::Result<(hrtao_core::Primary, f64, f64)> {
        let settings = self.settings.clone();
        let frame = self.frame_with(scene, scene_f, cam, &settings);
        self.r.pick_primary(&frame)
    }

    pub fn shows_final(&self, scene: &SceneGpu, scene_f: u32, cam: &Camera) -> bool {
        self.r
            .shows_final(&self.frame_with(scene, scene_f, cam, &self.settings))
    }

    pub fn pixel_cell_keys(
        &self,
        scene: &SceneGpu,
        cam: &Camera,
        scene_f: u32,
        px: &hrtao_core::gpu::GPixel,
    ) -> [hrtao_core::hash::CellKey; 4] {
        self.r
            .pixel_cell_keys(&self.frame_with(scene, scene_f, cam, &self.settings), px)
    }

    pub fn hash_on_gpu(
        &mut self,
        scene: &SceneGpu,
        cases: &[hrtao_core::gpu::HashTestCase],
    ) -> hrtao_core::Result<Vec<hrtao_core::gpu::HashTestCase>> {
        let settings = self.settings.clone();
        self.r.hash_on_gpu(scene, &settings, cases)
    }
}

impl std::ops::Deref for Headless {
    type Target = Renderer;
    fn deref(&self) -> &Renderer {
        &self.r
    }
}

impl std::ops::DerefMut for Headless {
    fn deref_mut(&mut self) -> &mut Renderer {
        &mut self.r
    }
}

/// Renders `frames` frames and returns the renderer (for read-backs).
pub fn render(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    cam: &Camera,
    settings: AoSettings,
    frames: u32,
) -> (Headless, SceneGpu) {
    let sg = SceneGpu::new(gpu, scene).expect("scene upload");
    let mut r = Headless::new(gpu, cam.width, cam.height, settings).expect("renderer");
    for _ in 0..frames {
        r.render(&sg, scene.f(), cam).expect("frame");
    }
    (r, sg)
}

/// A file of the repository's test data (`testdata/` at the repository root).
pub fn testdata(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(rel)
}

/// The test scenes with Cycles references (`testdata/refs/index.json`): the cycloidal gearbox (the bundled scene,
/// `assets/default.glb`) and the rod assembly, both MIT.
pub const REFERENCE_SCENES: [&str; 2] = ["cycloidal", "rod"];

/// A reference scene by its key in `testdata/refs/index.json` ("cycloidal" or "rod"), with its reference camera
/// for `w`×`h` (160×90, 320×180 or 640×360) and its AO radius.
pub fn shared_scene(key: &str, w: u32, h: u32) -> (Scene, Camera, f32) {
    assert!(
        REFERENCE_SCENES.contains(&key),
        "no test scene {key:?}: the repository's test data holds {REFERENCE_SCENES:?}"
    );
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(testdata("refs/index.json")).unwrap()).unwrap();
    let entry = &index[key];
    let scene = hrtao_scene::load(
        testdata(entry["scene"].as_str().unwrap()).to_str().unwrap(),
        &mut |_| {},
    )
    .unwrap();
    let cam = Camera::load(&testdata(&format!("refs/{key}_{w}x{h}.camera.json"))).unwrap();
    (scene, cam, entry["radius"].as_f64().unwrap() as f32)
}

/// A scene and its camera on a device: the device, the scene, the camera and the scene's acceleration structures
/// (dropped before the device).
pub fn on_gpu((scene, cam): (Scene, Camera)) -> (Arc<Gpu>, Scene, Camera, SceneGpu) {
    let gpu = gpu();
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    (gpu, scene, cam, sg)
}

/// `shared_scene(key, w, h)` on a device: the device, the scene, its camera and AO radius, and the scene's
/// acceleration structures (dropped before the device).
pub fn shared_scene_gpu(key: &str, w: u32, h: u32) -> (Arc<Gpu>, Scene, Camera, f32, SceneGpu) {
    let gpu = gpu();
    let (scene, cam, radius) = shared_scene(key, w, h);
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    (gpu, scene, cam, radius, sg)
}

/// The Blender Cycles AO reference of a view (`testdata/refs/KEY_WxH.cycles.exr`, R = G = B = AO, row 0 at the
/// top), checked for its size.
pub fn cycles_ref(key: &str, w: u32, h: u32) -> Vec<f32> {
    let path = testdata(&format!("refs/{key}_{w}x{h}.cycles.exr"));
    let (rw, rh, ao) =
        hrtao_core::imageio::read_ao(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!((rw, rh), (w, h), "reference size");
    assert!(ao.iter().all(|v| (0.0..=1.0).contains(v)), "AO in [0, 1]");
    ao
}

/// One frame from an empty map at 8 rays per pixel on a reference view: the AO with `hrtao(8, R)` changed by each
/// of `variants` (settings overrides as JSON, `AoSettings::with_overrides`) over one scene upload, the view's
/// G-buffer and its Cycles reference.
#[allow(dead_code)]
pub struct FirstFrames {
    pub ao: Vec<Vec<f32>>,
    pub gbuffer: Vec<hrtao_core::gpu::GPixel>,
    pub cycles: Vec<f32>,
}

#[allow(dead_code)]
pub fn first_frames(key: &str, w: u32, h: u32, variants: &[&str]) -> FirstFrames {
    let gpu = gpu();
    let (scene, cam, radius) = shared_scene(key, w, h);
    let sg = SceneGpu::new(&gpu, &scene).expect("scene upload");
    let mut gbuffer = Vec::new();
    let ao = variants
        .iter()
        .map(|variant| {
            let settings = hrtao(8, radius)
                .with_overrides(variant)
                .expect("settings overrides");
            let mut r = Headless::new(&gpu, cam.width, cam.height, settings).expect("renderer");
            r.render(&sg, scene.f(), &cam).expect("frame");
            gbuffer = r.read_gbuffer().unwrap();
            r.read_ao().unwrap()
        })
        .collect();
    assert_clean(&gpu);
    FirstFrames {
        ao,
        gbuffer,
        cycles: cycles_ref(key, w, h),
    }
}

/// `first_frames`' MAE against Cycles, one per variant.
#[allow(dead_code)]
pub fn first_frame_errors(key: &str, w: u32, h: u32, variants: &[&str]) -> Vec<f32> {
    let f = first_frames(key, w, h, variants);
    f.ao.iter().map(|a| mae(a, &f.cycles)).collect()
}

/// Mean absolute error over pixels not open (AO < 0.999) in both images.
pub fn mae(a: &[f32], b: &[f32]) -> f32 {
    hrtao_core::metrics::ao_error(a, b).mae as f32
}

/// A converged per-pixel RTAO reference of the scene (rays x frames samples per pixel).
pub fn reference(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    cam: &Camera,
    radius: f32,
    rays: u32,
    frames: u32,
) -> Vec<f32> {
    let (r, _sg) = render(gpu, scene, cam, rtao(rays, radius), frames);
    r.read_ao().unwrap()
}

pub fn hrtao(rays: u32, radius: f32) -> AoSettings {
    let mut s = AoSettings::default().with_radius(radius);
    s.map.rays_per_pixel = rays;
    s
}

/// What `check_map` found: cells stamped in the last frame and pixels whose keys were checked.
#[derive(Debug, Default)]
pub struct MapCheck {
    pub live_cells: usize,
    pub checked_pixels: usize,
}

/// Checks the hash map after the last frame rendered by `r` with `cam` and F = `scene_f`, against the CPU
/// mirror of the hash (not against what holds by construction):
/// - every cell a pixel uses holds that pixel's key (CPU `cell_key`, the current F), was stamped this frame and
///   lies within its home slot's probe run (what the resolve's lookups scan);
/// - no key is held twice within its probe run (no duplicates);
/// - counters stay within their bounds (target cells at most max_samples + one frame's claims, every cell at
///   most SAMPLE_CAP + one frame's rays, unoccluded <= samples);
/// - if `before` (the map before the frame) is given: no cell used this frame lost samples (a reset of a live
///   cell), unless its key changed.
pub fn check_map(
    r: &Headless,
    sg: &SceneGpu,
    cam: &Camera,
    scene_f: u32,
    before: Option<&[hrtao_core::gpu::HashCell]>,
) -> MapCheck {
    use hrtao_core::gpu;
    let cells = r.read_hash_cells().unwrap();
    let gbuf = r.read_gbuffer().unwrap();
    let pcs = r.read_pixel_cells().unwrap();
    let now = r.frame_index().wrapping_sub(1);
    let s = &r.settings.map;
    let slack = (gbuf.len() as u32) * s.rays_per_pixel;
    let mut used = std::collections::HashSet::new();
    let mut out = MapCheck::default();
    for (px, pc) in gbuf.iter().zip(&pcs) {
        if px.t < 0.0 {
            continue;
        }
        let keys = r.pixel_cell_keys(sg, cam, scene_f, px);
        for (level, &c) in pc.cells.iter().enumerate() {
            if c == gpu::INVALID_CELL {
                continue;
            }
            let cell = &cells[c as usize];
            assert_eq!(
                cell.checksum(),
                keys[level].checksum,
                "pixel cell {c} at level {level} holds another key"
            );
            let dist = c.wrapping_sub(keys[level].slot) & (s.hash_capacity - 1);
            assert!(
                dist < hrtao_core::settings::MAX_PROBE,
                "cell {c} lies {dist} slots from its key's home"
            );
            // The home slot bounds the lookups of its keys (`HashCell::probe_run`, find_cell): a key beyond
            // it would be missed by the resolve.
            let run = cells[keys[level].slot as usize].probe_run;
            assert!(
                dist < run,
                "cell {c} lies {dist} slots from its key's home {}, whose probe run is {run}",
                keys[level].slot
            );
            assert_eq!(cell.last_frame(), now, "a cell used this frame was not stamped");
            used.insert(c);
        }
        out.checked_pixels += 1;
    }
    // Duplicates: a cell stamped this frame and another slot of its probe window holding the same checksum
    // that is still live (used within the cache lifetime, `lifetime_frames` of the last frame; the checksum
    // includes F, so both are of the current F):
    // the second copy's samples would be orphaned.
    let cap = s.hash_capacity as usize;
    for (i, a) in cells.iter().enumerate() {
        if a.checksum() == gpu::EMPTY_CELL {
            continue;
        }
        assert!(
            a.unoccluded <= a.samples,
            "cell {i}: {} unoccluded of {} samples",
            a.unoccluded,
            a.samples
        );
        // Near-field control variate: the classified rays are some of the cell's, and those open within r_n
        // some of them; a cell whose every ray was classified has no more open rays than open within r_n <= R.
        assert!(
            a.near_open <= a.near_traced && a.near_traced <= a.samples,
            "cell {i}: {} open within r_n of {} classified, {} samples",
            a.near_open,
            a.near_traced,
            a.samples
        );
        if a.near_traced == a.samples {
            assert!(
                a.unoccluded <= a.near_open,
                "cell {i}: {} unoccluded, {} open within r_n",
                a.unoccluded,
                a.near_open
            );
        }
        assert!(
            a.samples <= gpu::SAMPLE_CAP + slack,
            "cell {i}: {} samples",
            a.samples
        );
        // Claims stop at max_samples: one frame's blocks (at most 4 budgets per pixel with adaptive sampling)
        // may pass it.
        assert!(
            a.qmc_index <= s.max_samples + 4 * slack,
            "cell {i}: QMC index {} past max_samples {}",
            a.qmc_index,
            s.max_samples
        );
        if a.last_frame() != now {
            continue;
        }
        out.live_cells += 1;
        for d in 1..hrtao_core::settings::MAX_PROBE as usize {
            for j in [(i + d) % cap, (i + cap - d) % cap] {
                let b = &cells[j];
                let live = now.wrapping_sub(b.last_frame()) <= r.lifetime_frames();
                assert!(
                    !(b.checksum() == a.checksum() && live),
                    "key {:#x} held twice, in slots {i} and {j}",
                    a.checksum()
                );
            }
        }
        // (Before a renderer's first frame there is no map: nothing to compare with.)
        if let Some(old) = before.and_then(|b| b.get(i)) {
            if old.checksum() == a.checksum() {
                assert!(
                    a.samples >= old.samples,
                    "live cell {i} was reset: {} -> {} samples",
                    old.samples,
                    a.samples
                );
            }
        }
    }
    out.live_cells = out.live_cells.max(used.len());
    out
}

/// A perspective camera with z up and a 50° vertical field of view, `width`×`height` pixels.
pub fn z_up_camera(eye: [f32; 3], target: [f32; 3], width: u32, height: u32) -> Camera {
    z_up_camera_fov(eye, target, 50.0, (width, height))
}

/// A perspective camera with z up and a vertical field of view of `fov_y_deg`, `width`×`height` pixels.
pub fn z_up_camera_fov(
    eye: [f32; 3],
    target: [f32; 3],
    fov_y_deg: f32,
    (width, height): (u32, u32),
) -> Camera {
    Camera::perspective(eye, target, [0.0, 0.0, 1.0], fov_y_deg, (width, height))
}

/// The bundled scene (`assets/default.glb`) and its camera (`assets/default.camera.json`) at `w` x `h`.
pub fn bundled(w: u32, h: u32) -> (Scene, Camera) {
    let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let scene = hrtao_scene::load(assets.join("default.glb").to_str().unwrap(), &mut |_| {}).unwrap();
    let cam = Camera {
        width: w,
        height: h,
        ..Camera::load(&assets.join("default.camera.json")).unwrap()
    };
    (scene, cam)
}

/// The pass-image sequence on `cam`: frames 1 to 3 still, then two of a small orbit (a new view each: navigation
/// over a settled map), each tracing rays; `after` sees each frame's renderer (frame index from 0). The AO of
/// frames 1, 3 and 5.
pub fn five_frames(
    r: &mut Headless,
    sg: &SceneGpu,
    scene: &Scene,
    cam: &Camera,
    mut after: impl FnMut(u32, &mut Headless),
) -> Vec<Vec<f32>> {
    let mut out = Vec::new();
    for i in 0..5u32 {
        let mut c = *cam;
        if i >= 3 {
            c.eye[0] += 0.5 * (i - 2) as f32;
        }
        let report = r.render(sg, scene.f(), &c).unwrap();
        assert!(report.rays > 0, "frame {i} traced rays");
        after(i, r);
        if matches!(i, 0 | 2 | 4) {
            out.push(r.read_ao().unwrap());
        }
    }
    out
}

/// Surface pixels of the floor (instance 0) next to where block `part` stood: within `ring` of its old box,
/// outside it (its contact shadow).
#[allow(dead_code)]
pub fn ring_pixels(r: &Headless, bounds: hrtao_scene::Aabb, ring: f32) -> Vec<usize> {
    let gbuf = r.read_gbuffer().unwrap();
    (0..gbuf.len())
        .filter(|&i| {
            let p = &gbuf[i];
            let d = (bounds.min - Vec3::from(p.position))
                .max(Vec3::from(p.position) - bounds.max)
                .max(Vec3::ZERO)
                .length();
            p.t >= 0.0 && p.instance == 0 && d > 0.0 && d <= ring
        })
        .collect()
}

/// The mean of `img` over the pixels `px`.
#[allow(dead_code)]
pub fn mean_at(img: &[f32], px: &[usize]) -> f32 {
    px.iter().map(|&i| img[i]).sum::<f32>() / px.len().max(1) as f32
}

/// Hides instance `part` of `scene` (a local edit; `sg` follows): the floor pixels around where it stood in `r`'s
/// last frame (`ring_pixels`, 0.6 wide) and their mean AO before the edit.
pub fn remove_part(r: &Headless, scene: &mut Scene, sg: &mut SceneGpu, part: u32) -> (Vec<usize>, f32) {
    let ring = ring_pixels(r, scene.instance_bounds(part), 0.6);
    let with_part = mean_at(&r.read_ao().unwrap(), &ring);
    scene.set_visible(part, false).unwrap();
    sg.update_instances(scene, u32::MAX).unwrap();
    (ring, with_part)
}

/// The mean AO over the pixels `px` of `r`'s last frame, and of a fresh render of `scene` (`frames` frames of
/// `settings`): after an edit, what the edited scene shows against what it shows from scratch.
pub fn mean_against_fresh(
    r: &Headless,
    gpu: &Arc<Gpu>,
    (scene, cam): (&Scene, &Camera),
    (settings, frames): (AoSettings, u32),
    px: &[usize],
) -> (f32, f32) {
    let after = mean_at(&r.read_ao().unwrap(), px);
    let (fresh, _sg) = render(gpu, scene, cam, settings, frames);
    (after, mean_at(&fresh.read_ao().unwrap(), px))
}

/// Prints the mean AO of the `ring` floor pixels by a removed block: `with_part` before the removal, `after` it
/// (`when`), `expected` of a fresh render without the block; asserts there are more than `min_pixels` of them
/// and the block cast a contact shadow there (`with_part` at least 0.1 darker than `expected`).
pub fn check_contact_shadow(
    ring: usize,
    (with_part, after, expected): (f32, f32, f32),
    when: &str,
    min_pixels: usize,
) {
    eprintln!(
        "{ring} floor pixels by the removed block: AO {with_part:.3} with it, {after:.3} {when}, {expected:.3} fresh"
    );
    assert!(ring > min_pixels, "{ring}");
    assert!(with_part < expected - 0.1, "the block cast a contact shadow");
}

/// AO on a floor at distance `d` from an infinite wall rising from it (a 90° wedge), radius `r`:
/// cosine-weighted directions project uniformly on the unit disk, and those with x <= -d/r hit the wall,
/// so the occluded fraction is a circular segment: (acos(a) - a sqrt(1 - a^2)) / pi with a = d/r.
pub fn wedge_ao(d: f32, r: f32) -> f32 {
    let a = (d / r).clamp(0.0, 1.0);
    1.0 - (a.acos() - a * (1.0 - a * a).sqrt()) / std::f32::consts::PI
}

/// Floor z = 0 and a wall x = 0 (facing +x), both far larger than any AO radius used here.
pub fn wedge() -> Scene {
    let wall = quad(Vec3::new(0.0, 0.0, 50.0), Vec3::Y * 100.0, Vec3::Z * 50.0);
    scene_of(vec![floor(), wall])
}

/// A 160×90 view of the wedge from `eye` toward `target`, z up.
pub fn wedge_camera(eye: [f32; 3], target: [f32; 3]) -> hrtao_core::Camera {
    z_up_camera(eye, target, 160, 90)
}

/// Mean |AO - analytic| over the wedge's floor pixels at `lo <= x < hi` from the wall (AO radius `radius`), and
/// how many there are.
pub fn wedge_floor_error(
    ao: &[f32],
    gb: &[hrtao_core::gpu::GPixel],
    radius: f32,
    lo: f32,
    hi: f32,
) -> (f32, usize) {
    let (mut sum, mut n) = (0.0f32, 0usize);
    for (p, a) in gb.iter().zip(ao) {
        let x = p.position[0];
        if p.t > 0.0 && p.normal[2] > 0.99 && x >= lo && x < hi {
            sum += (a - wedge_ao(x, radius)).abs();
            n += 1;
        }
    }
    (sum / n.max(1) as f32, n)
}
