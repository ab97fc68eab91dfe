//! Long fuzz runs of the scene and asset loaders (see `docs/fuzzing.md` for how to use it):
//!
//! ```sh
//! cargo run --release -p specchio-bench --example fuzz -- --target gltf --iterations 1000000
//! ```
//!
//! Options: `--target scene|obj|gltf|glb|png|baseline|landmarks|all` (default all, run one after another),
//! `--iterations N` per target (default 100000), `--seed S` (default 1), `--time-limit-ms MS`
//! per input before it counts as a hang (default 2000), `--out DIR` for faulting inputs
//! (default `out/fuzz`). Exits with status 1 if any input panicked or hung.

use std::path::{Path, PathBuf};
use std::time::Duration;

// Loaded by path, as tests/bench/fuzz.rs loads it, so that its own `#[path]` modules resolve alike.
#[path = "harness.rs"]
mod harness;

use harness::{Config, Target};

/// The options, as given on the command line (defaults filled in).
struct Options {
    targets: Vec<Target>,
    out: PathBuf,
    iterations: u64,
    seed: u64,
    time_limit: Duration,
}

/// The totals over every target run.
#[derive(Default)]
struct Totals {
    faults: usize,
    executions: u64,
    seconds: f64,
}

impl Totals {
    /// Adds one target's report.
    fn add(&mut self, report: &harness::Report) {
        self.faults += report.faults.len();
        self.executions += report.executions;
        self.seconds += report.seconds;
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let options = parse_options(&args);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut totals = Totals::default();
    for &target in &options.targets {
        let report = run_target(&root, &options.config(target));
        print_report(target, &report);
        totals.add(&report);
    }
    println!(
        "total: {} executions in {:.1} s, {} faults",
        totals.executions, totals.seconds, totals.faults
    );
    if totals.faults > 0 {
        std::process::exit(1);
    }
}

/// Reads the options from `args`, failing on an unknown option or a bad value.
fn parse_options(args: &[String]) -> Options {
    check_flags(args);
    let targets = parse_targets(value(args, "--target").as_deref());
    let out = value(args, "--out").map_or_else(|| PathBuf::from("out/fuzz"), PathBuf::from);
    let iterations = number(args, "--iterations", 100_000);
    let seed = number(args, "--seed", 1);
    let time_limit = Duration::from_millis(number(args, "--time-limit-ms", 2000));
    Options {
        targets,
        out,
        iterations,
        seed,
        time_limit,
    }
}

/// Fails on any `--` argument that is not one of the options.
fn check_flags(args: &[String]) {
    for a in args.iter().filter(|a| a.starts_with("--")) {
        if ![
            "--target",
            "--iterations",
            "--seed",
            "--time-limit-ms",
            "--out",
        ]
        .contains(&a.as_str())
        {
            fail(&format!("unknown option {a}"));
        }
    }
}

/// The value after `flag` in `args`, if the flag is given.
fn value(args: &[String], flag: &str) -> Option<String> {
    let i = args.iter().position(|a| a == flag)?;
    Some(
        args.get(i + 1)
            .unwrap_or_else(|| fail(&format!("{flag} needs a value")))
            .clone(),
    )
}

/// The whole number after `flag` in `args`, or `default` without the flag.
fn number(args: &[String], flag: &str, default: u64) -> u64 {
    value(args, flag).map_or(default, |v| {
        v.parse()
            .unwrap_or_else(|_| fail(&format!("{flag}: `{v}` is not a whole number")))
    })
}

/// The targets `--target` names: every one for none or `all`.
fn parse_targets(name: Option<&str>) -> Vec<Target> {
    match name {
        None | Some("all") => Target::ALL.to_vec(),
        Some(name) => vec![Target::parse(name).unwrap_or_else(|| {
            // The list from the targets themselves, so it never misses one.
            let names: Vec<&str> = Target::ALL.iter().map(|t| t.name()).collect();
            fail(&format!(
                "--target: `{name}` is not one of {}, all",
                names.join(", ")
            ))
        })],
    }
}

impl Options {
    /// The harness's set-up for one target.
    fn config(&self, target: Target) -> Config {
        Config {
            target,
            iterations: self.iterations,
            seed: self.seed,
            time_limit: self.time_limit,
            out: self.out.clone(),
            max_hangs: 3,
        }
    }
}

/// Runs one target, printing its progress to stderr as it goes.
fn run_target(root: &Path, config: &Config) -> harness::Report {
    let target = config.target;
    harness::run(root, config, |r| {
        eprintln!(
            "{}: {} executions, {:.0}/s, {} panics, {} hangs",
            target.name(),
            r.executions,
            r.executions as f64 / r.seconds.max(1e-9),
            r.panics(),
            r.hangs()
        );
    })
}

/// Prints one target's result and its faults.
fn print_report(target: Target, report: &harness::Report) {
    println!(
        "{}: {} executions in {:.1} s ({:.0}/s), {} accepted, {} panics, {} hangs",
        target.name(),
        report.executions,
        report.seconds,
        report.executions as f64 / report.seconds.max(1e-9),
        report.accepted,
        report.panics(),
        report.hangs()
    );
    for f in &report.faults {
        println!("  {} ({}): {}", f.kind, f.saved.display(), f.message);
    }
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(2);
}
