//! `specchio`: the command-line tool. `main` reads like a table of contents: parse the
//! arguments, then run one subcommand (each in its own module).

mod info;
mod probe;
mod render;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Simulates a catadioptric camera (a camera looking at a spherical mirror) with dynamic
/// cube-map reflections on Vulkan.
#[derive(Parser)]
#[command(name = "specchio", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// What the Vulkan devices are and which features later methods need.
    Info(info::Args),
    /// Render a scene: observer, sensor, side-by-side views and the six cube faces.
    Render(render::Args),
    /// (internal) Compare a cube method with six-pass on a tiny scene; run in a child process
    /// because a broken driver may crash.
    #[command(hide = true)]
    Probe(probe::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(args) => info::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Probe(args) => probe::run(&args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
