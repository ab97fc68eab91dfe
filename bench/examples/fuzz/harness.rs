//! A small mutation fuzzer for the scene and asset loaders, on stable Rust.
//!
//! Inputs are the project's own scenes, meshes and textures, mutated (byte and bit flips,
//! insertions, deletions, duplications, splices, interesting numbers, and field edits that keep
//! JSON and TOML well-formed so that the loaders' deeper checks are reached). Each input runs on
//! a worker thread under `catch_unwind`; a panic, or an input that has not finished within the
//! time limit (a hang), is counted and the input saved. Shared by the `fuzz` example (long runs)
//! and `tests/bench/fuzz.rs` (a short fixed-seed run in the test suite).

use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

// The mutations draw from the project's one seeded sequence (`specchio::random`): a run with a
// given `--seed` replays on every platform.
use specchio::random::SplitMix64;
use specchio::scene::{load_str, Mesh, TextureData};

// The readers of the bench baseline and the landmarks file.
#[path = "records.rs"]
mod records;

/// What a fuzz input is fed to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `specchio::scene::load_str`, as if the text were the seed scene's file.
    Scene,
    Obj,
    Gltf,
    Glb,
    Png,
    /// A `specchio bench --json` record read as `--baseline`.
    Baseline,
    /// A `specchio localise` landmarks file read as `--landmarks`, checked against its seed.
    Landmarks,
}

impl Target {
    pub const ALL: [Target; 7] = [
        Target::Scene,
        Target::Obj,
        Target::Gltf,
        Target::Glb,
        Target::Png,
        Target::Baseline,
        Target::Landmarks,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Target::Scene => "scene",
            Target::Obj => "obj",
            Target::Gltf => "gltf",
            Target::Glb => "glb",
            Target::Png => "png",
            Target::Baseline => "baseline",
            Target::Landmarks => "landmarks",
        }
    }

    pub fn parse(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }

    /// File extensions of the seeds.
    fn extension(self) -> &'static str {
        match self {
            Target::Scene => "toml",
            Target::Baseline | Target::Landmarks => "json",
            other => other.name(),
        }
    }

    /// The folders its seeds come from.
    fn seed_folders(self) -> &'static [&'static str] {
        match self {
            Target::Baseline => &["bench/baselines"],
            Target::Landmarks => &["tests/seeds/landmarks"],
            _ => &[
                "scenes",
                "scenes/hard",
                "scenes/test",
                "scenes/meshes",
                "scenes/textures",
                "tests/scenes/bad",
                "tests/scenes/bad-assets",
                "tests/scenes/bad-assets/assets",
            ],
        }
    }
}

/// One seed: its bytes, and the file it came from (scenes resolve assets against it).
#[derive(Clone)]
pub struct Seed {
    pub path: PathBuf,
    pub bytes: Vec<u8>,
}

/// The seeds of `target`: every file with its extension in the given folders, sorted, so a
/// run with a fixed random seed is reproducible.
pub fn seeds(root: &Path, target: Target) -> Vec<Seed> {
    let mut out = Vec::new();
    for folder in target.seed_folders() {
        let Ok(entries) = std::fs::read_dir(root.join(folder)) else {
            continue;
        };
        let mut paths: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == target.extension()))
            .collect();
        paths.sort();
        for path in paths {
            if let Ok(bytes) = std::fs::read(&path) {
                out.push(Seed { path, bytes });
            }
        }
    }
    out
}

/// Feeds one input to the target. Errors are expected; only panics and hangs are faults.
/// Returns whether the input was accepted (such inputs are kept to mutate further).
pub fn execute(target: Target, input: &[u8], seed_path: &Path) -> bool {
    let folder = seed_path.parent().unwrap_or(Path::new("."));
    match target {
        Target::Scene => load_str(&String::from_utf8_lossy(input), seed_path).is_ok(),
        Target::Obj => Mesh::from_obj_bytes(input).is_ok(),
        Target::Gltf | Target::Glb => Mesh::from_gltf_bytes(input, folder).is_ok(),
        Target::Png => TextureData::from_png_bytes(input, seed_path).is_ok(),
        Target::Baseline => records::baseline(input),
        Target::Landmarks => records::landmarks(input, seed_path),
    }
}

/// Numbers that sit on edges: zero, signs, powers of two and their neighbours, limits of the
/// integer and float types, non-finite values.
const INTERESTING: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "4",
    "7",
    "8",
    "255",
    "256",
    "-129",
    "65535",
    "65536",
    "2147483647",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9007199254740993",
    "18446744073709551615",
    "18446744073709551616",
    "1e38",
    "3.5e38",
    "1e308",
    "1e309",
    "-1e309",
    "1e-45",
    "0.5",
    "nan",
    "inf",
    "-inf",
    "5126",
    "5125",
    "5123",
    "5121",
    "34962",
    "99999999",
];

pub fn mutate(rng: &mut SplitMix64, input: &[u8], other: &[u8], target: Target) -> Vec<u8> {
    let mut data = input.to_vec();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        data = match rng.below(10) {
            0 => flip_bit(rng, data),
            1 => set_byte(rng, data),
            2 => insert_bytes(rng, data),
            3 => delete_range(rng, data),
            4 => duplicate_range(rng, data),
            5 => splice(rng, data, other),
            6 => binary_number(rng, data),
            7 | 8 => text_number(rng, data),
            _ => structured(rng, data, target),
        };
    }
    data
}

fn flip_bit(rng: &mut SplitMix64, mut d: Vec<u8>) -> Vec<u8> {
    if !d.is_empty() {
        let i = rng.below(d.len());
        d[i] ^= 1 << rng.below(8);
    }
    d
}

fn set_byte(rng: &mut SplitMix64, mut d: Vec<u8>) -> Vec<u8> {
    if !d.is_empty() {
        let i = rng.below(d.len());
        let special = [
            0u8, 0xff, 0x7f, 0x80, b'"', b'[', b']', b'{', b'}', b'=', b'\n',
        ];
        d[i] = if rng.below(2) == 0 {
            special[rng.below(special.len())]
        } else {
            rng.next_u64() as u8
        };
    }
    d
}

fn insert_bytes(rng: &mut SplitMix64, mut d: Vec<u8>) -> Vec<u8> {
    let at = rng.below(d.len() + 1);
    let n = 1 + rng.below(8);
    let bytes: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
    d.splice(at..at, bytes);
    d
}

fn delete_range(rng: &mut SplitMix64, mut d: Vec<u8>) -> Vec<u8> {
    if !d.is_empty() {
        let at = rng.below(d.len());
        let n = 1 + rng.below((d.len() - at).min(64));
        d.drain(at..at + n);
    }
    d
}

fn duplicate_range(rng: &mut SplitMix64, mut d: Vec<u8>) -> Vec<u8> {
    if !d.is_empty() {
        let at = rng.below(d.len());
        let n = 1 + rng.below((d.len() - at).min(256));
        let chunk = d[at..at + n].to_vec();
        let to = rng.below(d.len() + 1);
        d.splice(to..to, chunk);
    }
    d
}

/// The start of one input joined to the end of another.
fn splice(rng: &mut SplitMix64, d: Vec<u8>, other: &[u8]) -> Vec<u8> {
    let cut = rng.below(d.len() + 1);
    let from = rng.below(other.len() + 1);
    let mut out = d[..cut].to_vec();
    out.extend_from_slice(&other[from..]);
    out
}

/// Overwrites 1, 2 or 4 bytes with an edge-case integer (little- or big-endian): lengths,
/// counts and offsets in GLB and PNG headers.
fn binary_number(rng: &mut SplitMix64, mut d: Vec<u8>) -> Vec<u8> {
    let values: [u32; 9] = [
        0,
        1,
        0x7f,
        0x80,
        0xff,
        0xffff,
        0x7fff_ffff,
        0x8000_0000,
        0xffff_ffff,
    ];
    let v = values[rng.below(values.len())];
    let width = [1, 2, 4][rng.below(3)];
    if d.len() >= width {
        let at = rng.below(d.len() - width + 1);
        let bytes = if rng.below(2) == 0 {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        };
        d[at..at + width].copy_from_slice(&bytes[..width]);
    }
    d
}

/// Replaces one run of digits in the text with an interesting number.
fn text_number(rng: &mut SplitMix64, mut d: Vec<u8>) -> Vec<u8> {
    let starts: Vec<usize> = (0..d.len())
        .filter(|&i| d[i].is_ascii_digit() && (i == 0 || !d[i - 1].is_ascii_digit()))
        .collect();
    if starts.is_empty() {
        return d;
    }
    let at = starts[rng.below(starts.len())];
    let end = (at..d.len())
        .find(|&i| !d[i].is_ascii_digit())
        .unwrap_or(d.len());
    let n = INTERESTING[rng.below(INTERESTING.len())];
    d.splice(at..end, n.bytes());
    d
}

/// Edits one value of a JSON (glTF) or TOML (scene) document and writes it back, so the input
/// stays parseable and reaches the checks behind the parser.
fn structured(rng: &mut SplitMix64, d: Vec<u8>, target: Target) -> Vec<u8> {
    match target {
        Target::Gltf | Target::Baseline | Target::Landmarks => {
            match serde_json::from_slice::<serde_json::Value>(&d) {
                Ok(mut v) => {
                    edit_json(rng, &mut v);
                    serde_json::to_vec(&v).unwrap_or(d)
                }
                Err(_) => d,
            }
        }
        Target::Scene => match std::str::from_utf8(&d)
            .ok()
            .and_then(|t| t.parse::<toml::Table>().ok())
        {
            Some(mut t) => {
                edit_toml(rng, &mut t);
                toml::to_string(&t).map(String::into_bytes).unwrap_or(d)
            }
            None => d,
        },
        _ => d,
    }
}

fn edit_json(rng: &mut SplitMix64, v: &mut serde_json::Value) {
    use serde_json::{json, Value};
    let children = match v {
        Value::Array(a) => a.len(),
        Value::Object(o) => o.len(),
        _ => 0,
    };
    // Go deeper most of the time; otherwise replace this value.
    if children > 0 && rng.below(4) != 0 {
        let k = rng.below(children);
        match v {
            Value::Array(a) => edit_json(rng, &mut a[k]),
            Value::Object(o) => {
                if rng.below(8) == 0 {
                    let key = o.keys().nth(k).cloned().unwrap_or_default();
                    o.remove(&key);
                } else if let Some((_, child)) = o.iter_mut().nth(k) {
                    edit_json(rng, child);
                }
            }
            _ => {}
        }
        return;
    }
    let n: i64 = [
        0, 1, -1, 2, 3, 4, 5, 7, 100, 5121, 5123, 5125, 5126, 65535, 4294967295,
    ][rng.below(15)];
    *v = match rng.below(7) {
        0 => json!(n),
        1 => json!(u64::MAX),
        2 => json!(1e38),
        3 => json!("../secret.bin"),
        4 => json!([n, n]),
        5 => Value::Null,
        _ => json!({}),
    };
}

fn edit_toml(rng: &mut SplitMix64, t: &mut toml::Table) {
    if t.is_empty() {
        return;
    }
    let k = rng.below(t.len());
    if let Some((_, v)) = t.iter_mut().nth(k) {
        edit_toml_value(rng, v);
    }
}

fn edit_toml_value(rng: &mut SplitMix64, v: &mut toml::Value) {
    use toml::Value;
    // Go deeper most of the time; otherwise replace this value.
    match v {
        Value::Table(inner) if !inner.is_empty() && rng.below(3) != 0 => {
            return edit_toml(rng, inner);
        }
        Value::Array(a) if !a.is_empty() && rng.below(3) != 0 => {
            let k = rng.below(a.len());
            return edit_toml_value(rng, &mut a[k]);
        }
        _ => {}
    }
    let n: i64 = [0, -1, 1, 2, 3, 1000, 1_000_000, i64::MAX, i64::MIN][rng.below(9)];
    *v = match rng.below(8) {
        0 => Value::Integer(n),
        1 => Value::Float(f64::NAN),
        2 => Value::Float(1e30),
        3 => Value::Float(-0.0),
        4 => Value::String("meshes/arrow.obj".into()),
        5 => Value::String("../meshes/pyramid.gltf".into()),
        6 => Value::Array(vec![Value::Integer(n); 3]),
        _ => Value::Boolean(true),
    };
}

/// A fault found: what happened and where the input was saved.
#[derive(Debug)]
pub struct Fault {
    pub kind: &'static str,
    pub message: String,
    pub saved: PathBuf,
}

#[derive(Debug, Default)]
pub struct Report {
    pub executions: u64,
    pub accepted: u64,
    pub seconds: f64,
    pub faults: Vec<Fault>,
}

impl Report {
    pub fn panics(&self) -> usize {
        self.faults.iter().filter(|f| f.kind == "panic").count()
    }
    pub fn hangs(&self) -> usize {
        self.faults.iter().filter(|f| f.kind == "hang").count()
    }
}

/// How a fuzz run is set up.
pub struct Config {
    pub target: Target,
    pub iterations: u64,
    pub seed: u64,
    /// An input still running after this long is a hang.
    pub time_limit: Duration,
    /// Where faulting inputs are written.
    pub out: PathBuf,
    /// Stop after this many hangs (each leaves a stuck worker thread behind).
    pub max_hangs: usize,
}

type Job = (Vec<u8>, PathBuf);
type Outcome = Result<bool, String>;

/// A thread that runs inputs under `catch_unwind` and answers with the outcome.
struct Worker {
    jobs: Sender<Job>,
    outcomes: Receiver<Outcome>,
}

impl Worker {
    fn start(target: Target, last_panic: Arc<Mutex<String>>) -> Worker {
        let (jobs, job_rx) = mpsc::channel::<Job>();
        let (out_tx, outcomes) = mpsc::channel();
        std::thread::Builder::new()
            .name(format!("fuzz-{}", target.name()))
            .spawn(move || {
                for (input, seed_path) in job_rx {
                    let r = panic::catch_unwind(AssertUnwindSafe(|| {
                        execute(target, &input, &seed_path)
                    }));
                    let outcome =
                        r.map_err(|_| last_panic.lock().map(|m| m.clone()).unwrap_or_default());
                    if out_tx.send(outcome).is_err() {
                        return;
                    }
                }
            })
            .expect("spawn a fuzz worker");
        Worker { jobs, outcomes }
    }
}

/// Runs `config.iterations` mutated inputs against `config.target`.
pub fn run(root: &Path, config: &Config, mut progress: impl FnMut(&Report)) -> Report {
    let seeds = seeds(root, config.target);
    assert!(!seeds.is_empty(), "no seeds for {}", config.target.name());
    // Panics are reported by the harness, not printed by the default hook on every hit.
    let last_panic = Arc::new(Mutex::new(String::new()));
    let hook_store = last_panic.clone();
    let previous = panic::take_hook();
    panic::set_hook(Box::new(move |info| {
        if let Ok(mut m) = hook_store.lock() {
            *m = info.to_string();
        }
    }));
    let mut worker = Worker::start(config.target, last_panic.clone());
    let mut rng = SplitMix64::new(config.seed);
    // Inputs that loaded cleanly, mutated further to reach deeper checks (bounded pool).
    let mut pool: Vec<Seed> = Vec::new();
    let mut report = Report::default();
    let start = Instant::now();
    for i in 0..config.iterations {
        let base = if !pool.is_empty() && rng.below(4) == 0 {
            &pool[rng.below(pool.len())]
        } else {
            &seeds[rng.below(seeds.len())]
        };
        let other = &seeds[rng.below(seeds.len())].bytes;
        let input = mutate(&mut rng, &base.bytes, other, config.target);
        let seed_path = base.path.clone();
        worker
            .jobs
            .send((input.clone(), seed_path.clone()))
            .expect("worker alive");
        report.executions += 1;
        match worker.outcomes.recv_timeout(config.time_limit) {
            Ok(Ok(accepted)) => {
                if accepted {
                    report.accepted += 1;
                    if pool.len() < 256 {
                        pool.push(Seed {
                            path: seed_path,
                            bytes: input,
                        });
                    } else {
                        let k = rng.below(pool.len());
                        pool[k] = Seed {
                            path: seed_path,
                            bytes: input,
                        };
                    }
                }
            }
            Ok(Err(message)) => report
                .faults
                .push(save(config, "panic", i, &input, &seed_path, message)),
            Err(RecvTimeoutError::Timeout) | Err(RecvTimeoutError::Disconnected) => {
                let message = format!("still running after {:?}", config.time_limit);
                report
                    .faults
                    .push(save(config, "hang", i, &input, &seed_path, message));
                if report.hangs() >= config.max_hangs {
                    break;
                }
                // The stuck thread cannot be stopped; leave it and carry on with a new one.
                worker = Worker::start(config.target, last_panic.clone());
            }
        }
        if i % 10_000 == 9_999 {
            report.seconds = start.elapsed().as_secs_f64();
            progress(&report);
        }
    }
    report.seconds = start.elapsed().as_secs_f64();
    panic::set_hook(previous);
    report
}

/// Writes a faulting input (and a note naming its seed and message) under `config.out`.
fn save(
    config: &Config,
    kind: &'static str,
    i: u64,
    input: &[u8],
    seed: &Path,
    message: String,
) -> Fault {
    let _ = std::fs::create_dir_all(&config.out);
    let name = format!("{}-{kind}-{}-{i}", config.target.name(), config.seed);
    let saved = config
        .out
        .join(format!("{name}.{}", config.target.extension()));
    let _ = std::fs::write(&saved, input);
    let note = format!("seed file: {}\n{message}\n", seed.display());
    let _ = std::fs::write(config.out.join(format!("{name}.txt")), note);
    Fault {
        kind,
        message,
        saved,
    }
}
