//! Sky light (the paper's "environment shadows", §6): the environment that lights the model, as the `--light-out`
//! contract defines it (`environment.rs`), and the spherical-harmonic basis its light is carried in
//! (`sh.rs`): the cells will keep the directions their rays escaped in as a transfer vector in that basis, so a
//! rotation of the environment turns its coefficients and traces no new rays.
pub mod environment;
pub mod light;
pub mod sh;

pub use environment::{Environment, Equirect};
pub use light::{EnvironmentSpec, SkyLight};
pub use sh::ShRgb;
