//! What the development examples share: `--flag value` arguments and `--set` overrides of `AoSettings`.
use hrtao_core::{AoSettings, Primary};

/// The command line after the program name; `take` removes a flag and its value.
pub struct Args(pub Vec<String>);

impl Args {
    pub fn from_env() -> Args {
        Args(std::env::args().skip(1).collect())
    }

    /// The value after `flag` (removed with it), or `default`.
    pub fn take(&mut self, flag: &str, default: &str) -> String {
        match self.0.iter().position(|a| a == flag) {
            Some(i) if i + 1 < self.0.len() => {
                let v = self.0.remove(i + 1);
                self.0.remove(i);
                v
            }
            _ => default.to_string(),
        }
    }

    /// `--primary raster|rayquery` (default raster). Not every example including this module uses it.
    #[allow(dead_code)]
    pub fn primary(&mut self) -> Primary {
        if self.take("--primary", "raster") == "raster" {
            Primary::Raster
        } else {
            Primary::RayQuery
        }
    }
}

/// `base` with the fields of the JSON object `overrides` replaced (e.g. `{"variance_filter": false}`).
pub fn with_overrides(base: &AoSettings, overrides: &str) -> anyhow::Result<AoSettings> {
    base.with_overrides(overrides).map_err(anyhow::Error::msg)
}
