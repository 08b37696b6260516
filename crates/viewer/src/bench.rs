//! `hrtao bench`: placeholder until the benchmark lands.
use anyhow::{bail, Result};
use clap::Args;

#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// Scene: file or gen:... spec.
    #[arg(long)]
    pub scene: String,
}

pub fn run(_args: &BenchArgs) -> Result<()> {
    bail!("hrtao bench is not implemented yet")
}
