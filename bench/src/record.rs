//! The benchmark's record: what `--json` writes and `--baseline` reads, as typed structs, so
//! that the writer, the gate, the table, the CSV, the plot and the github array all name the
//! same fields through the compiler (a misspelt key cannot silently change a verdict).
//!
//! Reading is strict: every struct refuses keys it does not know, and [`read`] refuses a file
//! that lacks any key the record has (`null` stands for an absent value, and must be written).
//! The layout is documented in docs/benchmarks.md ("Output").

use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use specchio::files::read_regular_file;
use specchio::reference::angular::AngularError;
use specchio::reference::ReferenceStats;
use specchio::render::floors::Floor;
use specchio::render::methods::Method;
use specchio::scene::Lookup;
use specchio::vk::device::DeviceInfo;
use specchio::vk::queries::PipelineStats;

/// Everything one `specchio bench` run measured, with its provenance.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    pub specchio_version: String,
    pub command: String,
    /// None outside a git checkout or without git.
    pub git: Option<Git>,
    pub device: DeviceInfo,
    pub llvm_version: Option<String>,
    pub environment: Environment,
    pub settings: Settings,
    pub peak_rss_bytes: Option<u64>,
    pub methods_not_run: Vec<NotRun>,
    pub results: Vec<MethodRow>,
    pub floors: Vec<FloorRow>,
    pub accuracy: Vec<Accuracy>,
    pub references: Vec<ReferenceRow>,
    pub speed_vs_error: Vec<SpeedVsError>,
    /// The trade-off ladder: every rung's frame cost and error (docs/benchmarks.md).
    pub tradeoff: Vec<RungRow>,
    pub rungs_not_run: Vec<RungNotRun>,
    pub dynamic: Vec<Dynamic>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Git {
    pub commit: String,
    /// Whether tracked files differed from the commit (None when git could not say).
    pub modified: Option<bool>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Environment {
    pub lp_num_threads: Option<String>,
    pub malloc_trim_threshold_bytes: Option<i32>,
    pub cpus: Option<usize>,
}

/// The options the run used, after `--quick` and the defaults.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    pub scenes: Vec<String>,
    pub methods: Vec<Method>,
    pub cube_sizes: Vec<u32>,
    pub lookups: Vec<Lookup>,
    /// The trade-off rungs asked for (by label; empty with `--no-tradeoff`).
    pub rungs: Vec<String>,
    pub frames: u32,
    pub warmup: u32,
    pub runs: u32,
    /// Frames each method kept in flight in its throughput timing (`results[].in_flight_ms`);
    /// absent in records from before it was measured.
    #[serde(default)]
    pub frames_in_flight: Option<u32>,
    pub quick: bool,
    /// `--full`'s defaults.
    pub full: bool,
    /// The tracing rungs' build order (`--trace-order`: split or given).
    pub trace_order: String,
    /// Where the tracing rungs walked their rays (`--trace-in`), when it was given; else the
    /// device's default (`TraceIn::default_for`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace_in: Option<String>,
    /// The layout the bvh rung's trees had (`--bvh-layout`, else the device's default): its
    /// work counters are that layout's. Absent in records from before it could be chosen
    /// (all cwbvh).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bvh_layout: Option<String>,
    pub dynamic_cube_size: u32,
    pub refresh: String,
}

/// A method the device cannot run, and why.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NotRun {
    pub method: Method,
    pub reason: String,
}

/// Median, 10th and 90th percentile (nearest rank, `specchio::metrics::percentile`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stats {
    pub median: f64,
    pub p10: f64,
    pub p90: f64,
}

impl Stats {
    /// None for no values (the record then says `null`).
    pub fn of(mut values: Vec<f64>) -> Option<Stats> {
        use specchio::metrics::percentile::percentile;
        Some(Stats {
            median: percentile(&mut values, 0.5)?,
            p10: percentile(&mut values, 0.1)?,
            p90: percentile(&mut values, 0.9)?,
        })
    }
}

/// One method on one scene at one face size: the row the gate compares.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodRow {
    pub scene: String,
    pub method: Method,
    pub cube_size: u32,
    pub updates: usize,
    pub wall_ms: Option<Stats>,
    pub run_medians_ms: Vec<f64>,
    /// Wall time per frame with `settings.frames_in_flight` frames in flight: the frames
    /// submitted back to back, from the first submission to the last frame finished, one
    /// value per run (its throughput, where `wall_ms` times each frame alone). Absent in
    /// records from before it was measured.
    #[serde(default)]
    pub in_flight_ms: Option<Stats>,
    pub cpu_record_ms: Option<Stats>,
    pub gpu_fill_ms: Option<Stats>,
    pub gpu_fill_and_mips_ms: Option<Stats>,
    /// Per face, six-pass only (the one-pass methods have no per-face timestamps).
    pub gpu_face_ms: Option<Vec<Option<Stats>>>,
    /// The last update's counters (None without pipeline statistics).
    pub fill_stats: Option<PipelineStats>,
    pub triangles: usize,
    pub objects: usize,
    pub work: Work,
    pub efficiency: Efficiency,
}

impl MethodRow {
    /// The case the row is for, as the gate names it.
    pub fn case(&self) -> String {
        format!("{} / {} / {}²", self.scene, self.method, self.cube_size)
    }
}

/// Work counters summed over the timed updates; a counter the driver lacks is None (null).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Work {
    pub vertex_invocations: Option<u64>,
    pub clipping_primitives: Option<u64>,
    pub fragment_invocations: Option<u64>,
    pub task_invocations: Option<u64>,
    pub mesh_invocations: Option<u64>,
    pub faces_rendered: u64,
    pub objects_drawn: u64,
}

impl Work {
    /// Every counter with its name (the names only label the gate's messages).
    pub fn counters(&self) -> [(&'static str, Option<u64>); 7] {
        [
            ("vertex_invocations", self.vertex_invocations),
            ("clipping_primitives", self.clipping_primitives),
            ("fragment_invocations", self.fragment_invocations),
            ("task_invocations", self.task_invocations),
            ("mesh_invocations", self.mesh_invocations),
            ("faces_rendered", Some(self.faces_rendered)),
            ("objects_drawn", Some(self.objects_drawn)),
        ]
    }
}

/// A method's median over its floors' medians (None without floors).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Efficiency {
    pub vs_geometry_plus_fill: Option<f64>,
    pub vs_clear: Option<f64>,
}

/// One floor on one scene at one face size.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FloorRow {
    pub scene: String,
    pub floor: Floor,
    pub cube_size: u32,
    pub updates: usize,
    pub wall_ms: Option<Stats>,
    pub run_medians_ms: Vec<f64>,
    pub gpu_fill_ms: Option<Stats>,
    pub fill_stats: Option<PipelineStats>,
}

/// The error of one scene, face size and lookup mode (the same for every method: see
/// `methods_identical`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Accuracy {
    pub scene: String,
    pub cube_size: u32,
    pub lookup: Lookup,
    /// Which image: the sensor view (the catadioptric camera).
    pub camera: String,
    pub flip_mean: Option<f64>,
    pub flip_p99: Option<f64>,
    pub rmse: Option<f64>,
    /// NaN or Inf pixels in the rasterized image (0 expected).
    pub non_finite_pixels: u64,
    /// Angle between the direction each mirror pixel looked up and the exact one.
    pub angular: AngularError,
    /// Whether every method gave the same sensor image, bit for bit.
    pub methods_identical: bool,
}

/// The exact reference traced for a scene's error measurement.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceRow {
    pub scene: String,
    pub time_s: f64,
    pub camera: String,
    pub spp: u32,
    pub stats: ReferenceStats,
}

/// A method's time beside the error of its face size and lookup.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedVsError {
    pub result: MethodRow,
    pub accuracy: Accuracy,
}

/// One rung of the trade-off ladder on one scene at one face size: what a sensor frame costs
/// with it and how far its views are from the exact reference.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RungRow {
    pub scene: String,
    pub cube_size: u32,
    /// The rung's label (`box`, `ray-query`, ...), unique in the ladder.
    pub rung: String,
    /// Its lookup; null for the host's tracer (`cpu`), which draws nothing on the device.
    pub lookup: Option<Lookup>,
    /// Timed frames (all at t = 0, the frame whose error is measured).
    pub frames: usize,
    /// Per frame, the GPU time of the cube's update (six-pass fill of all six faces plus
    /// mips; for ray-query, the top-level acceleration structure's rebuild) plus the sensor
    /// view (scene and mirror), plus the host time of the lookup's own per-frame work (the
    /// bvh lookup's top-level rebuild): what the sensor frame costs. None without timestamps.
    /// For the host's tracer (`cpu`): its whole frame's wall time (its BVH built, the sensor
    /// traced).
    pub frame_cost_ms: Option<Stats>,
    /// Its parts (the host's tracer has no GPU parts).
    pub gpu_cube_ms: Option<Stats>,
    pub gpu_sensor_ms: Option<Stats>,
    /// The host's part: the lookup's per-frame work, or the host tracer's BVH build.
    pub cpu_lookup_ms: Option<Stats>,
    /// Submit to fence of the whole frame (observer, sensor, the pair and readback included).
    pub wall_ms: Option<Stats>,
    pub work: RungWork,
    /// Of the sensor's mirror fragments over the timed frames, the share whose ray the lookup
    /// traced (only `distance-exact`: the rays its search could not resolve).
    pub sensor_traced_fraction: Option<f64>,
    /// Error against the reference at 1 sample per pixel (None with `--no-accuracy`).
    pub sensor: Option<ViewError>,
    pub observer: Option<ViewError>,
    /// On the Pareto front of frame cost against sensor mean FLIP among the rungs of the same
    /// scene and face size (None when either is unmeasured).
    pub pareto: Option<bool>,
}

impl RungRow {
    /// The case the row is for, as the gate names it.
    pub fn case(&self) -> String {
        format!("{} / rung {} / {}²", self.scene, self.rung, self.cube_size)
    }
}

/// A rung's work counters summed over its timed frames; None where the driver has no
/// pipeline statistics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RungWork {
    /// Faces the cube fill drew (0 for a lookup that reads no cube map).
    pub faces_rendered: u64,
    pub fill_vertex_invocations: Option<u64>,
    pub fill_fragment_invocations: Option<u64>,
    /// Fragment shader invocations of the sensor view (its scene draws and the mirror).
    pub sensor_fragment_invocations: Option<u64>,
    /// For a lookup that counts its trace's work (`bvh`): its sensor frame's walk, counted on
    /// the CPU step for step as the shader walks (exact, the same on every device), summed
    /// over the timed frames: rays, nodes fetched, objects entered, triangles tested. None
    /// for the other lookups.
    pub trace: Option<specchio::bvh::Work>,
}

impl RungWork {
    /// Every counter with its name (the names only label the gate's messages).
    pub fn counters(&self) -> [(&'static str, Option<u64>); 8] {
        let trace = |f: fn(&specchio::bvh::Work) -> u64| self.trace.as_ref().map(f);
        [
            ("faces_rendered", Some(self.faces_rendered)),
            ("fill_vertex_invocations", self.fill_vertex_invocations),
            ("fill_fragment_invocations", self.fill_fragment_invocations),
            (
                "sensor_fragment_invocations",
                self.sensor_fragment_invocations,
            ),
            ("trace_rays", trace(|t| t.rays)),
            ("trace_nodes", trace(|t| t.nodes)),
            ("trace_instances", trace(|t| t.instances)),
            ("trace_triangles", trace(|t| t.triangles)),
        ]
    }
}

/// One view's error against the reference's image of the same view and instant.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewError {
    pub flip_mean: Option<f64>,
    pub flip_p99: Option<f64>,
    /// NaN or Inf pixels in the rasterized image (0 expected).
    pub non_finite_pixels: u64,
    /// Angle between the direction each mirror pixel looked up and the exact one.
    pub angular: AngularError,
}

/// A rung the device cannot run, and why.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RungNotRun {
    pub rung: String,
    pub reason: String,
}

/// One frame of an animated scene under the three updates: faces and texels re-rendered and
/// submit-to-fence times.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicFrame {
    pub time_s: f64,
    /// Faces the incremental updates re-render (the same for rectangles and whole faces).
    pub faces_incremental: u32,
    pub faces_full: u32,
    /// Texels the dirty rectangles re-render (a full update: six faces' worth).
    pub texels_rects: u64,
    pub texels_full: u64,
    pub rects_ms: f64,
    pub whole_faces_ms: f64,
    pub full_ms: f64,
}

/// Incremental against full updates of one animated scene: only the dirty rectangles of the
/// dirty faces, the dirty faces whole, all six faces.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dynamic {
    pub scene: String,
    pub method: Method,
    pub cube_size: u32,
    /// Scene time of the measurement's first frame, a warm-up (`--dynamic-from`).
    pub from_s: f64,
    pub frames: Vec<DynamicFrame>,
    /// Over the frames where something moved (full update ran): medians, and the ratios of
    /// the medians to the full update's; null where nothing moved (they were 0.00 ms).
    pub changed_frames: usize,
    pub faces_incremental_median: Option<f64>,
    pub texels_rects_median: Option<f64>,
    pub rects_ms_median: Option<f64>,
    pub whole_faces_ms_median: Option<f64>,
    pub full_ms_median: Option<f64>,
    /// Rectangles over full (time).
    pub ratio: Option<f64>,
    /// Whole dirty faces over full (time).
    pub whole_faces_ratio: Option<f64>,
    /// Rectangles' texels over full's.
    pub texels_ratio: Option<f64>,
}

impl Dynamic {
    /// The row as the gate names it.
    pub fn case(&self) -> String {
        let from = specchio::text::num_text(self.from_s);
        format!("{} / dynamic {}² from {from} s", self.scene, self.cube_size)
    }

    /// The work counters summed over the frames: faces and texels of the incremental and the
    /// full updates (the dirty rectangles' and the whole faces' faces are the same).
    pub fn counters(&self) -> [(&'static str, Option<u64>); 4] {
        let sum = |f: fn(&DynamicFrame) -> u64| Some(self.frames.iter().map(f).sum());
        [
            ("faces_incremental", sum(|f| u64::from(f.faces_incremental))),
            ("faces_full", sum(|f| u64::from(f.faces_full))),
            ("texels_rects", sum(|f| f.texels_rects)),
            ("texels_full", sum(|f| f.texels_full)),
        ]
    }
}

/// Largest `--baseline` record read (bytes): the full sweep's record is well under 1 MiB.
pub const MAX_RECORD_BYTES: u64 = 64 << 20;

/// Reads a `specchio bench --json` file: refused, naming the file and the key, when a key is
/// unknown (misspelt), missing, or of the wrong type.
pub fn read(path: &Path) -> Result<Record> {
    let bytes = read_regular_file(path, MAX_RECORD_BYTES)
        .with_context(|| format!("cannot read the baseline {}", path.display()))?;
    let text = String::from_utf8(bytes)
        .with_context(|| format!("the baseline {} is not UTF-8 text", path.display()))?;
    parse(&text).with_context(|| {
        format!(
            "{}: not a `specchio bench --json` record of this version (regenerate it: see \
             docs/benchmarks.md, \"The regression gate\")",
            path.display()
        )
    })
}

/// [`read`] on text.
pub fn parse(text: &str) -> Result<Record> {
    // A key written twice is refused first (serde_json would keep the last one); a value of
    // the wrong type is named by its path (`settings.frames`), serde's message alone gives
    // only the line and column.
    let raw: Value = specchio::files::json::parse_unique_keys(text)?;
    let record: Record = serde_path_to_error::deserialize(&mut serde_json::Deserializer::from_str(
        text,
    ))
    .map_err(|e| match e.path().to_string().as_str() {
        "." => anyhow::anyhow!("{}", e.inner()),
        path => anyhow::anyhow!("{path}: {}", e.inner()),
    })?;
    // serde fills a missing `Option` with None; the record writes every key, so a missing
    // one is a damaged or hand-edited file, not an absent value.
    if let Some(key) = first_missing(&raw, &serde_json::to_value(&record)?, "") {
        anyhow::bail!("key `{key}` is missing (write `null` for an absent value)");
    }
    Ok(record)
}

/// The first key (as a path such as `results[0].work.vertex_invocations`) that `typed` has
/// and `raw` lacks.
fn first_missing(raw: &Value, typed: &Value, at: &str) -> Option<String> {
    match (raw, typed) {
        (Value::Object(raw), Value::Object(typed)) => typed.iter().find_map(|(k, t)| {
            let here = if at.is_empty() {
                k.clone()
            } else {
                format!("{at}.{k}")
            };
            match raw.get(k) {
                None => Some(here),
                Some(r) => first_missing(r, t, &here),
            }
        }),
        (Value::Array(raw), Value::Array(typed)) => raw
            .iter()
            .zip(typed)
            .enumerate()
            .find_map(|(i, (r, t))| first_missing(r, t, &format!("{at}[{i}]"))),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASELINE: &str = include_str!("../baselines/quick.json");

    #[test]
    fn the_committed_baseline_reads_and_writes_back_the_same_json() {
        let record = parse(BASELINE).expect("bench/baselines/quick.json is a record");
        assert!(!record.results.is_empty());
        let raw: Value = serde_json::from_str(BASELINE).unwrap();
        assert_eq!(serde_json::to_value(&record).unwrap(), raw);
    }

    #[test]
    fn a_misspelt_key_is_refused_and_named() {
        let bad = BASELINE.replacen("\"fragment_invocations\"", "\"fragment_invocatons\"", 1);
        let e = format!("{:#}", parse(&bad).unwrap_err());
        assert!(
            e.contains("unknown field `fragment_invocatons`") && e.contains("line"),
            "{e}"
        );
    }

    /// A value of the wrong type is named by its path, not only by a column of a one-line file.
    #[test]
    fn a_value_of_the_wrong_type_is_named_by_its_path() {
        let mut raw: Value = serde_json::from_str(BASELINE).unwrap();
        raw["settings"]["frames"] = Value::String("5".into());
        let e = format!("{:#}", parse(&raw.to_string()).unwrap_err());
        assert!(
            e.starts_with("settings.frames: invalid type: string \"5\""),
            "{e}"
        );
        let mut raw: Value = serde_json::from_str(BASELINE).unwrap();
        raw["results"][1]["work"]["vertex_invocations"] = Value::Bool(true);
        let e = format!("{:#}", parse(&raw.to_string()).unwrap_err());
        assert!(
            e.starts_with("results[1].work.vertex_invocations: invalid type"),
            "{e}"
        );
    }

    /// serde_json keeps the last of two equal keys: a hand-edited baseline with a time
    /// written twice is refused, naming the key and its line.
    #[test]
    fn a_key_written_twice_is_refused_and_named() {
        let bad = BASELINE.replacen("\"updates\": 5", "\"updates\": 5, \"updates\": 7", 1);
        assert_ne!(bad, BASELINE);
        let e = format!("{:#}", parse(&bad).unwrap_err());
        assert!(
            e.contains("`updates` is written twice") && e.contains("line"),
            "{e}"
        );
    }

    #[test]
    fn a_missing_key_is_refused_and_named() {
        // An optional counter: serde alone would read its absence as null.
        let mut raw: Value = serde_json::from_str(BASELINE).unwrap();
        raw["results"][1]["work"]
            .as_object_mut()
            .unwrap()
            .remove("vertex_invocations");
        let e = format!("{:#}", parse(&raw.to_string()).unwrap_err());
        assert!(e.contains("`results[1].work.vertex_invocations`"), "{e}");
        // A required one.
        let mut raw: Value = serde_json::from_str(BASELINE).unwrap();
        raw["results"][0].as_object_mut().unwrap().remove("updates");
        let e = format!("{:#}", parse(&raw.to_string()).unwrap_err());
        assert!(e.contains("missing field `updates`"), "{e}");
    }

    #[test]
    fn a_wrong_type_or_unknown_method_is_refused() {
        let bad = BASELINE.replacen("\"method\": \"six-pass\"", "\"method\": \"nine-pass\"", 1);
        let e = format!("{:#}", parse(&bad).unwrap_err());
        assert!(e.contains("unknown method `nine-pass`"), "{e}");
        let bad = BASELINE.replacen("\"updates\": 5", "\"updates\": \"5\"", 1);
        assert!(parse(&bad).is_err());
    }

    #[test]
    fn stats_use_the_nearest_rank() {
        let s = Stats::of((1..=10).map(f64::from).collect()).unwrap();
        assert_eq!((s.median, s.p10, s.p90), (5.0, 1.0, 9.0));
        assert_eq!(Stats::of(Vec::new()), None);
    }
}
