//! Command-line interface: every command's arguments. The commands import them from here (never the reverse).
use std::path::PathBuf;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use hrtao_core::camera::UpAxis;
use hrtao_core::{AoSettings, Mode, SectionPlane, Sections};
use hrtao_scene::glam::DVec3;
use hrtao_scene::Scene;

/// `hrtao --version`: the package version and the commit it was built from (none from a source tarball).
pub const VERSION: &str = match option_env!("HRTAO_GIT_COMMIT") {
    Some(_) => concat!(
        env!("CARGO_PKG_VERSION"),
        " (commit ",
        env!("HRTAO_GIT_COMMIT"),
        ")"
    ),
    None => env!("CARGO_PKG_VERSION"),
};

#[derive(Parser, Debug)]
#[command(
    name = "hrtao",
    version = VERSION,
    about = "CAD viewport with noise-free ray-traced ambient occlusion (HRTAO)",
    long_about = "CAD viewport with noise-free ray-traced ambient occlusion (HRTAO).\n\n\
        `hrtao FILE` opens FILE in the viewer (as `hrtao view FILE`); with no argument the viewer opens the \
        bundled gearbox. The other commands render, benchmark and list devices without a window."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// The viewer's options when no command is given (`hrtao FILE` is `hrtao view FILE`).
    #[command(flatten)]
    pub view: ViewArgs,
    /// Verbose logging (debug level; RUST_LOG overrides).
    #[arg(long, short, global = true, conflicts_with = "quiet")]
    pub verbose: bool,
    /// Quiet: warnings and errors only, no progress bars.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// STEP/IGES tessellation: linear deflection as a fraction of each part's size [default: 0.005; the fine
    /// choice: 0.001].
    #[arg(long, global = true, value_name = "FRACTION")]
    pub deflection: Option<f64>,
    /// STEP/IGES tessellation: linear deflection in millimetres for every part (F3D's way), instead of
    /// --deflection.
    #[arg(long, global = true, value_name = "MM", conflicts_with = "deflection")]
    pub deflection_mm: Option<f64>,
    /// STEP/IGES tessellation: angular deflection in degrees [default: 35; the fine choice: 10].
    #[arg(long, global = true, value_name = "DEGREES")]
    pub angular_deflection: Option<f64>,
    /// Meshes without normals of their own (STL; OBJ without `vn`, PLY without nx/ny/nz): smooth shading across
    /// edges whose faces meet at up to this angle, 0..=180 [default: 40, the feature edges' --crease]. Sharper
    /// edges stay creases.
    #[arg(long, global = true, value_name = "DEGREES", conflicts_with = "flat_normals")]
    pub smooth_angle: Option<f32>,
    /// Meshes without normals of their own shade with face normals (no smoothing). Files with normals and glTF
    /// (flat without NORMAL, as its spec says) are not affected by either flag.
    #[arg(long, global = true)]
    pub flat_normals: bool,
}

impl Cli {
    /// Makes `--smooth-angle`/`--flat-normals` the smoothing of every load with default options (`hrtao render`,
    /// `bench`, and the viewer's panel); an angle outside 0..=180 is an error.
    pub fn set_mesh_smoothing(&self) -> Result<(), String> {
        let crease = match (self.smooth_angle, self.flat_normals) {
            (_, true) => None,
            (Some(deg), false) => {
                Some(hrtao_scene::normals::check_crease(deg).map_err(|e| format!("--smooth-angle: {e}"))?)
            }
            (None, false) => return Ok(()),
        };
        hrtao_scene::normals::set_default_crease_deg(crease);
        Ok(())
    }
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the interactive viewer (the default with no command).
    View(ViewArgs),
    /// Benchmark HRTAO against per-pixel RTAO along a camera path (JSON + table).
    Bench(BenchArgs),
    /// Render a scene headless to PNG (shaded) and PFM/EXR (linear AO).
    Render(RenderArgs),
    /// List every Vulkan device, whether hrtao can use it, and which one it chooses and why.
    Devices(DeviceArgs),
    /// A file manager's preview: a small PNG with AO, bounded in file size, memory and time (the desktop's
    /// thumbnailer, packaging/hrtao.thumbnailer, runs it).
    Thumbnail(ThumbnailArgs),
    /// Write the shell completions (bash, zsh, fish) and the man pages into DIR (packaging/install.sh).
    #[command(hide = true)]
    GenerateShellFiles(ShellFilesArgs),
}

/// The model formats, as the help and the Open dialog list them: every extension of
/// [`hrtao_scene::SUPPORTED_EXTENSIONS`], e.g. `.gltf, .glb, .obj`.
pub fn formats() -> String {
    hrtao_scene::SUPPORTED_EXTENSIONS
        .iter()
        .map(|e| format!(".{e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The help of an option that names a model: `WHAT: FORMATS, or a generator spec such as EXAMPLE` and `tail`.
fn model_help(what: &str, example: &str, tail: &str) -> String {
    format!(
        "{what}: {}, or a generator spec such as {example}{tail}.",
        formats()
    )
}

/// An environment variable hrtao reads: its name (with the values it takes, if few), and what it does. The one
/// list behind `hrtao --help` and docs/command-line.md (whose table has exactly these rows: tests/formats.rs).
pub struct EnvVar {
    pub name: &'static str,
    pub text: &'static str,
}

/// Every environment variable hrtao and its tests read, in the order `--help` and docs/command-line.md list them.
pub const ENVIRONMENT: &[EnvVar] = &[
    EnvVar {
        name: "RUST_LOG",
        text: "log filter (env_logger), e.g. RUST_LOG=debug or RUST_LOG=hrtao_core=debug; default info (-v: \
               debug, -q: warn)",
    },
    EnvVar {
        name: "HRTAO_DEVICE",
        text: "use the best device whose name contains this text (as --device)",
    },
    EnvVar {
        name: "HRTAO_VALIDATION=1",
        text: "the Khronos validation layer on (as --validation); messages are logged and counted, and scripted \
               runs exit 1 on any",
    },
    EnvVar {
        name: "HRTAO_RAY_BACKEND=query|pipeline",
        text: "trace rays with ray queries or ray-tracing pipelines (as --ray-backend; default: ray queries where \
               the device has them)",
    },
    EnvVar {
        name: "HRTAO_HIDE_RAY_QUERY=1",
        text: "every device looks like one without ray queries (as the pipelines-only data-centre GPUs): the \
               binary and the test suite run on ray-tracing pipelines, and the tests that need ray queries skip \
               with a message",
    },
    EnvVar {
        name: "HRTAO_MAX_SCENE_MB",
        text: "memory a scene may take while it loads, in MiB (default: half the physical memory, at most 16 GiB)",
    },
    EnvVar {
        name: "HRTAO_DEVICE_MEMORY_LIMIT",
        text: "refuse device allocations past this many MiB (simulates a small GPU)",
    },
    EnvVar {
        name: "HRTAO_OCCT_CPU_SECONDS",
        text: "CPU seconds the STEP/IGES worker process may use per file (default 300); past it the load fails \
               with an error naming the file",
    },
    EnvVar {
        name: "HRTAO_IFC_PYTHON",
        text: "the Python interpreter that runs the IFC worker (default: bin/python3 of the venv \
               scripts/install-ifc.sh makes, hrtao/ifc-venv in the XDG data directory, ~/.local/share); without \
               it an .ifc file is an error naming the install command",
    },
    EnvVar {
        name: "HRTAO_IFC_CPU_SECONDS",
        text: "CPU seconds the IFC worker process may use per file (default 300); past it the load fails with an \
               error naming the file",
    },
    EnvVar {
        name: "HRTAO_FRAMES_IN_FLIGHT=1|2",
        text: "frames the viewer submits before it waits for the oldest, over the settings file's \
               frames_in_flight (default: 2 on a GPU, 1 on a software device)",
    },
    EnvVar {
        name: "HRTAO_SWAPCHAIN_FORMAT=unorm|srgb",
        text: "the viewer chooses its swapchain format among those of one kind only (default: 8-bit UNORM, else \
               8-bit sRGB); for tests of both paths",
    },
    EnvVar {
        name: "HRTAO_UI_PROBE=1",
        text: "the viewer logs where named panel controls are (`ui probe: NAME at X,Y WxH`, window pixels) \
               whenever they move: the window tests click them with xdotool",
    },
    EnvVar {
        name: "XDG_CONFIG_HOME",
        text: "the viewer's settings file is hrtao/viewer.json there (default ~/.config); a relative path is \
               ignored, as the XDG specification says",
    },
    EnvVar {
        name: "XDG_DATA_HOME",
        text: "the IFC worker's venv is hrtao/ifc-venv there (default ~/.local/share); a relative path is ignored",
    },
    EnvVar {
        name: "XDG_CACHE_HOME",
        text: "the bundled scene is written as a file to hrtao/bundled there (default ~/.cache, else the \
               temporary directory)",
    },
    EnvVar {
        name: "XDG_PICTURES_DIR",
        text: "where F12 saves screenshots unless the panel names a folder (default: the XDG pictures directory, \
               else ~/Pictures)",
    },
    EnvVar {
        name: "DISPLAY, WAYLAND_DISPLAY",
        text: "the viewer needs one; without either it says so (run scripted runs under xvfb-run)",
    },
    EnvVar {
        name: "HRTAO_SHARED",
        text: "benchmarks and measurement tools only: a folder of extra scenes and references not in the \
               repository; the test suite never reads it",
    },
    EnvVar {
        name: "HRTAO_SOAK_FRAMES",
        text: "tests only: frames of the soak test (default 200)",
    },
    EnvVar {
        name: "MESA_SHADER_CACHE_DISABLE, MESA_SHADER_CACHE_DIR",
        text: "Mesa's own; scripts/test.sh keeps the shader cache in target/mesa-shader-cache",
    },
];

/// `--primary`: how primary visibility is found (`crate::setup::Device::install` applies it).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PrimaryChoice {
    /// Measured: the faster of ray queries and rasterisation for this scene on this device.
    #[default]
    Auto,
    /// One ray query per pixel.
    RayQuery,
    /// Rasterised visibility, then one ray-triangle test per pixel.
    Raster,
}

/// `bench --auto-camera`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AutoCamera {
    /// Frame the whole scene from outside.
    Fit,
    /// Stand at a corner of the bounds at 80 % of their height and look across the scene.
    Corner,
}

/// `bench --group`: the table of the report a result goes to.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    Scenes,
    Scale,
}

impl Group {
    pub fn name(self) -> &'static str {
        match self {
            Group::Scenes => "scenes",
            Group::Scale => "scale",
        }
    }
}

/// `WxH`, each side within 1..=16384.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}` must look like 1280x720"))?;
    let side = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("`{s}`: {e}"));
    let (w, h) = (side(w)?, side(h)?);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("`{s}`: each side must be within 1..=16384"));
    }
    Ok((w, h))
}

/// A JSON object of `AoSettings` fields (checked for syntax and field names; values are checked with the rest
/// of the settings).
pub fn parse_settings_json(s: &str) -> Result<String, String> {
    let fields: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(s).map_err(|e| format!("not a JSON object of settings: {e}"))?;
    let known = serde_json::to_value(AoSettings::default()).map_err(|e| e.to_string())?;
    if let Some(k) = fields.keys().find(|k| known.get(k.as_str()).is_none()) {
        return Err(format!("no setting `{k}`"));
    }
    Ok(s.to_string())
}

/// The value parser of an option that sets the AO setting `key` (its `--set` key): the value must pass the
/// setting's declaration (`hrtao_core::settings`: range, rule), checked as `--set` checks it.
fn setting<T>(key: &'static str) -> impl TypedValueParser<Value = T>
where
    T: std::str::FromStr + serde::Serialize + Clone + Send + Sync + 'static,
    T::Err: std::fmt::Display,
{
    move |s: &str| -> Result<T, String> {
        let v: T = s.parse().map_err(|e| format!("{e}"))?;
        AoSettings::default()
            .with_overrides(&serde_json::json!({ key: &v }).to_string())
            .map(|_| v)
    }
}

fn parse_render_scale(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    let range = crate::view::RENDER_SCALE;
    if !range.contains(&v) {
        return Err(format!("{v} is not within {}..={}", range.start(), range.end()));
    }
    Ok(v)
}

/// The AO modes, listed in the help and in errors.
fn mode_parser() -> impl TypedValueParser<Value = Mode> {
    PossibleValuesParser::new([
        PossibleValue::new("hrtao").help("the paper's hash-map AO with our additions"),
        PossibleValue::new("rtao").help("per-pixel ray-traced AO (the baseline)"),
        PossibleValue::new("none").alias("no-ao").help("no AO"),
        PossibleValue::new("debug-cells").alias("cells"),
        PossibleValue::new("debug-lod").alias("lod"),
        PossibleValue::new("debug-samples").alias("samples"),
    ])
    .map(|s| s.parse::<Mode>().expect("every listed mode parses"))
}

/// `K VALUE` pairs of a repeatable two-value option, K a frame count.
pub fn frame_pairs(option: &str, values: &[String]) -> anyhow::Result<Vec<(u32, String)>> {
    values
        .chunks(2)
        .map(|kv| match kv {
            [k, v] => Ok((
                k.parse::<u32>()
                    .map_err(|e| anyhow::anyhow!("{option} K: `{k}`: {e}"))?,
                v.clone(),
            )),
            _ => anyhow::bail!("{option} takes K and a value"),
        })
        .collect()
}

/// The `--set-at-frame K JSON` pairs, each JSON checked as `--set` checks it.
pub fn set_at_frame(values: &[String]) -> anyhow::Result<Vec<(u32, String)>> {
    let pairs = frame_pairs("--set-at-frame", values)?;
    for (_, json) in &pairs {
        parse_settings_json(json).map_err(|e| anyhow::anyhow!("--set-at-frame: {e}"))?;
    }
    Ok(pairs)
}

#[derive(Args, Debug, Clone, Default)]
pub struct DeviceArgs {
    /// Use the best device whose name contains this text (case-insensitive).
    #[arg(long, env = "HRTAO_DEVICE")]
    pub device: Option<String>,
    /// Enable the Khronos validation layer (also HRTAO_VALIDATION=1).
    #[arg(long)]
    pub validation: bool,
    /// Trace rays with ray queries (`query`) or ray-tracing pipelines (`pipeline`); default: ray queries where
    /// the device has them, else pipelines.
    #[arg(long, value_name = "query|pipeline", env = "HRTAO_RAY_BACKEND")]
    pub ray_backend: Option<hrtao_core::RayBackend>,
}

/// The camera, up axis and primary visibility, for `render`, `bench` and `view` (`crate::setup` applies them).
#[derive(Args, Debug, Clone, Default)]
pub struct SetupArgs {
    /// Camera JSON {"eye","target","up","fov_y_deg","width","height"} (the viewer's first view), orthographic
    /// with "projection": "orthographic" and "ortho_height" (world height of the image); default: the scene's
    /// `NAME.camera.json` beside it, else fit the scene.
    #[arg(long)]
    pub camera: Option<PathBuf>,
    /// World up axis: x, y, z, -x, -y or -z (default: in the viewer, the one chosen in the panel for this file;
    /// else the camera file's, else z for the bundled scene and gen: specs, else the format's: IFC and 3MF z,
    /// glTF y; else y).
    #[arg(long, value_parser = UpAxis::parse, allow_hyphen_values = true)]
    pub up: Option<UpAxis>,
    /// Primary visibility (in `bench`, of every mode): measured (auto), ray queries or rasterised.
    #[arg(long, value_enum, default_value_t = PrimaryChoice::Auto)]
    pub primary: PrimaryChoice,
}

/// Section planes, for `render`, `bench` and `view`.
#[derive(Args, Debug, Clone, Default)]
pub struct SectionArgs {
    /// Section plane NX,NY,NZ,D in the file's coordinates: geometry where n·p > d is cut away (repeatable, at
    /// most 3), e.g. `--section 0,0,1,2.5` removes everything above z = 2.5.
    #[arg(long = "section", value_name = "NX,NY,NZ,D", allow_hyphen_values = true)]
    pub section: Vec<SectionPlane>,
}

impl SectionArgs {
    /// The planes in the scene's coordinates (the scene may be recentred from the file's, see `Scene::origin`).
    pub fn sections(&self, scene: &Scene) -> Result<Sections, String> {
        let planes = self
            .section
            .iter()
            .map(|p| {
                let n = DVec3::from(p.normal.map(f64::from));
                let on_plane = scene.from_file(n * p.offset as f64);
                SectionPlane::new(p.normal, hrtao_scene::glam::Vec3::from(p.normal).dot(on_plane))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Sections::new(planes)
    }
}

#[derive(Args, Debug, Clone)]
pub struct AoArgs {
    /// AO mode.
    #[arg(long, default_value = "hrtao", value_parser = mode_parser())]
    pub mode: Mode,
    /// AO radius in scene units (default: 8 for the bundled scene, else 5% of the bounds diagonal).
    #[arg(long)]
    pub radius: Option<f32>,
    /// Ray budget: rays per pixel per frame.
    #[arg(long, default_value_t = AoSettings::default().map.rays_per_pixel, value_parser = setting::<u32>("rays_per_pixel"))]
    pub rays: u32,
    /// s_p: target feature size in pixels (eq. 2).
    #[arg(long, default_value_t = AoSettings::default().map.s_p, value_parser = setting::<f32>("s_p"))]
    pub sp: f32,
    /// s_nd: normal discretisation (eq. 5).
    #[arg(long, default_value_t = AoSettings::default().map.s_nd, value_parser = setting::<f32>("s_nd"))]
    pub snd: f32,
    /// Rays per hash cell after which the cell stops receiving rays.
    #[arg(long, default_value_t = AoSettings::default().map.max_samples, value_parser = setting::<u32>("max_samples"))]
    pub max_samples: u32,
    /// Minimum samples before a cell is used instead of a coarser one (§4).
    #[arg(long, default_value_t = AoSettings::default().map.min_samples, value_parser = setting::<u32>("min_samples"))]
    pub min_samples: u32,
    /// À-trous filter iterations (0 disables the filter, §5).
    #[arg(long, default_value_t = AoSettings::default().filter.filter_iterations, value_parser = setting::<u32>("filter_iterations"))]
    pub filter_iterations: u32,
    /// Hash map capacity in cells (a power of two).
    #[arg(long, default_value_t = AoSettings::default().map.hash_capacity, value_parser = setting::<u32>("hash_capacity"))]
    pub hash_capacity: u32,
    /// Render a uniform grey clay instead of the materials' base colours.
    #[arg(long)]
    pub clay: bool,
    /// Draw feature edges (silhouettes and creases) over the shaded image (never in the AO image).
    #[arg(long)]
    pub edges: bool,
    /// Crease angle of the feature edges, in degrees.
    #[arg(long, default_value_t = AoSettings::default().display.crease_deg, value_parser = setting::<f32>("crease_deg"))]
    pub crease: f32,
    /// Sky light (ours): light the model with this environment and its soft shadows instead of the AO look:
    /// `uniform`, `gradient` or an equirectangular Radiance .hdr file (zenith: --up).
    #[arg(long, value_name = "uniform|gradient|FILE.hdr")]
    pub environment: Option<String>,
    /// Sky light: turn the environment counter-clockwise seen from above, in degrees.
    #[arg(long, value_name = "DEG", default_value_t = AoSettings::default().light.environment_rotation, allow_negative_numbers = true,
        value_parser = setting::<f32>("environment_rotation"))]
    pub environment_rotation: f32,
    /// Sky light: scale the environment's light by K.
    #[arg(long, value_name = "K", default_value_t = AoSettings::default().light.environment_intensity,
        value_parser = setting::<f32>("environment_intensity"))]
    pub environment_intensity: f32,
    /// Any other AO setting, as a JSON object of `AoSettings` fields (applied last), e.g.
    /// `--set '{"refine": false, "filter_iterations": 3}'`. Every key with its valid values and default:
    /// docs/command-line.md.
    #[arg(long, value_name = "JSON", value_parser = parse_settings_json)]
    pub set: Option<String>,
}

impl AoArgs {
    /// The settings these options ask for, with `ao_radius` the radius the setup chose (`setup::Prepared::radius`:
    /// `--radius` when given, else the scene's default; the one place for that rule is `crate::setup`).
    pub fn settings(&self, ao_radius: f32) -> anyhow::Result<AoSettings> {
        let mut settings = AoSettings::default();
        settings.display.mode = self.mode;
        settings.map.ao_radius = ao_radius;
        settings.map.rays_per_pixel = self.rays;
        settings.map.s_p = self.sp;
        settings.map.s_nd = self.snd;
        settings.map.max_samples = self.max_samples;
        settings.map.min_samples = self.min_samples;
        settings.filter.filter_iterations = self.filter_iterations;
        settings.map.hash_capacity = self.hash_capacity;
        settings.display.shaded = !self.clay;
        settings.display.edges = self.edges;
        settings.display.crease_deg = self.crease;
        if let Some(environment) = &self.environment {
            settings.light.sky_light = true;
            // A file is named by its absolute path: the settings outlive the working directory (prefs).
            settings.light.environment = match hrtao_core::sky::EnvironmentSpec::parse(environment) {
                Ok(hrtao_core::sky::EnvironmentSpec::File(path)) => std::path::absolute(&path)
                    .unwrap_or(path)
                    .to_string_lossy()
                    .into_owned(),
                _ => environment.clone(),
            };
        }
        settings.light.environment_rotation = self.environment_rotation;
        settings.light.environment_intensity = self.environment_intensity;
        match &self.set {
            Some(json) => settings.with_overrides(json).map_err(anyhow::Error::msg),
            None => Ok(settings),
        }
    }
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    // Scene: every format (`formats`), or a generator spec; the bundled gearbox by default.
    #[arg(long, help = model_help("Scene", "gen:racks?rows=10&cols=10", " (default: the bundled gearbox with its camera)"))]
    pub scene: Option<String>,
    #[command(flatten)]
    pub setup: SetupArgs,
    /// Image width (overrides the camera file).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (overrides the camera file).
    #[arg(long)]
    pub height: Option<u32>,
    /// The plan view of a storey of an IFC building (its name, or its number from 0): only its elements, cut 1.2 m
    /// above its elevation, seen from the top in an orthographic view framing it (over --camera and --section).
    #[arg(long, value_name = "STOREY")]
    pub plan: Option<String>,
    #[command(flatten)]
    pub ao: AoArgs,
    /// Frames to render with the same camera (per-pixel RTAO averages them; the HRTAO map persists).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Scripted: apply these settings (a JSON object, as --set takes it) after K frames, as the panel would
    /// (repeatable).
    #[arg(long, num_args = 2, value_names = ["K", "JSON"], hide = true)]
    pub set_at_frame: Vec<String>,
    #[command(flatten)]
    pub sections: SectionArgs,
    /// Shaded output image (.png).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Linear AO output (.pfm or .exr).
    #[arg(long)]
    pub ao_out: Option<PathBuf>,
    /// Linear sky light output (with --environment): RGB at the first hit through each pixel centre, a white
    /// Lambertian lit by the environment with its shadows, background 0; a colour .pfm or an RGB .exr.
    #[arg(long)]
    pub light_out: Option<PathBuf>,
    /// A reference of the AO image (.pfm or .exr, e.g. a Blender Cycles one): the last frame's error against it
    /// goes into --stats (`ao_error`: MAE and RMSE over the pixels not open in both).
    #[arg(long, value_name = "FILE")]
    pub ao_reference: Option<PathBuf>,
    /// A reference of the sky light (.pfm or .exr, background 0; with --environment): the last frame's error
    /// against it goes into --stats (`light_error`: MAE over the pixels the model covers in either, and the
    /// reference's mean there).
    #[arg(long, value_name = "FILE")]
    pub light_reference: Option<PathBuf>,
    /// Statistics JSON (device, timings, rays).
    #[arg(long)]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

#[derive(Args, Debug, Clone, Default)]
pub struct ViewArgs {
    // Model to open: every format (`formats`), or a generator spec; the bundled gearbox by default.
    #[arg(value_name = "FILE", help = model_help("Model to open", "gen:city", " (default: the bundled gearbox)"))]
    pub file: Option<String>,
    #[command(flatten)]
    pub setup: SetupArgs,
    /// Window size, e.g. 1280x720.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Largest internal resolution as a fraction of the 3D view (default 1): a still image is rendered at it;
    /// while the camera moves the scale drops to meet the frame-time target (never below 0.35 unless capped).
    #[arg(long, value_parser = parse_render_scale)]
    pub render_scale: Option<f32>,
    /// AO mode.
    #[arg(long, value_parser = mode_parser())]
    pub mode: Option<Mode>,
    /// Ray budget in rays per frame, whatever the internal resolution (turns the frame-time target off).
    #[arg(long, value_name = "N")]
    pub rays_per_frame: Option<u32>,
    /// Keep the ray budget and the moving render scale fixed instead of following the frame-time target.
    #[arg(long)]
    pub no_auto_budget: bool,
    /// AO radius in scene units (default: 8 for the bundled scene, else 5% of the bounds diagonal).
    #[arg(long)]
    pub radius: Option<f32>,
    /// Scripted mode: render this many frames once the scene is ready, then take the screenshots.
    #[arg(long)]
    pub frames: Option<u32>,
    /// Scripted mode: save the 3D view (no UI) at window resolution to this PNG after --frames.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Scripted mode: render --screenshot at this size in the background (tiles, one frame per viewer frame,
    /// each tile until converged) while the window keeps drawing; the run ends once the PNG is written.
    #[arg(long, value_name = "WxH", requires = "screenshot", value_parser = parse_size)]
    pub screenshot_size: Option<(u32, u32)>,
    /// Scripted mode: save the whole window including the UI to this PNG after --frames.
    #[arg(long)]
    pub screenshot_ui: Option<PathBuf>,
    /// Scripted mode: extra frames rendered for --screenshot at window size (the hash map keeps converging);
    /// with --screenshot-size each tile renders until converged instead.
    #[arg(long, default_value_t = 4)]
    pub screenshot_frames: u32,
    /// Scripted mode: resize the window to WxH after frame K (tests resizing), e.g. `--resize-at-frame 2 320x200`.
    #[arg(long, num_args = 2, value_names = ["K", "WxH"], hide = true)]
    pub resize_at_frame: Vec<String>,
    /// Scripted mode: open FILE after frame K, as a user would from the panel (tests that a bad file leaves the
    /// current scene in place), e.g. `--open-at-frame 1 broken.glb`.
    #[arg(long, num_args = 2, value_names = ["K", "FILE"], hide = true)]
    pub open_at_frame: Vec<String>,
    /// Scripted mode: apply these settings (a JSON object, as `render --set` takes it) after K rendered frames,
    /// as the panel would (repeatable).
    #[arg(long, num_args = 2, value_names = ["K", "JSON"], hide = true)]
    pub set_at_frame: Vec<String>,
    /// Scripted mode: orbit the view's pivot by 2° per frame for N frames, then stay still until the image has
    /// converged at full resolution (then the screenshots, --exit).
    #[arg(long, value_name = "N")]
    pub orbit: Option<u32>,
    /// Scripted mode: walk the model (walk mode) from `start`, dropped onto the floor below it, through the
    /// waypoints in turn at walking speed (one blocked for 2 s is given up), then end the script. The file:
    /// `{"start": [x, y, z], "waypoints": [[x, y], ...]}` in the file's coordinates, x, y on the floor plane of
    /// the up axis (for a Z-up model, plan coordinates). `--stats` records each frame's `eye` and `walk`.
    #[arg(long, value_name = "PATH.json", conflicts_with = "orbit")]
    pub walk_path: Option<PathBuf>,
    /// Scripted mode: write per-frame statistics (wall/GPU ms, internal and view size, moving) to this JSON.
    #[arg(long, value_name = "FILE")]
    pub stats: Option<PathBuf>,
    /// Scripted mode: write the view's AO of every rendered frame (at the internal size) as DIR/frame_NNNN.pfm,
    /// and its roughness in --stats.
    #[arg(long, value_name = "DIR", hide = true)]
    pub ao_out: Option<PathBuf>,
    /// Scripted mode without --frames: the viewer behaves as for a user (renders while refining, rests once
    /// converged) and exits at its first rest at least SECONDS after the last input (or the start), writing
    /// --stats.
    #[arg(long, value_name = "SECONDS", hide = true, conflicts_with_all = ["frames", "orbit"])]
    pub exit_after: Option<f64>,
    /// Scripted mode: exit after --frames (exit status 1 if anything failed or validation reported messages).
    #[arg(long)]
    pub exit: bool,
    /// Scripted mode: fail if the run has not finished after this many seconds (0 = never). Default: 600, plus
    /// 600 per million pixels of --screenshot-size (a 3840×2160 shot takes minutes to tens of minutes on a CPU).
    #[arg(long)]
    pub timeout: Option<u64>,
    /// Settings/bookmarks file (default: ~/.config/hrtao/viewer.json).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Neither read nor write the settings file.
    #[arg(long)]
    pub no_config: bool,
    /// Start with the side panel hidden (Tab toggles it).
    #[arg(long)]
    pub no_panel: bool,
    #[command(flatten)]
    pub sections: SectionArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// `hrtao thumbnail`: the limits that keep a file manager from waiting on a file too big or too slow.
#[derive(Args, Debug, Clone)]
pub struct ThumbnailArgs {
    /// Longest side of the PNG in pixels (the thumbnailer's %s: 128, 256, 512 or 1024).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(16..=2048))]
    pub size: u32,
    // The model: every format (`formats`), or a generator spec.
    #[arg(value_name = "INPUT", help = model_help("The model", "gen:city", ""))]
    pub input: String,
    /// The PNG to write: written whole (through a temporary file beside it) or not at all.
    #[arg(value_name = "OUTPUT.png")]
    pub output: PathBuf,
    /// Frames of AO to render at most (fewer when half of --timeout has passed).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub frames: u32,
    /// Give up after this many seconds (exit status 1, no PNG): loading, the device and the frames together.
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0, value_parser = parse_timeout)]
    pub timeout: f64,
    /// Refuse a model file larger than this many MiB.
    #[arg(long, value_name = "MIB", default_value_t = 256)]
    pub max_file_mb: u64,
    /// Memory the scene may take while it loads, in MiB (HRTAO_MAX_SCENE_MB, when lower, wins); the device's
    /// allocations are capped at twice this plus 512 MiB.
    #[arg(long, value_name = "MIB", default_value_t = 1024, value_parser = clap::value_parser!(u64).range(16..))]
    pub max_memory_mb: u64,
    /// Tests: the AO mode (`none` shows what the AO adds).
    #[arg(long, default_value = "hrtao", value_parser = mode_parser(), hide = true)]
    pub mode: Mode,
    #[command(flatten)]
    pub device: DeviceArgs,
}

fn parse_timeout(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if !(0.1..=3600.0).contains(&v) {
        return Err(format!("{v} is not within 0.1..=3600 seconds"));
    }
    Ok(v)
}

/// `hrtao generate-shell-files DIR`.
#[derive(Args, Debug, Clone)]
pub struct ShellFilesArgs {
    /// The folder to write into: hrtao.bash, _hrtao (zsh), hrtao.fish and man1/hrtao*.1.
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
}

#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    // Scene: every format (`formats`), or a generator spec.
    #[arg(long, required = true, help = model_help("Scene", "gen:racks?rows=10&cols=10", ""))]
    pub scene: Option<String>,
    #[command(flatten)]
    pub setup: SetupArgs,
    /// Navigation path: a JSON array of cameras (or {"cameras": [...]}); sizes come from --width/--height.
    #[arg(long, conflicts_with = "orbit")]
    pub path: Option<PathBuf>,
    /// Navigation: N frames orbiting the camera target by --orbit-step degrees per frame (default 16).
    #[arg(long)]
    pub orbit: Option<u32>,
    /// Degrees per orbit frame (a walking-speed camera move at 60 frames per second).
    #[arg(long, default_value_t = 0.25)]
    pub orbit_step: f32,
    /// Image width (default: the camera file's, else 320).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the camera file's, else 180).
    #[arg(long)]
    pub height: Option<u32>,
    /// At most this many static frames after the first frame and before the navigation, letting cells fill as
    /// they would during the first fraction of a second on a GPU (the paper's navigation is with a warm map).
    #[arg(long, default_value_t = 128)]
    pub settle: u32,
    /// Stop settling once a frame traces fewer than this fraction of the first frame's rays.
    #[arg(long, default_value_t = 0.1)]
    pub settle_until: f64,
    /// Automatic camera, instead of the file's `NAME.camera.json` (no --camera); from a corner, inside a room,
    /// depth complexity grows with its size [default: fit].
    #[arg(long, value_enum)]
    pub auto_camera: Option<AutoCamera>,
    /// First-frame repetitions (each from an empty hash map); the summary takes medians.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeat: u32,
    /// Skip the error measurements (reference, curves, search over B): timing and memory only.
    #[arg(long)]
    pub no_quality: bool,
    /// Rays per pixel per frame of the progressive per-pixel RTAO run (resolution of the search over B).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    pub step: u32,
    /// Cap of the search over per-pixel rays (0: 64 × B, at least 64).
    #[arg(long, default_value_t = 0)]
    pub max_rays: u32,
    /// Rays per pixel of the converged per-pixel RTAO reference (disjoint from the searched samples).
    #[arg(long, default_value_t = 1024)]
    pub ref_rays: u32,
    /// Static HRTAO frames for HRTAO's error-versus-rays curve.
    #[arg(long, default_value_t = 8)]
    pub hrtao_frames: u32,
    /// Optional independent reference AO image (.pfm or .exr, e.g. a Blender Cycles reference of testdata/refs).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Name in reports (default: the scene file stem or spec).
    #[arg(long)]
    pub label: Option<String>,
    /// Group in reports.
    #[arg(long, value_enum, default_value_t = Group::Scenes)]
    pub group: Group,
    /// Write the results here (schema hrtao-bench/1; `cargo run -p bench-report -- DIR` renders a directory of
    /// them as docs/benchmarks.md).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// AO settings (--mode is ignored: the bench runs both HRTAO and per-pixel RTAO).
    #[command(flatten)]
    pub ao: AoArgs,
    #[command(flatten)]
    pub sections: SectionArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn section_planes_are_given_in_file_coordinates() {
        let mut scene = Scene::new("far");
        scene.origin = [1.0e6, -2.0e6, 0.0];
        let args = SectionArgs {
            section: vec![
                "2,0,0,2000010".parse().unwrap(),
                "0,-1,0,2000003".parse().unwrap(),
            ],
        };
        let s = args.sections(&scene).unwrap();
        // x > 1e6 + 5 in the file is x > 5 in the scene; -y > 2e6 + 3 is -y > 3.
        assert_eq!(s.planes[0].normal, [1.0, 0.0, 0.0]);
        assert!((s.planes[0].offset - 5.0).abs() < 1e-3, "{:?}", s.planes[0]);
        assert!((s.planes[1].offset - 3.0).abs() < 1e-3, "{:?}", s.planes[1]);
        let four = SectionArgs {
            section: vec!["1,0,0,0".parse().unwrap(); 4],
        };
        assert!(four.sections(&scene).unwrap_err().contains("at most 3"));
    }
}
