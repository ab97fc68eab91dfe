//! The benchmark's Bencher Metric Format (BMF) output: the record's times and errors as the JSON
//! object that Bencher's `json` adapter reads (`bencher run --adapter json`), so that a run can be
//! tracked commit by commit on bencher.dev, beside the github-action-benchmark array
//! ([`super::report::github`]).
//!
//! BMF (<https://bencher.dev/docs/reference/bencher-metric-format/>, schema
//! <https://bencher.dev/bmf.json>) is one object: benchmark name -> measure -> metric, the metric
//! `{ "value", "lower_value", "upper_value" }` with only `value` required. Bencher creates a
//! benchmark or a measure it has not seen when the report is uploaded; a measure created that way
//! is named by its slug and gets a generic placeholder unit (Bencher's
//! `services/api/src/model/project/measure.rs`), so each slug here says its unit itself.
//!
//! # Benchmarks
//!
//! One per scene, case, cube face size and device, the four parts joined by `/`, each part a slug
//! (lower-case ASCII letters and digits, single hyphens), so that a name stays the same when a
//! scene's folder, a driver's version or a letter's case changes:
//!
//! - a fill method: `{scene}/{method}/{size}/{device}`, e.g. `many-objects/six-pass/512/llvmpipe`;
//! - a trade-off rung: `{scene}/rung-{label}/{size}/{device}`, e.g.
//!   `many-objects/rung-ray-query/512/llvmpipe` (`rung-`, as the gate says `rung ray-query`, keeps
//!   a rung apart from a method: a rung's cost is a whole sensor frame, not a fill);
//! - an animated scene's on-change updates (`dynamic`): `{scene}/update-{kind}/{size}/{device}`,
//!   `kind` one of `rects` (dirty rectangles), `whole-faces`, `full`, e.g.
//!   `many-objects/update-rects/512/llvmpipe`.
//!
//! `{scene}` is the scene file's stem (`scenes/many-objects.toml` -> `many-objects`); `{size}` the
//! face size in pixels; `{device}` the Vulkan device name up to its first ` (`, where drivers put
//! versions and build details (`llvmpipe (LLVM 15.0.6, 256 bits)` -> `llvmpipe`,
//! `AMD Radeon RX 7900 XTX (RADV NAVI31)` -> `amd-radeon-rx-7900-xtx`). Two rows that would get
//! one name (two scenes `a/room.toml` and `b/room.toml`) are an error, never one overwriting the
//! other.
//!
//! # Measures
//!
//! | slug | of | value | lower_value, upper_value | unit |
//! |---|---|---|---|---|
//! | `cube-update-ms` | a fill method's cube update: all six faces and the mips, submit to fence (`results[].wall_ms`) | median | p10, p90 | milliseconds |
//! | `cube-update-in-flight-ms` | the same updates submitted back to back with `settings.frames_in_flight` in flight: wall time per update (`results[].in_flight_ms`, one value per run) | median | p10, p90 | milliseconds |
//! | `frame-cost-ms` | a rung's time per sensor frame: cube update plus sensor view on the GPU, plus the lookup's host work; the `cpu` rung's whole frame on the host (`tradeoff[].frame_cost_ms`) | median | p10, p90 | milliseconds |
//! | `sensor-flip-mean` | a rung's sensor image against the exact reference at t = 0, 1 sample per pixel (`tradeoff[].sensor.flip_mean`) | mean FLIP | - | FLIP, 0 (identical) to 1 |
//! | `update-ms` | an animated scene's on-change update of that kind, submit to fence, over the frames with motion (`dynamic[].frames[].rects_ms`, `whole_faces_ms`, `full_ms`) | median | p10, p90 | milliseconds |
//! | `texels-rendered` | the texels that update re-rendered (`texels_rects`, `texels_full`; whole faces: faces × size²) | median | p10, p90 | texels |
//! | `trace-nodes-per-ray` | a traced rung's walk over its sensor frame at t = 0 (`bvh`): tree nodes fetched per ray, both levels (`tradeoff[].work.trace`) | exact count / rays | - | nodes per ray |
//! | `trace-objects-per-ray` | the same walk's objects entered per ray | exact count / rays | - | objects per ray |
//! | `trace-triangles-per-ray` | the same walk's triangles tested per ray | exact count / rays | - | triangles per ray |
//!
//! Smaller is better for all nine. The three walk counts are exact and the same on every
//! machine (counted on the CPU by the shader's own walk), so a change in them is a change in
//! the trees or the walk, never noise: a tracker can hold them to a zero threshold. The times
//! stay in milliseconds, not Bencher's built-in `latency` (nanoseconds): the record and every other output are in milliseconds, and the two
//! times are different quantities (a wall time of the fill alone; GPU timestamps of a whole
//! sensor frame) that should not share one measure, one plot axis and one threshold.
//!
//! A measure is written only when its numbers are finite (and, for a median with its
//! percentiles, ordered p10 <= median <= p90): JSON has no NaN, serde_json would write `null`,
//! and Bencher refuses a report whose `value` is not a number. A row with no measure left is
//! not written at all.
//!
//! # Left out
//!
//! Rays per second of the tracing rungs: the record cannot give it honestly. It keeps
//! `sensor_traced_fraction` (a share, `distance-exact` only; `ray-query` keeps no tally), not the
//! sensor's mirror fragments and traced rays it came from, and no GPU time of the mirror draw
//! alone (`frame_cost_ms` includes the cube update and the sensor's scene draws). See
//! docs/benchmarks.md, "Bencher Metric Format".

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};
use specchio::vk::device::DeviceInfo;

use super::record::{Dynamic, DynamicFrame, Record, Stats};

#[cfg(test)]
mod tests;
#[cfg(test)]
mod validator;

/// A measure this output writes (the table in the module's documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// A fill method's cube update, milliseconds.
    CubeUpdateMs,
    /// A fill method's cube update among others in flight, milliseconds per update.
    CubeUpdateInFlightMs,
    /// A rung's GPU time per sensor frame, milliseconds.
    FrameCostMs,
    /// A rung's sensor mean FLIP against the exact reference (0 to 1).
    SensorFlipMean,
    /// An animated scene's on-change update, milliseconds.
    UpdateMs,
    /// The texels that update re-rendered.
    TexelsRendered,
    /// A traced rung's tree nodes fetched per sensor ray.
    TraceNodesPerRay,
    /// A traced rung's objects entered per sensor ray.
    TraceObjectsPerRay,
    /// A traced rung's triangles tested per sensor ray.
    TraceTrianglesPerRay,
}

impl Measure {
    /// Every measure (the tests check the documentation's table against it).
    #[cfg(test)]
    pub const ALL: [Measure; 9] = [
        Measure::CubeUpdateMs,
        Measure::CubeUpdateInFlightMs,
        Measure::FrameCostMs,
        Measure::SensorFlipMean,
        Measure::UpdateMs,
        Measure::TexelsRendered,
        Measure::TraceNodesPerRay,
        Measure::TraceObjectsPerRay,
        Measure::TraceTrianglesPerRay,
    ];

    /// The key under a benchmark, and the measure's slug in Bencher.
    pub fn slug(self) -> &'static str {
        match self {
            Measure::CubeUpdateMs => "cube-update-ms",
            Measure::CubeUpdateInFlightMs => "cube-update-in-flight-ms",
            Measure::FrameCostMs => "frame-cost-ms",
            Measure::SensorFlipMean => "sensor-flip-mean",
            Measure::UpdateMs => "update-ms",
            Measure::TexelsRendered => "texels-rendered",
            Measure::TraceNodesPerRay => "trace-nodes-per-ray",
            Measure::TraceObjectsPerRay => "trace-objects-per-ray",
            Measure::TraceTrianglesPerRay => "trace-triangles-per-ray",
        }
    }
}

/// One measure's numbers. Only the constructors make one, and they refuse what BMF cannot carry
/// (a non-finite number) or should not (bounds on the wrong side of the value).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Metric {
    value: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lower_value: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    upper_value: Option<f64>,
}

impl Metric {
    /// A value alone (None unless finite).
    pub fn single(value: f64) -> Option<Metric> {
        value.is_finite().then_some(Metric {
            value,
            lower_value: None,
            upper_value: None,
        })
    }

    /// The median, bounded by the 10th and 90th percentiles (None unless all three are finite
    /// and in order).
    pub fn spread(s: Stats) -> Option<Metric> {
        let finite = [s.p10, s.median, s.p90].iter().all(|x| x.is_finite());
        (finite && s.p10 <= s.median && s.median <= s.p90).then_some(Metric {
            value: s.median,
            lower_value: Some(s.p10),
            upper_value: Some(s.p90),
        })
    }
}

/// A BMF document: benchmark name -> measure slug -> metric. Sorted maps, so that two runs list
/// their benchmarks in the same order and their files diff line by line.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Bmf(pub BTreeMap<String, BTreeMap<String, Metric>>);

/// The BMF document of a run: every fill method's cube update time and every rung's frame cost,
/// sensor error and (traced rungs) walk per ray, named as the module's documentation says. An
/// error when two rows would share a benchmark name.
pub fn bmf(record: &Record) -> Result<Bmf> {
    let device = device_slug(&record.device);
    let mut out = Builder::default();
    for r in &record.results {
        let name = benchmark_name(&r.scene, r.method.name(), r.cube_size, &device);
        let measures = out.claim(name, r.case())?;
        put(
            measures,
            Measure::CubeUpdateMs,
            r.wall_ms.and_then(Metric::spread),
        );
        put(
            measures,
            Measure::CubeUpdateInFlightMs,
            r.in_flight_ms.and_then(Metric::spread),
        );
    }
    for r in &record.tradeoff {
        let case = format!("rung-{}", r.rung);
        let name = benchmark_name(&r.scene, &case, r.cube_size, &device);
        let measures = out.claim(name, r.case())?;
        put(
            measures,
            Measure::FrameCostMs,
            r.frame_cost_ms.and_then(Metric::spread),
        );
        let flip = r.sensor.as_ref().and_then(|v| v.flip_mean);
        put(
            measures,
            Measure::SensorFlipMean,
            flip.and_then(Metric::single),
        );
        if let Some(t) = &r.work.trace {
            // No ray, no ratio: 0/0 is NaN, which `single` refuses.
            let per_ray = |count: u64| Metric::single(count as f64 / t.rays as f64);
            put(measures, Measure::TraceNodesPerRay, per_ray(t.nodes));
            put(measures, Measure::TraceObjectsPerRay, per_ray(t.instances));
            put(
                measures,
                Measure::TraceTrianglesPerRay,
                per_ray(t.triangles),
            );
        }
    }
    for d in &record.dynamic {
        dynamic(&mut out, d, &device)?;
    }
    let mut bmf = out.bmf;
    bmf.0.retain(|_, measures| !measures.is_empty());
    Ok(bmf)
}

/// An animated scene's three kinds of update: each one's time and texels per frame with motion.
fn dynamic(out: &mut Builder, d: &Dynamic, device: &str) -> Result<()> {
    let moved: Vec<&DynamicFrame> = d.frames.iter().filter(|f| f.faces_full > 0).collect();
    let face = f64::from(d.cube_size) * f64::from(d.cube_size);
    type Of = fn(&DynamicFrame, f64) -> (f64, f64);
    let kinds: [(&str, Of); 3] = [
        ("rects", |f, _| (f.rects_ms, f.texels_rects as f64)),
        ("whole-faces", |f, face| {
            (f.whole_faces_ms, f64::from(f.faces_incremental) * face)
        }),
        ("full", |f, _| (f.full_ms, f.texels_full as f64)),
    ];
    for (kind, of) in kinds {
        let name = benchmark_name(&d.scene, &format!("update-{kind}"), d.cube_size, device);
        let measures = out.claim(name, format!("{} update-{kind}", d.scene))?;
        let (ms, texels): (Vec<f64>, Vec<f64>) = moved.iter().map(|f| of(f, face)).unzip();
        let spread = |v: Vec<f64>| Stats::of(v).and_then(Metric::spread);
        put(measures, Measure::UpdateMs, spread(ms));
        put(measures, Measure::TexelsRendered, spread(texels));
    }
    Ok(())
}

/// The BMF text: pretty-printed with a final newline, as `--json` writes the record.
pub fn json(bmf: &Bmf) -> Result<String> {
    Ok(serde_json::to_string_pretty(bmf)? + "\n")
}

/// `{scene}/{case}/{size}/{device}` (see the module's documentation); `device` is already a
/// slug ([`device_slug`]).
pub fn benchmark_name(scene: &str, case: &str, cube_size: u32, device: &str) -> String {
    format!("{}/{}/{cube_size}/{device}", scene_slug(scene), slug(case))
}

/// The scene part of a benchmark name: the file's stem as a slug (`scenes/heavy.toml` ->
/// `heavy`). Exposed so that the options can refuse two scenes with one stem before the run.
pub fn scene_slug(scene: &str) -> String {
    let stem = Path::new(scene)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    first_slug(&[&stem, scene]).unwrap_or_else(|| "scene".to_owned())
}

/// The device part of a benchmark name: the device name up to its first ` (` as a slug; the
/// whole name, then the driver's short name, where that leaves nothing.
pub fn device_slug(device: &DeviceInfo) -> String {
    // `split` yields at least one piece, the whole name when it has no ` (`.
    let head = device.name.split(" (").next().unwrap_or_default();
    first_slug(&[head, &device.name, &device.short_name]).unwrap_or_else(|| "device".to_owned())
}

/// The first of `texts` whose slug is not empty.
fn first_slug(texts: &[&str]) -> Option<String> {
    texts.iter().map(|t| slug(t)).find(|s| !s.is_empty())
}

/// `text` as a slug: ASCII letters and digits lower-cased, each run of anything else one hyphen,
/// none at either end; Bencher's own slugs have the same form (`lib/bencher_valid/src/slug.rs`).
fn slug(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut gap = false;
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            if gap && !out.is_empty() {
                out.push('-');
            }
            out.push(c.to_ascii_lowercase());
            gap = false;
        } else {
            gap = true;
        }
    }
    out
}

/// `metric` under `measure`'s slug, when there is one.
fn put(measures: &mut BTreeMap<String, Metric>, measure: Measure, metric: Option<Metric>) {
    if let Some(m) = metric {
        measures.insert(measure.slug().to_owned(), m);
    }
}

/// The document being built, and which row claimed each benchmark name.
#[derive(Default)]
struct Builder {
    bmf: Bmf,
    /// Name -> the row's case as the gate names it (for the error).
    claimed: BTreeMap<String, String>,
}

impl Builder {
    /// The measures of the new benchmark `name`, for the row `case`; an error when an earlier
    /// row has the name already (even one that wrote no measure: the next run may have some).
    fn claim(&mut self, name: String, case: String) -> Result<&mut BTreeMap<String, Metric>> {
        if let Some(earlier) = self.claimed.get(&name) {
            bail!(
                "two benchmark rows would have the Bencher benchmark name `{name}`: {earlier} \
                 and {case} (scene files with the same name in different folders?)"
            );
        }
        self.claimed.insert(name.clone(), case);
        Ok(self.bmf.0.entry(name).or_default())
    }
}
