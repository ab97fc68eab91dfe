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

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| -> Option<String> {
        let i = args.iter().position(|a| a == flag)?;
        Some(
            args.get(i + 1)
                .unwrap_or_else(|| fail(&format!("{flag} needs a value")))
                .clone(),
        )
    };
    let number = |flag: &str, default: u64| -> u64 {
        value(flag).map_or(default, |v| {
            v.parse()
                .unwrap_or_else(|_| fail(&format!("{flag}: `{v}` is not a whole number")))
        })
    };
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
    let targets = match value("--target").as_deref() {
        None | Some("all") => Target::ALL.to_vec(),
        Some(name) => vec![Target::parse(name).unwrap_or_else(|| {
            fail(&format!(
                "--target: `{name}` is not one of scene, obj, gltf, glb, png, all"
            ))
        })],
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = value("--out").map_or_else(|| PathBuf::from("out/fuzz"), PathBuf::from);
    let mut faults = 0;
    let (mut total_execs, mut total_secs) = (0u64, 0f64);
    for target in targets {
        let config = Config {
            target,
            iterations: number("--iterations", 100_000),
            seed: number("--seed", 1),
            time_limit: Duration::from_millis(number("--time-limit-ms", 2000)),
            out: out.clone(),
            max_hangs: 3,
        };
        let report = harness::run(&root, &config, |r| {
            eprintln!(
                "{}: {} executions, {:.0}/s, {} panics, {} hangs",
                target.name(),
                r.executions,
                r.executions as f64 / r.seconds.max(1e-9),
                r.panics(),
                r.hangs()
            );
        });
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
        faults += report.faults.len();
        total_execs += report.executions;
        total_secs += report.seconds;
    }
    println!("total: {total_execs} executions in {total_secs:.1} s, {faults} faults");
    if faults > 0 {
        std::process::exit(1);
    }
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(2);
}
