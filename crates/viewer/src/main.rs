//! `hrtao`: CAD viewport with noise-free ray-traced ambient occlusion (HRTAO), and its headless commands.
mod bench;
mod cli;
mod common;
mod occt_worker;
mod plan;
mod render_cmd;
mod setup;
mod shell_files;
mod thumbnail;
mod view;

use clap::{CommandFactory, FromArgMatches};

/// `hrtao -h`: examples.
const EXAMPLES: &str = "\
Examples:
  hrtao                               open the bundled gearbox in the viewer
  hrtao model.step                    open a model (any format listed under [FILE])
  hrtao render --scene model.glb --out shot.png --ao-out ao.exr --frames 8
  hrtao thumbnail --size 256 model.step preview.png
  hrtao bench --scene gen:racks?rows=10&cols=10 --json racks.json
  hrtao devices                       which Vulkan device hrtao uses, and why

`hrtao --help` also lists the viewer's keys and the environment variables.";

/// `  NAME` then the text wrapped at 76 columns, indented: narrow enough that clap's own wrapping at the
/// terminal's width leaves it alone.
fn two_column<'a>(rows: impl IntoIterator<Item = (&'a str, &'a str)>) -> String {
    let mut out = String::new();
    for (name, text) in rows {
        out.push_str(&format!("  {name}\n"));
        let mut line = String::from("      ");
        for word in text.split_whitespace() {
            if line.len() + word.len() >= 76 && !line.trim_start().is_empty() {
                out.push_str(line.trim_end());
                out.push('\n');
                line = String::from("      ");
            }
            line.push_str(word);
            line.push(' ');
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

fn cli_command() -> clap::Command {
    let examples = EXAMPLES.lines().take_while(|l| !l.starts_with("`hrtao --help`"));
    cli::Cli::command().after_help(EXAMPLES).after_long_help(format!(
        "{}\n\nViewer keys and mouse (the panel's Help lists them too):\n{}\nEnvironment:\n{}",
        examples.collect::<Vec<_>>().join("\n").trim_end(),
        two_column(view::BINDINGS.iter().copied()),
        two_column(cli::ENVIRONMENT.iter().map(|v| (v.name, v.text)))
    ))
}

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
    let args = match cli::Cli::from_arg_matches(&cli_command().get_matches()) {
        Ok(a) => a,
        Err(e) => e.format(&mut cli_command()).exit(),
    };
    let default_level = match (args.verbose, args.quiet) {
        (true, _) => "debug",
        (_, true) => "warn",
        _ => "info",
    };
    common::set_quiet(args.quiet);
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or(default_level))
        .format_timestamp_millis()
        .init();
    if let Err(e) =
        occt_worker::set_tessellation(args.deflection, args.deflection_mm, args.angular_deflection)
            .and_then(|()| args.set_mesh_smoothing())
    {
        eprintln!("hrtao: error: {e}");
        std::process::exit(2);
    }
    let result = match args.command {
        Some(cli::Command::Render(r)) => render_cmd::run(&r),
        Some(cli::Command::Devices(d)) => render_cmd::list_devices(&d),
        Some(cli::Command::View(v)) => view::run(&v),
        Some(cli::Command::Bench(b)) => bench::run(&b),
        Some(cli::Command::Thumbnail(t)) => thumbnail::run(&t),
        Some(cli::Command::GenerateShellFiles(g)) => shell_files::write(cli_command(), &g.dir),
        None => view::run(&args.view),
    };
    if let Err(e) = result {
        eprintln!("hrtao: error: {e:#}");
        std::process::exit(1);
    }
}
