//! Errors of the core crate: every failure a user can meet gets a message that says what and where.
use ash::vk;

#[derive(thiserror::Error, Debug)]
pub enum CoreError {
    #[error("{0}")]
    NoDevice(String),
    #[error("{0} failed: {1}")]
    Vulkan(&'static str, vk::Result),
    #[error("the GPU device was lost during {0} (driver crash or timeout); restart hrtao")]
    DeviceLost(&'static str),
    #[error("out of GPU memory: {0}")]
    Memory(String),
    #[error("{0}")]
    Invalid(String),
    #[error("I/O error on {path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("scene: {0}")]
    Scene(#[from] hrtao_scene::SceneError),
}

impl CoreError {
    pub fn from_vk(what: &'static str, e: vk::Result) -> Self {
        match e {
            vk::Result::ERROR_DEVICE_LOST => CoreError::DeviceLost(what),
            vk::Result::TIMEOUT => CoreError::DeviceLost(what),
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                CoreError::Memory(format!("{what}: {e}"))
            }
            other => CoreError::Vulkan(what, other),
        }
    }
}

pub type Result<T, E = CoreError> = std::result::Result<T, E>;
