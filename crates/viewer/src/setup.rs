//! From a command's arguments to a scene on the device: the one place for the rules `view`, `render` and `bench`
//! share (which camera, which up axis, which AO radius, which sections, whether an empty scene is an error, and
//! how primary visibility is found). Each command turns its arguments into [`SetupInputs`]; [`prepare`] applies
//! the rules to the loaded scene without the device; [`Device::open`] and [`Device::install`] build the scene's
//! acceleration structures and the renderer. Before this module the three commands each had their own copy, and
//! the copies disagreed (a `NAME.camera.json` beside a model was used by the viewer only, `gen:` scenes stood on
//! z in `bench` but on y in `render`).
//!
//! The rules, in the order [`prepare`] applies them:
//! - **Empty scene**: an error naming the file, in every command (nothing to frame, nothing to measure; a scene
//!   whose instances are all hidden later on, by an edit, still renders its background).
//! - **Camera**: `--camera FILE`; else `NAME.camera.json` beside the model when it exists (a CAD user saves the
//!   view beside the model and expects every command to open on it; the bundled gearbox has its camera there
//!   too); else an automatic camera (`--auto-camera` of `bench`, else fitted to the bounds). An explicit
//!   `bench --auto-camera` asks for the automatic camera, so it wins over the file beside the model. The file's
//!   camera is used as saved: `--up` never turns it.
//! - **Up axis** (the world's: the automatic camera's, and the axis the viewer orbits about, walks on and sets
//!   the sky's zenith by): `--up` (the viewer passes the axis the user chose in the panel for that file here
//!   too); else the up of the camera file in use; else z for the bundled scene and `gen:` specs (both are
//!   modelled z-up); else the one the format implies (`Scene::up`: IFC and 3MF z, glTF y); else y (most
//!   exporters').
//! - **Image size**: `--width`/`--height` of `render` and `bench`; else the camera file's; else the command's
//!   own size for an automatic camera ([`SetupInputs::fit_size`]; the viewer adapts the camera to its window).
//! - **AO radius**: `--radius`; else [`BUNDLED_RADIUS`] for the bundled scene (millimetres; 5 % of its diagonal
//!   would be 3× as wide); else 5 % of the bounds' diagonal ([`default_radius`]).
//! - **Sections**: `--section`, given in the file's coordinates, moved into the scene's.
//! - **Primary visibility** ([`Device::install`]): `--primary`, by default measured
//!   (`Renderer::pick_primary`: the faster of ray queries and rasterisation for this scene on this device, on
//!   the first frame's camera), except that a command whose results are per-pass GPU times (`bench`:
//!   [`SetupInputs::pass_times`]) keeps ray queries where the device cannot time rasterised frames (lavapipe
//!   writes the timestamps after a render pass only at the end of the submission: such frames report no pass
//!   times, `Renderer::timestamps_measure`). Every renderer of a command gets the same choice, so `bench`'s
//!   modes differ in their AO only.
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{anyhow, bail, Context, Result};
use hrtao_core::camera::UpAxis;
use hrtao_core::raster::{Primary, Rasterizer};
use hrtao_core::{AoSettings, Camera, FrameDesc, Gpu, Renderer, SceneGpu, Sections};
use hrtao_scene::Scene;

use crate::cli::{AutoCamera, BenchArgs, DeviceArgs, PrimaryChoice, RenderArgs, SectionArgs, ViewArgs};

/// The AO radius of the bundled gearbox (millimetres; 5 % of its diagonal would be 3× as wide).
pub const BUNDLED_RADIUS: f32 = 8.0;

/// Field of view of an automatic camera, in degrees.
const FIT_FOV_DEG: f32 = 40.0;

/// What a command asks for, before the scene is loaded: its arguments that choose the scene, the camera, the up
/// axis, the AO radius, the sections and the primary visibility. `Default` is the bundled scene with nothing
/// forced, at the viewer's size (what the viewer asks for a file opened from its window:
/// `SetupInputs { spec: Some(path), up, ..Default::default() }`).
#[derive(Clone, Debug)]
pub struct SetupInputs {
    /// The model (path or `gen:` spec); `None`: the bundled scene.
    pub spec: Option<String>,
    /// `--camera`.
    pub camera: Option<PathBuf>,
    /// `bench --auto-camera`, when given.
    pub auto_camera: Option<AutoCamera>,
    /// `--up`.
    pub up: Option<UpAxis>,
    /// `--radius`.
    pub radius: Option<f32>,
    /// `--width`, `--height`: the image size, over the camera's.
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// The command's image size for an automatic camera.
    pub fit_size: (u32, u32),
    /// `--section`.
    pub sections: SectionArgs,
    /// `--primary`.
    pub primary: PrimaryChoice,
    /// The command's results are per-pass GPU times (`bench`): a measured primary visibility is one whose frames
    /// the device times.
    pub pass_times: bool,
}

impl Default for SetupInputs {
    fn default() -> SetupInputs {
        SetupInputs {
            spec: None,
            camera: None,
            auto_camera: None,
            up: None,
            radius: None,
            width: None,
            height: None,
            fit_size: (640, 360),
            sections: SectionArgs::default(),
            primary: PrimaryChoice::Auto,
            pass_times: false,
        }
    }
}

impl SetupInputs {
    /// `hrtao [view] [FILE]`: the viewer's first scene (it sizes the camera to its window itself).
    pub fn from_view(args: &ViewArgs) -> SetupInputs {
        SetupInputs {
            spec: args.file.clone(),
            camera: args.setup.camera.clone(),
            up: args.setup.up,
            radius: args.radius,
            sections: args.sections.clone(),
            primary: args.setup.primary,
            ..Default::default()
        }
    }

    /// `hrtao render`.
    pub fn from_render(args: &RenderArgs) -> SetupInputs {
        SetupInputs {
            spec: args.scene.clone(),
            camera: args.setup.camera.clone(),
            up: args.setup.up,
            radius: args.ao.radius,
            width: args.width,
            height: args.height,
            sections: args.sections.clone(),
            primary: args.setup.primary,
            ..Default::default()
        }
    }

    /// `hrtao bench` (its automatic camera is 320×180, the size of its figures).
    pub fn from_bench(args: &BenchArgs) -> SetupInputs {
        SetupInputs {
            spec: args.scene.clone(),
            camera: args.setup.camera.clone(),
            auto_camera: args.auto_camera,
            up: args.setup.up,
            radius: args.ao.radius,
            width: args.width,
            height: args.height,
            fit_size: (320, 180),
            sections: args.sections.clone(),
            primary: args.setup.primary,
            pass_times: true,
        }
    }

    /// The viewer's inputs for the scene `spec` it opens now: the command line's camera, radius and sections
    /// are the first scene's; its up axis and primary visibility hold for every scene (`self` keeps those for
    /// the next). The up axis the user chose for this file in the panel (`remembered`) applies unless `--up`
    /// says otherwise.
    pub fn for_next_scene(&mut self, spec: &str, remembered: Option<UpAxis>) -> SetupInputs {
        let later = SetupInputs {
            up: self.up,
            primary: self.primary,
            ..Default::default()
        };
        let mut inputs = SetupInputs {
            spec: Some(spec.to_string()),
            ..std::mem::replace(self, later)
        };
        inputs.up = inputs.up.or(remembered);
        inputs
    }

    /// What to load: the spec, or the bundled scene's file.
    pub fn load_spec(&self) -> String {
        match &self.spec {
            Some(s) => s.clone(),
            None => crate::common::default_scene_path().display().to_string(),
        }
    }

    /// Whether the scene is the bundled gearbox: no spec, or a path to the bundled scene's file (the viewer
    /// opens it by path).
    pub fn is_bundled(&self) -> bool {
        is_bundled(self.spec.as_deref())
    }
}

/// The viewer's preferences as its command line overrides them: `--mode`, `--rays-per-frame` (a fixed budget),
/// `--no-auto-budget`, and the tessellation and smoothing flags, which become the panel's load options.
pub(crate) fn view_prefs(args: &ViewArgs, prefs: &mut crate::view::prefs::Prefs) {
    use crate::view::{load_options, pacer};
    if let Some(m) = args.mode {
        prefs.settings.display.mode = m;
    }
    if let Some(r) = args.rays_per_frame {
        prefs.rays_per_frame = r.clamp(pacer::MIN_RAYS_PER_FRAME, pacer::MAX_RAYS_PER_FRAME);
        prefs.auto_budget = false;
    }
    if args.no_auto_budget {
        prefs.auto_budget = false;
    }
    if let Some(t) = hrtao_scene::command_line_cad_tessellation() {
        prefs.cad_load = load_options::CadLoadOptions::from_tessellation(t);
    }
    if let Some(c) = hrtao_scene::normals::command_line_crease_deg() {
        prefs.mesh_load = load_options::MeshLoadOptions::from_crease(c);
    }
}

/// Whether `spec` names the bundled scene: `None` (no model given), or the bundled scene's file
/// (`common::default_scene_path`, compared canonically).
pub(crate) fn is_bundled(spec: Option<&str>) -> bool {
    let Some(spec) = spec else {
        return true;
    };
    if spec.starts_with("gen:") {
        return false;
    }
    let canonical = |p: &Path| std::fs::canonicalize(p).ok();
    canonical(Path::new(spec)).is_some_and(|p| Some(p) == canonical(&crate::common::default_scene_path()))
}

/// `NAME.camera.json` beside the model file `spec` (none for a `gen:` spec).
pub(crate) fn camera_beside(spec: &str) -> Option<PathBuf> {
    if spec.starts_with("gen:") {
        return None;
    }
    Some(Path::new(spec).with_extension("camera.json"))
}

/// The AO radius when none is given: [`BUNDLED_RADIUS`] for the bundled scene, else 5 % of the bounds'
/// diagonal (at least 1e-6; 5 % of 1 for an empty or non-finite box).
pub fn default_radius(bundled: bool, scene: &Scene) -> f32 {
    if bundled {
        return BUNDLED_RADIUS;
    }
    let diagonal = scene.bounds().diagonal().length();
    let diagonal = if diagonal.is_finite() && diagonal > 0.0 {
        diagonal
    } else {
        1.0
    };
    (diagonal * 0.05).max(1e-6)
}

/// Metres per scene unit: millimetres for the bundled gearbox (a CAD export whose glTF says metres), else the
/// file's unit (STEP, IGES, IFC), else metres.
pub fn metres_per_unit(scene: &Scene, bundled: bool) -> f32 {
    if bundled {
        return 1e-3;
    }
    scene.unit_m.filter(|u| u.is_finite() && *u > 0.0).unwrap_or(1.0) as f32
}

/// The world up axis a camera implies: the signed axis its up vector leans to most.
pub fn up_axis_of(camera: &Camera) -> UpAxis {
    UpAxis::nearest(hrtao_scene::glam::Vec3::from(camera.up))
}

/// What [`prepare`] decided for a loaded scene.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The first camera, in the scene's coordinates, at the command's image size.
    pub camera: Camera,
    /// The camera file it came from (`--camera` or the one beside the model); `None`: an automatic camera.
    pub camera_file: Option<PathBuf>,
    /// The world up axis.
    pub up: UpAxis,
    /// The radius when none is given (the viewer's panel resets to it).
    pub default_radius: f32,
    /// The AO radius: `--radius`, else `default_radius`.
    pub radius: f32,
    /// The section planes, in the scene's coordinates.
    pub sections: Sections,
    /// The scene is the bundled gearbox (a CAD export in millimetres although its glTF says metres).
    pub bundled: bool,
    /// How primary visibility is to be found (`--primary`, and whether its frames must be timed:
    /// [`Device::install`] applies it).
    pub primary: PrimaryChoice,
    pub pass_times: bool,
}

/// Applies the rules of this module (see its documentation) to `scene`, loaded from `inputs`. No device.
pub fn prepare(inputs: &SetupInputs, scene: &Scene) -> Result<Prepared> {
    let spec = inputs.load_spec();
    let bounds = scene.bounds();
    if bounds.is_empty() {
        bail!("scene `{spec}` has no visible geometry");
    }
    for w in &scene.warnings {
        log::warn!("{spec}: {w}");
    }
    let bundled = inputs.is_bundled();
    let camera_file = match (&inputs.camera, inputs.auto_camera) {
        (Some(p), _) => Some(p.clone()),
        (None, Some(_)) => None,
        (None, None) => camera_beside(&spec).filter(|p| p.is_file()),
    };
    let file_camera = camera_file
        .as_ref()
        .map(|p| Camera::load_in(p, scene.origin).with_context(|| format!("camera {}", p.display())))
        .transpose()?;
    // The bundled gearbox is a Z-up CAD export in a glTF (which says Y up); generated scenes are Z up; else the
    // format's (IFC and 3MF Z, glTF Y), else Y.
    let default_up = if bundled || spec.starts_with("gen:") {
        UpAxis::Z
    } else {
        scene.up.unwrap_or(UpAxis::Y)
    };
    let up = inputs
        .up
        .or(file_camera.as_ref().map(up_axis_of))
        .unwrap_or(default_up);
    let (w, h) = inputs.fit_size;
    let mut camera = match file_camera {
        Some(c) => c,
        None => match inputs.auto_camera.unwrap_or(AutoCamera::Fit) {
            AutoCamera::Fit => Camera::fit(bounds.min, bounds.max, up, FIT_FOV_DEG, w, h),
            AutoCamera::Corner => Camera {
                width: w,
                height: h,
                ..corner_camera(bounds.min, bounds.max, up)
            },
        },
    };
    if let Some(w) = inputs.width {
        camera.width = w;
    }
    if let Some(h) = inputs.height {
        camera.height = h;
    }
    camera.validate().map_err(|e| anyhow!("camera: {e}"))?;
    let default_radius = default_radius(bundled, scene);
    let sections = inputs.sections.sections(scene).map_err(|e| anyhow!(e))?;
    Ok(Prepared {
        camera,
        camera_file,
        up,
        default_radius,
        radius: inputs.radius.unwrap_or(default_radius),
        sections,
        bundled,
        primary: inputs.primary,
        pass_times: inputs.pass_times,
    })
}

impl Prepared {
    /// The viewer's first camera for its 3D view of `view_aspect` (width / height; None: not laid out): oriented
    /// with a true up vector (the viewer's navigation keeps it orthogonal), and a camera file framed for a wider
    /// image backed off so that the view shows the same horizontal extent.
    pub fn view_camera(&self, view_aspect: Option<f32>) -> Camera {
        use crate::view::nav;
        let p = &self.camera;
        let mut cam = nav::orbit(p, nav::target(p), self.up.vector(), 0.0, 0.0);
        let file_aspect = cam.width as f32 / cam.height.max(1) as f32;
        match view_aspect {
            Some(view_aspect) if self.camera_file.is_some() && view_aspect < file_aspect => {
                let widen = file_aspect / view_aspect;
                if cam.is_orthographic() {
                    cam.ortho_height *= widen;
                } else {
                    let t = nav::target(&cam);
                    cam.eye = (t + (nav::eye(&cam) - t) * widen).to_array();
                }
            }
            _ => {}
        }
        cam
    }

    /// The unit the viewer measures in: STEP and IGES declare their length unit; the bundled gearbox is a CAD
    /// export in millimetres (its glTF says metres).
    pub fn unit(&self, scene: &Scene) -> Option<crate::view::measure::Unit> {
        use crate::view::measure::Unit;
        if self.bundled {
            Some(Unit::Mm)
        } else {
            scene.unit_m.and_then(Unit::from_metres)
        }
    }
}

/// `bench --auto-camera corner`: a camera at the `min` corner of the box (outside it by 2 % of the diagonal), at
/// 80 % of its height, looking at the middle of the far half.
pub fn corner_camera(min: hrtao_scene::glam::Vec3, max: hrtao_scene::glam::Vec3, up: UpAxis) -> Camera {
    let upv = up.vector();
    let d = max - min;
    let along = d - upv * d.dot(upv);
    let base_min = min - upv * min.dot(upv);
    let h = |f: f32| upv * (min.dot(upv) + f * d.dot(upv));
    let eye = base_min - along.normalize_or_zero() * d.length() * 0.02 + h(0.8);
    let target = base_min + along * 0.6 + h(0.3);
    Camera {
        eye: eye.to_array(),
        target: target.to_array(),
        up: upv.to_array(),
        fov_y_deg: 50.0,
        width: 320,
        height: 180,
        ..Default::default()
    }
}

/// The device and a renderer with its pipelines: what a command can make before its scene is loaded (`render`
/// makes it on a thread while the scene loads).
pub struct Device {
    pub gpu: Arc<Gpu>,
    pub renderer: Renderer,
    /// Device bytes the renderer allocated when it was made (`bench` reports the scene's bytes without them).
    renderer_bytes: u64,
}

/// A scene on the device, ready to render.
pub struct Installed {
    pub gpu: Arc<Gpu>,
    pub scene_gpu: SceneGpu,
    pub renderer: Renderer,
    /// The primary visibility every renderer of the command uses.
    pub primary: Primary,
    /// Device bytes once the scene was built, before any frame: all but the renderer's, and all.
    pub scene_device_bytes: u64,
    pub total_device_bytes: u64,
}

impl Device {
    /// Opens the device as every command opens it (`common::open_gpu`) and makes a renderer.
    pub fn open(d: &DeviceArgs) -> Result<Device> {
        let gpu = crate::common::open_gpu(d)?;
        let before = gpu.device_memory_bytes();
        let renderer = Renderer::new(&gpu)?;
        let renderer_bytes = gpu.device_memory_bytes().saturating_sub(before);
        Ok(Device {
            gpu,
            renderer,
            renderer_bytes,
        })
    }

    /// Builds `scene`'s acceleration structures with the prepared sections, and chooses the primary visibility
    /// (`prepared.primary`; `Auto` measures it on the prepared camera with `settings`).
    pub fn install(self, scene: &Scene, prepared: &Prepared, settings: &AoSettings) -> Result<Installed> {
        let Device {
            gpu,
            mut renderer,
            renderer_bytes,
        } = self;
        let scene_gpu = build_scene_gpu(&gpu, scene, &prepared.sections)?;
        let total_device_bytes = gpu.device_memory_bytes();
        let frame = FrameDesc::new(&scene_gpu, scene.f(), prepared.camera, settings);
        let (primary, _) =
            choose_primary(&gpu, &mut renderer, prepared.primary, prepared.pass_times, &frame)?;
        Ok(Installed {
            scene_device_bytes: total_device_bytes.saturating_sub(renderer_bytes),
            total_device_bytes,
            gpu,
            scene_gpu,
            renderer,
            primary,
        })
    }
}

impl Installed {
    /// Another renderer of the scene, with the same primary visibility (`bench`'s renderer of the paper's mode).
    pub fn another_renderer(&self) -> Result<Renderer> {
        let mut r = Renderer::new(&self.gpu)?;
        r.set_primary(self.primary);
        Ok(r)
    }
}

/// The scene's acceleration structures with `sections` applied.
pub fn build_scene_gpu(gpu: &Arc<Gpu>, scene: &Scene, sections: &Sections) -> Result<SceneGpu> {
    let mut scene_gpu = SceneGpu::new(gpu, scene)?;
    scene_gpu.set_sections(scene, sections, u32::MAX)?;
    log::info!(
        "acceleration structures: {} BLAS in {:.0} ms, TLAS of {} instances in {:.1} ms",
        scene_gpu.stats.blas_count,
        scene_gpu.stats.blas_ms,
        scene_gpu.stats.tlas_instances,
        scene_gpu.stats.tlas_ms
    );
    Ok(scene_gpu)
}

/// Sets `renderer`'s primary visibility as `choice` asks: `Auto` measures both on `frame`
/// (`Renderer::pick_primary`, which leaves the hash map alone and starts a new still image), unless `pass_times`
/// and the device cannot time rasterised frames (then ray queries, unmeasured); `Raster` on a device that cannot
/// rasterise it is an error. Returns the choice and, when measured, the ray-query frame's milliseconds (else NaN):
/// the viewer's first ray budget follows it.
pub fn choose_primary(
    gpu: &Gpu,
    renderer: &mut Renderer,
    choice: PrimaryChoice,
    pass_times: bool,
    frame: &FrameDesc,
) -> Result<(Primary, f64)> {
    let primary = match choice {
        PrimaryChoice::Auto if pass_times && !times_frames(renderer, Primary::Raster) => {
            log::info!("primary visibility: RayQuery (this device does not time rasterised frames' passes)");
            renderer.set_primary(Primary::RayQuery);
            return Ok((Primary::RayQuery, f64::NAN));
        }
        PrimaryChoice::Auto => {
            let (primary, rq_ms, raster_ms) = renderer.pick_primary(frame)?;
            log::info!(
                "primary visibility: {primary:?} (ray queries {rq_ms:.0} ms, raster {raster_ms:.0} ms at {}x{})",
                frame.camera.width,
                frame.camera.height
            );
            return Ok((primary, rq_ms));
        }
        PrimaryChoice::RayQuery => Primary::RayQuery,
        PrimaryChoice::Raster => {
            Rasterizer::available(gpu).map_err(|e| anyhow!("--primary raster: {e}"))?;
            if pass_times && !times_frames(renderer, Primary::Raster) {
                log::warn!("--primary raster: this device does not time rasterised frames' passes");
            }
            Primary::Raster
        }
    };
    renderer.set_primary(primary);
    log::info!("primary visibility: {primary:?} (--primary)");
    Ok((primary, f64::NAN))
}

/// Whether the device times the passes of `renderer`'s frames with `primary` (its own primary kept).
fn times_frames(renderer: &mut Renderer, primary: Primary) -> bool {
    let kept = renderer.primary();
    renderer.set_primary(primary);
    let timed = renderer.timestamps_measure();
    renderer.set_primary(kept);
    timed
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::{Cli, Command};

    /// A folder of this test's own.
    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("hrtao-setup-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A tetrahedron 2 × 3 × 4 as an ASCII STL file in `dir`.
    fn write_part(dir: &Path) -> String {
        let v = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 4.0]];
        let mut stl = String::from("solid part\n");
        for [a, b, c] in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            stl.push_str("facet normal 0 0 0\nouter loop\n");
            for i in [a, b, c] {
                let [x, y, z] = v[i];
                stl.push_str(&format!("vertex {x} {y} {z}\n"));
            }
            stl.push_str("endloop\nendfacet\n");
        }
        stl.push_str("endsolid part\n");
        let path = dir.join("part.stl");
        std::fs::write(&path, stl).unwrap();
        path.display().to_string()
    }

    /// A z-up camera file.
    fn write_camera(path: &Path, eye: [f32; 3]) {
        let json = format!(
            r#"{{"eye": [{}, {}, {}], "target": [1, 1, 1], "up": [0, 0, 1], "fov_y_deg": 30, "width": 200,
               "height": 100}}"#,
            eye[0], eye[1], eye[2]
        );
        std::fs::write(path, json).unwrap();
    }

    fn parse(line: &[&str]) -> Cli {
        Cli::try_parse_from(line).unwrap_or_else(|e| panic!("{line:?}: {e}"))
    }

    /// The inputs of `hrtao FILE`, `hrtao view FILE`, `hrtao render --scene FILE` and `hrtao bench --scene FILE`
    /// with the same options `rest`. `file` None: no model (the bundled scene), which `bench` takes by path.
    fn inputs(file: Option<&str>, rest: &[&str]) -> Vec<(&'static str, SetupInputs)> {
        let bundled = crate::common::default_scene_path().display().to_string();
        let line = |head: &[&str], file: Option<&str>| {
            let line: Vec<&str> = ["hrtao"]
                .iter()
                .chain(head)
                .copied()
                .chain(file)
                .chain(rest.iter().copied())
                .collect();
            parse(&line)
        };
        let view = |c: Cli| match c.command {
            Some(Command::View(v)) => SetupInputs::from_view(&v),
            None => SetupInputs::from_view(&c.view),
            other => panic!("{other:?}"),
        };
        let scene_flag: &[&str] = if file.is_some() { &["--scene"] } else { &[] };
        let render = match line(&[&["render"], scene_flag].concat(), file).command {
            Some(Command::Render(r)) => SetupInputs::from_render(&r),
            other => panic!("{other:?}"),
        };
        let bench = match line(&["bench", "--scene"], Some(file.unwrap_or(&bundled))).command {
            Some(Command::Bench(b)) => SetupInputs::from_bench(&b),
            other => panic!("{other:?}"),
        };
        vec![
            ("hrtao FILE", view(line(&[], file))),
            ("view", view(line(&["view"], file))),
            ("render", render),
            ("bench", bench),
        ]
    }

    /// Prepares `scene` for every command with the same options and checks they agree; returns the viewer's.
    fn same_everywhere(file: Option<&str>, rest: &[&str], scene: &Scene) -> Prepared {
        let all: Vec<_> = inputs(file, rest)
            .into_iter()
            .map(|(name, i)| {
                (
                    name,
                    prepare(&i, scene).unwrap_or_else(|e| panic!("{name}: {e:#}")),
                )
            })
            .collect();
        // Each command sizes an automatic camera for its own image; everything else is the same.
        let pose = |p: &Prepared| Camera {
            width: 1,
            height: 1,
            ..p.camera
        };
        let (first, a) = &all[0];
        for (name, b) in &all[1..] {
            let what = format!("{first} and {name} with {file:?} {rest:?}");
            assert_eq!(pose(a), pose(b), "{what}: camera");
            assert_eq!(a.camera_file, b.camera_file, "{what}: camera file");
            assert_eq!(a.up, b.up, "{what}: up axis");
            assert_eq!(a.radius, b.radius, "{what}: radius");
            assert_eq!(a.default_radius, b.default_radius, "{what}: default radius");
            assert_eq!(a.bundled, b.bundled, "{what}: bundled");
            assert_eq!(a.sections.planes, b.sections.planes, "{what}: sections");
            if a.camera_file.is_some() {
                assert_eq!(a.camera, b.camera, "{what}: a camera file's size");
            }
        }
        all.into_iter().next().unwrap().1
    }

    #[test]
    fn view_render_and_bench_set_up_alike() {
        let d = dir("alike");
        let file = write_part(&d);
        let (part, _) = crate::common::load_scene(&file).unwrap();
        let diagonal = part.bounds().diagonal().length();

        // No camera file: fitted, y up, 5 % of the diagonal.
        let p = same_everywhere(Some(&file), &[], &part);
        assert_eq!(
            (p.camera_file.as_deref(), p.up, p.bundled),
            (None, UpAxis::Y, false)
        );
        assert!(
            (p.radius - diagonal * 0.05).abs() < 1e-6,
            "{} of {diagonal}",
            p.radius
        );
        assert_eq!(p.camera.up, [0.0, 1.0, 0.0]);

        // The camera saved beside the model, by every command, and its up axis.
        let beside = d.join("part.camera.json");
        write_camera(&beside, [9.0, -9.0, 5.0]);
        let p = same_everywhere(Some(&file), &[], &part);
        assert_eq!(p.camera_file.as_deref(), Some(beside.as_path()));
        assert_eq!((p.camera.eye, p.camera.width), ([9.0, -9.0, 5.0], 200));
        assert_eq!(p.up, UpAxis::Z);

        // --camera over the file beside; --up, --radius and --section as given.
        let other = d.join("other.json");
        write_camera(&other, [-7.0, 8.0, 2.0]);
        let rest = [
            "--camera",
            other.to_str().unwrap(),
            "--up",
            "y",
            "--radius",
            "0.25",
            "--section",
            "0,0,1,1.5",
        ];
        let p = same_everywhere(Some(&file), &rest, &part);
        assert_eq!(p.camera_file.as_deref(), Some(other.as_path()));
        assert_eq!(p.camera.eye, [-7.0, 8.0, 2.0]);
        assert_eq!((p.up, p.radius), (UpAxis::Y, 0.25));
        assert_eq!(p.sections.planes.len(), 1);

        // A generated scene stands on z.
        let spec = "gen:box?size=2";
        let (generated, _) = crate::common::load_scene(spec).unwrap();
        let p = same_everywhere(Some(spec), &[], &generated);
        assert_eq!((p.camera_file.as_deref(), p.up), (None, UpAxis::Z));
        assert_eq!(p.camera.up, [0.0, 0.0, 1.0]);
        let _ = std::fs::remove_dir_all(d);
    }

    /// The bundled scene (no model given, or its file by path): its radius, its camera beside it, z up.
    #[test]
    fn the_bundled_scene_is_set_up_alike() {
        let (part, _) = crate::common::load_scene("gen:box?size=2").unwrap();
        let p = same_everywhere(None, &[], &part);
        assert!(p.bundled);
        assert_eq!((p.radius, p.default_radius), (BUNDLED_RADIUS, BUNDLED_RADIUS));
        let camera = crate::common::default_scene_path().with_extension("camera.json");
        assert_eq!(p.camera_file.as_deref(), Some(camera.as_path()));
        assert_eq!(p.up, UpAxis::Z);
        let p = same_everywhere(None, &["--radius", "2"], &part);
        assert_eq!((p.radius, p.default_radius), (2.0, BUNDLED_RADIUS));
    }

    #[test]
    fn an_empty_scene_is_an_error_naming_the_file_in_every_command() {
        let d = dir("empty");
        let file = write_part(&d);
        for (name, i) in inputs(Some(&file), &[]) {
            let e = prepare(&i, &Scene::new("empty")).unwrap_err().to_string();
            assert!(
                e.contains("part.stl") && e.contains("no visible geometry"),
                "{name}: {e}"
            );
        }
        let _ = std::fs::remove_dir_all(d);
    }

    /// `bench --auto-camera` asks for an automatic camera: the file beside the model is not used.
    #[test]
    fn an_explicit_automatic_camera_wins_over_the_file_beside() {
        let d = dir("auto");
        let file = write_part(&d);
        write_camera(&d.join("part.camera.json"), [9.0, -9.0, 5.0]);
        let (part, _) = crate::common::load_scene(&file).unwrap();
        for (auto, fov) in [("fit", FIT_FOV_DEG), ("corner", 50.0)] {
            let cli = parse(&["hrtao", "bench", "--scene", &file, "--auto-camera", auto]);
            let Some(Command::Bench(b)) = cli.command else {
                panic!()
            };
            let p = prepare(&SetupInputs::from_bench(&b), &part).unwrap();
            assert_eq!(p.camera_file, None, "{auto}");
            assert_eq!(
                (p.camera.fov_y_deg, p.camera.width, p.up),
                (fov, 320, UpAxis::Y),
                "{auto}"
            );
        }
        let _ = std::fs::remove_dir_all(d);
    }
}
