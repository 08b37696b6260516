//! `bench-report DIR [--markdown FILE]`: reads every `hrtao bench` result of DIR (schema `hrtao-bench/1`, with
//! the `first_frame/` and `latency/` results under it, `scripts/bench-step.sh`'s `step_*.json` and
//! `scripts/gpu-check.sh`'s `gpu/report.json`) and writes the markdown report (default: DIR/../benchmarks.md) and
//! its PNG plots beside the results. A development tool: `hrtao bench` measures, this renders, and the user's
//! binary carries none of it.
//!
//! `cargo run -p bench-report -- docs/bench --markdown docs/benchmarks.md`
mod first_frame_report;
mod formats_report;
mod gpu_report;
mod latency_report;
mod plot;
mod ray_backend_report;
mod report;
mod results;
mod sky_report;
mod step_sweep_report;
mod viewer_report;
mod walk_report;

use std::path::PathBuf;

use clap::Parser;

/// The markdown + PNG report of a directory of `hrtao bench` results.
#[derive(Parser, Debug)]
#[command(version)]
struct Args {
    /// Directory of `hrtao bench --json` results; the plots are written beside them.
    dir: PathBuf,
    /// Markdown output (default: DIR/../benchmarks.md).
    #[arg(long)]
    markdown: Option<PathBuf>,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    report::run(&args.dir, args.markdown.as_deref())
}
