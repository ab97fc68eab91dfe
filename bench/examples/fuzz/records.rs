//! The fuzz targets that are files a user hands a command besides scenes: the bench baseline
//! and the landmarks file, read by the benchmark crate's own readers.

use std::path::Path;

use specchio_bench::localise::database;
use specchio_bench::record;

/// A `specchio bench --json` record, read as `--baseline` reads it.
pub fn baseline(input: &[u8]) -> bool {
    record::parse(&String::from_utf8_lossy(input)).is_ok()
}

/// A landmarks file, checked as `localise --landmarks` checks it against a run with the
/// seed's own settings (so mutated inputs reach the signature checks behind the match).
pub fn landmarks(input: &[u8], seed_path: &Path) -> bool {
    let seed: Option<database::Database> = std::fs::read(seed_path)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok());
    let Some(mut run) = seed else {
        return false;
    };
    run.landmarks.clear();
    let expected = |source: &str| match source == run.source {
        true => Ok(run.clone()),
        false => Err(format!("field `source` is {source}, not {}", run.source)),
    };
    database::parse(input, "fuzz input", &expected).is_ok()
}
