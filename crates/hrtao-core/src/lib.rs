//! hrtao-core: the Vulkan ray-query core of hrtao.
//!
//! - `context`: instance, validation, device selection (`Gpu`).
//! - `buffer`, `accel`: GPU memory and acceleration structures (`SceneGpu`).
//! - `gpu`: the GPU-visible structs shared with GLSL (generated header).
//! - `pass`, `timer`: the one way to declare and record a compute pass, and its timing.
//! - `raster`: rasterised primary visibility (the ray-query pass's G-buffer from instanced draws).
//! - `dispatch_plan`: ray-tracing passes cut into dispatches no GPU watchdog stops.
//! - `renderer`: the frame (primary visibility, per-pixel RTAO, HRTAO passes, composite).
//! - `hash`: CPU mirror of the shaders' hash functions (paper eq. 1-6).
//! - `tile`: a window of a larger image (large screenshots rendered tile by tile).
//! - `camera`, `settings`, `imageio`, `headless`: inputs and outputs.
//! - `stats`, `bench_json`: medians and ratios of measurements; the results `hrtao bench` writes.
// The test helpers the integration tests share (tests/common), also for the unit tests of a module that keeps its
// GPU tests beside its code (each of `additions`): they name this crate as the integration tests do.
#[cfg(test)]
extern crate self as hrtao_core;
#[cfg(test)]
#[path = "../tests/common/mod.rs"]
pub(crate) mod testkit;

pub mod accel;
pub mod additions;
pub mod barrier;
pub mod bench_json;
pub mod buffer;
pub mod camera;
pub mod clip;
pub mod context;
pub mod dispatch_plan;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod hash;
pub mod hash_map;
pub mod imageio;
pub mod in_flight;
pub mod metrics;
pub mod pass;
pub mod passes;
pub mod probes;
pub mod raster;
pub mod recorder;
pub mod regions;
pub mod renderer;
pub mod rt_pipeline;
pub mod section;
pub mod settings;
pub mod sky;
pub mod slice_order;
pub mod stats;
pub mod tile;
pub mod timer;

pub use accel::SceneGpu;
pub use camera::Camera;
pub use context::{ContextOptions, DeviceInfo, Gpu, RayBackend};
pub use error::{CoreError, Result};
pub use frame::{FrameDesc, Output, RayBudget, MAX_LATTICE};
pub use raster::Primary;
pub use renderer::{FrameReport, Renderer};
pub use section::{SectionPlane, Sections};
pub use settings::{AoSettings, Invalidates, Mode};
