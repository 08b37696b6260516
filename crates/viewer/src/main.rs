//! `hrtao`: CAD viewport with noise-free ray-traced ambient occlusion (HRTAO), and its headless commands.
mod bench;
mod cli;
mod common;
mod occt_worker;
mod render_cmd;
mod view;

use clap::Parser;

fn main() {
    // The STEP/IGES kernel's worker process (hidden: started by the scene loader, not by users).
    if std::env::args_os()
        .nth(1)
        .is_some_and(|a| a == occt_worker::SUBCOMMAND)
    {
        std::process::exit(occt_worker::main(std::env::args_os().skip(2).collect()));
    }
    if let Ok(exe) = std::env::current_exe() {
        hrtao_scene::set_default_cad_worker(exe);
    }
    let args = cli::Cli::parse();
    let default_level = if args.verbose { "debug" } else { "info" };
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or(default_level))
        .format_timestamp_millis()
        .init();
    if let Err(e) =
        occt_worker::set_tessellation(args.deflection, args.deflection_mm, args.angular_deflection)
    {
        eprintln!("hrtao: error: {e}");
        std::process::exit(2);
    }
    let result = match args.command {
        Some(cli::Command::Render(r)) => render_cmd::run(&r),
        Some(cli::Command::Devices(d)) => render_cmd::list_devices(&d),
        Some(cli::Command::View(v)) => view::run(&v),
        Some(cli::Command::Bench(b)) => bench::run(&b),
        None => view::run(&cli::ViewArgs::default()),
    };
    if let Err(e) = result {
        eprintln!("hrtao: error: {e:#}");
        std::process::exit(1);
    }
}
