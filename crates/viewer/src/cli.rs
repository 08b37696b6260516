//! Command-line interface.
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use hrtao_core::{AoSettings, Mode};

#[derive(Parser, Debug)]
#[command(
    name = "hrtao",
    version,
    about = "CAD viewport with noise-free ray-traced ambient occlusion (HRTAO)"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Verbose logging.
    #[arg(long, short, global = true)]
    pub verbose: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the interactive viewer (the default with no command).
    View(crate::view::ViewArgs),
    /// Benchmark HRTAO against per-pixel RTAO along a camera path (JSON + table).
    Bench(crate::bench::BenchArgs),
    /// Render a scene headless to PNG (shaded) and PFM/EXR (linear AO).
    Render(RenderArgs),
    /// List Vulkan devices and whether they support ray queries.
    Devices(DeviceArgs),
}

#[derive(Args, Debug, Clone)]
pub struct DeviceArgs {
    /// Use the first device whose name contains this text.
    #[arg(long)]
    pub device: Option<String>,
    /// Enable the Khronos validation layer (also HRTAO_VALIDATION=1).
    #[arg(long)]
    pub validation: bool,
}

#[derive(Args, Debug, Clone)]
pub struct AoArgs {
    /// AO mode: hrtao, rtao (per-pixel baseline), none, debug-cells, debug-lod, debug-samples.
    #[arg(long, default_value = "hrtao")]
    pub mode: Mode,
    /// AO radius in scene units (default: 5% of the scene's bounding-box diagonal).
    #[arg(long)]
    pub radius: Option<f32>,
    /// Ray budget: rays per pixel per frame.
    #[arg(long, default_value_t = AoSettings::default().rays_per_pixel)]
    pub rays: u32,
    /// s_p: target feature size in pixels (eq. 2).
    #[arg(long, default_value_t = AoSettings::default().s_p)]
    pub sp: f32,
    /// s_nd: normal discretisation (eq. 5).
    #[arg(long, default_value_t = AoSettings::default().s_nd)]
    pub snd: f32,
    /// Rays per hash cell after which the cell stops receiving rays.
    #[arg(long, default_value_t = AoSettings::default().max_samples)]
    pub max_samples: u32,
    /// Minimum samples before a cell is used instead of a coarser one (§4).
    #[arg(long, default_value_t = AoSettings::default().min_samples)]
    pub min_samples: u32,
    /// À-trous filter iterations (0 disables the filter, §5).
    #[arg(long, default_value_t = AoSettings::default().filter_iterations)]
    pub filter_iterations: u32,
    /// Hash map capacity in cells (a power of two).
    #[arg(long, default_value_t = AoSettings::default().hash_capacity)]
    pub hash_capacity: u32,
    /// Render a uniform grey clay instead of the materials' base colours.
    #[arg(long)]
    pub clay: bool,
}

impl AoArgs {
    pub fn settings(&self, scene_diagonal: f32) -> AoSettings {
        let scene_diagonal = if scene_diagonal.is_finite() && scene_diagonal > 0.0 {
            scene_diagonal
        } else {
            1.0
        };
        AoSettings {
            mode: self.mode,
            ao_radius: self.radius.unwrap_or((scene_diagonal * 0.05).max(1e-6)),
            rays_per_pixel: self.rays,
            s_p: self.sp,
            s_nd: self.snd,
            max_samples: self.max_samples,
            min_samples: self.min_samples,
            filter: self.filter_iterations > 0,
            filter_iterations: self.filter_iterations,
            hash_capacity: self.hash_capacity,
            shaded: !self.clay,
            ..AoSettings::default()
        }
    }
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene: .gltf, .glb, .obj, or a generator spec such as gen:racks?rows=10&cols=10.
    #[arg(long)]
    pub scene: String,
    /// Camera JSON {"eye","target","up","fov_y_deg","width","height"} (default: fit the scene).
    #[arg(long)]
    pub camera: Option<PathBuf>,
    /// Image width (overrides the camera file).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (overrides the camera file).
    #[arg(long)]
    pub height: Option<u32>,
    /// Up axis for the automatic camera: y or z.
    #[arg(long, default_value = "y")]
    pub up: String,
    #[command(flatten)]
    pub ao: AoArgs,
    /// Frames to render with the same camera (per-pixel RTAO averages them; the HRTAO map persists).
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// Shaded output image (.png).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Linear AO output (.pfm or .exr).
    #[arg(long)]
    pub ao_out: Option<PathBuf>,
    /// Statistics JSON (device, timings, rays).
    #[arg(long)]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    pub device: DeviceArgs,
}
