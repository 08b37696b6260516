//! `hrtao view`: the interactive viewer (winit + egui-ash). Placeholder until the viewer lands:
//! renders the scene headless instead.
use anyhow::Result;
use clap::Args;

#[derive(Args, Debug, Clone, Default)]
pub struct ViewArgs {
    /// Scene file to open (default: the bundled scene).
    pub file: Option<String>,
}

pub fn run(_args: &ViewArgs) -> Result<()> {
    crate::render_cmd::run_default()
}
