//! `specchio`: the command-line tool. `main` reads like a table of contents: parse the
//! arguments, then run one subcommand. The commands of this crate parse, call the engine and
//! say what they did; the benchmark and the localisation experiment are `specchio-bench`'s,
//! the viewer is `specchio-viewer`'s (in a build with the `viewer` feature, the default;
//! without it `specchio view` says how to get it, `no_viewer.rs`).

mod calibrate;
mod compare;
mod dataset;
mod image_files;
mod info;
// Compiled in every build so that its test runs where the tests run (with the viewer).
#[cfg_attr(feature = "viewer", allow(dead_code))]
mod no_viewer;
mod probe;
mod records;
mod reference;
mod render;
mod render_input;
mod render_report;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
#[cfg(not(feature = "viewer"))]
use no_viewer as view;
use specchio::process::{allocator, ending};
use specchio_bench::localise;
#[cfg(feature = "viewer")]
use specchio_viewer as view;

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
    /// Ray trace the exact mirror on the CPU (the reference the cube map is judged against).
    Reference(reference::Args),
    /// Speed against error of every cube fill method: interleaved timings, floors, error
    /// against the exact reference, incremental updates; JSON, CSV, SVG and a regression gate.
    Bench(specchio_bench::Args),
    /// Fit the central models robotics tools calibrate (OpenCV omnidir, Kalibr omni,
    /// OCamCalib) to the sensor's exact rays; export them with their residuals.
    Calibrate(calibrate::Args),
    /// The robot moved along a trajectory: per pose the sensor's image and ground-truth layers,
    /// its pose in the scene's frame and ROS REP-103's, a point cloud; an index for loaders.
    Dataset(dataset::Args),
    /// Appearance-based localisation: landmarks on a floor grid, random queries matched to
    /// them by a descriptor of the sensor's panorama; recall, position and heading errors.
    Localise(localise::Args),
    /// Error metrics of a test image against a reference (RMSE, PSNR, relMSE, FLIP), with an
    /// optional mask and FLIP heatmap.
    Compare(compare::Args),
    /// The live viewer: a window with the observer and the sensor side by side, keyboard
    /// control of the observer, the mirror, time, method, lookup and refresh (docs/viewer.md).
    View(view::Args),
    /// (internal) Compare a cube method with six-pass on a tiny scene; run in a child process
    /// because a broken driver may crash.
    #[command(hide = true)]
    Probe(probe::Args),
}

/// The second CPU driver, SwiftShader, lives in this checkout's `.drivers/` (put there by
/// `scripts/setup.sh`, not installed system-wide). Unless the user chose drivers through the
/// loader's variables, add it, so that `specchio` run from here lists it beside the system's
/// drivers (`cargo run` and `cargo test` get the same through `.cargo/config.toml`).
fn add_project_drivers() {
    const CHOSEN: [&str; 3] = ["VK_ADD_DRIVER_FILES", "VK_DRIVER_FILES", "VK_ICD_FILENAMES"];
    if CHOSEN.iter().any(|v| std::env::var_os(v).is_some()) {
        return;
    }
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../.drivers/swiftshader/vk_swiftshader_icd.json");
    if manifest.exists() {
        // Sound: no other thread exists yet, and the loader reads it when it is loaded.
        std::env::set_var("VK_ADD_DRIVER_FILES", manifest);
    }
}

fn main() -> ExitCode {
    // A reader of stdout that goes away (`specchio ... | head`) must not kill the run with
    // its staging folder on disk: writes then fail with EPIPE, which `stdout` handles.
    #[cfg(unix)]
    // SAFETY: sets the disposition of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_IGN);
    }
    specchio::output::survive_file_size_limit();
    add_project_drivers();
    allocator::tune();
    let cli = Cli::parse();
    specchio::process::progress::say_long_work();
    let result = match cli.command {
        Command::Info(args) => info::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Probe(args) => probe::run(&args),
        Command::Bench(args) => specchio_bench::run(&args),
        Command::Reference(args) => reference::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Calibrate(args) => calibrate::run(&args),
        Command::View(args) => view::run(&args),
        Command::Localise(args) => localise::run(&args),
        Command::Dataset(args) => dataset::run(&args),
    };
    ending::report(result)
}
