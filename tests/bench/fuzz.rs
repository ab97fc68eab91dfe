//! A short, fixed-seed fuzz run of every loader (scene, OBJ, glTF, GLB, PNG): no input may
//! panic or hang. Long runs use the `fuzz` example (docs/fuzzing.md); both share the harness.

use std::path::Path;
use std::time::Duration;

#[path = "../../bench/examples/fuzz/harness.rs"]
#[allow(dead_code)]
mod harness;

use harness::{Config, Target};

/// Inputs per target: a few seconds in all on a test build.
const ITERATIONS: u64 = 300;

#[test]
fn no_loader_panics_or_hangs_on_mutated_inputs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = std::env::temp_dir().join(format!("specchio-fuzz-{}", std::process::id()));
    let mut problems = Vec::new();
    for target in Target::ALL {
        let config = Config {
            target,
            iterations: ITERATIONS,
            seed: 20_250_101,
            // A hang guard, not a speed test: generous for a loaded machine.
            time_limit: Duration::from_secs(60),
            out: out.clone(),
            max_hangs: 1,
        };
        let report = harness::run(&root, &config, |_| {});
        assert_eq!(report.executions, ITERATIONS, "{target:?}: every input ran");
        for f in &report.faults {
            problems.push(format!(
                "{target:?} {} ({}): {}",
                f.kind,
                f.saved.display(),
                f.message
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    let _ = std::fs::remove_dir_all(&out);
}

/// The record targets mutate their seeds from an accepted start: a seed the reader refuses
/// (a landmarks file of an older version, say) would leave the target fuzzing only its
/// first check.
#[test]
fn the_record_targets_accept_their_seeds() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for target in [Target::Baseline, Target::Landmarks] {
        let seeds = harness::seeds(&root, target);
        assert!(!seeds.is_empty(), "{target:?}: no seed");
        for s in seeds {
            assert!(
                harness::execute(target, &s.bytes, &s.path),
                "{target:?}: {} is refused",
                s.path.display()
            );
        }
    }
}
