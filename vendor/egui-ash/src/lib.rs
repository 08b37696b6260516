mod allocator;
mod app;
pub mod event;
mod integration;
mod presenters;
mod renderer;
mod run;
#[cfg(feature = "persistence")]
pub mod storage;
mod utils;

pub use egui_winit::winit;
pub use raw_window_handle;

pub use allocator::*;
pub use app::*;
pub use renderer::*;
pub use run::*;

#[cfg(feature = "gpu-allocator")]
mod gpu_allocator;
