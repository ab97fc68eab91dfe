//! Known answers of the BMF writer, and a BMF validator written apart from it.

use serde_json::Value;
use specchio::reference::angular::AngularError;
use specchio::render::methods::Method;

use super::validator::violations;
use super::*;
use crate::record::{Dynamic, DynamicFrame, MethodRow, RungRow, ViewError};
use specchio::render::lookups::ladder;

/// The committed baseline, for the parts of a record these tests do not care about (settings,
/// environment, a row to copy), with the device named as lavapipe names it.
fn template() -> Record {
    let mut r: Record = serde_json::from_str(include_str!("../../baselines/quick.json"))
        .expect("bench/baselines/quick.json is a record");
    r.device.name = "llvmpipe (LLVM 15.0.6, 256 bits)".into();
    r.device.short_name = "lavapipe".into();
    r
}

fn stats(p10: f64, median: f64, p90: f64) -> Option<Stats> {
    Some(Stats { median, p10, p90 })
}

/// A template's record with its rows replaced by `results` and `tradeoff` (and no animated
/// scenes).
fn record(results: Vec<MethodRow>, tradeoff: Vec<RungRow>) -> Record {
    let mut r = template();
    r.results = results;
    r.tradeoff = tradeoff;
    r.dynamic = Vec::new();
    r
}

fn method_row(scene: &str, method: &str, size: u32, wall_ms: Option<Stats>) -> MethodRow {
    let mut row = template().results[0].clone();
    row.scene = scene.into();
    row.method = Method::parse(method).expect("a registered method");
    row.cube_size = size;
    row.wall_ms = wall_ms;
    row.in_flight_ms = None;
    row
}

/// A rung row; `flip` None: no error measured, Some(None): measured without a FLIP figure.
fn rung_row(
    scene: &str,
    rung: &str,
    size: u32,
    cost: Option<Stats>,
    flip: Option<Option<f64>>,
) -> RungRow {
    let mut row = template().tradeoff[0].clone();
    row.scene = scene.into();
    row.rung = rung.into();
    row.cube_size = size;
    row.frame_cost_ms = cost;
    row.sensor = flip.map(|flip_mean| ViewError {
        flip_mean,
        flip_p99: None,
        non_finite_pixels: 0,
        angular: AngularError::default(),
    });
    row
}

const ROOM: &str = "scenes/thesis-room.toml";
const MANY: &str = "scenes/many-objects.toml";

/// Two scenes, three methods at two sizes, four rungs; rows without statistics, with a NaN, an
/// infinity and percentiles out of order; a time in flight where only it was measured and
/// where it is out of order.
fn mixed() -> Record {
    let mut mesh = method_row(ROOM, "mesh", 64, None);
    mesh.in_flight_ms = stats(3.5, 4.0, 4.5);
    let mut multiview = method_row(MANY, "multiview", 512, stats(10.0, f64::NAN, 20.0));
    multiview.in_flight_ms = stats(9.0, 8.0, 10.0);
    record(
        vec![
            method_row(ROOM, "six-pass", 64, stats(1.5, 2.0, 3.0)),
            mesh,
            method_row(MANY, "six-pass", 512, stats(10.0, 12.5, 20.0)),
            multiview,
            method_row(MANY, "geometry", 512, stats(10.0, 11.0, f64::INFINITY)),
        ],
        vec![
            rung_row(ROOM, "box", 64, stats(6.0, 7.0, 8.0), Some(Some(0.25))),
            rung_row(ROOM, "ray-query", 64, stats(9.0, 10.0, 11.0), None),
            rung_row(MANY, "distance-exact", 512, None, Some(Some(0.01))),
            rung_row(
                MANY,
                "ray-query",
                512,
                stats(5.0, 4.0, 6.0),
                Some(Some(f64::NAN)),
            ),
            rung_row(MANY, "plain", 512, None, Some(None)),
        ],
    )
}

fn spread(lower: f64, value: f64, upper: f64) -> Metric {
    Metric {
        value,
        lower_value: Some(lower),
        upper_value: Some(upper),
    }
}

fn single(value: f64) -> Metric {
    Metric {
        value,
        lower_value: None,
        upper_value: None,
    }
}

fn document(entries: &[(&str, &[(Measure, Metric)])]) -> Bmf {
    Bmf(entries
        .iter()
        .map(|(name, measures)| {
            let measures = measures
                .iter()
                .map(|(m, metric)| (m.slug().to_owned(), *metric))
                .collect();
            (name.to_string(), measures)
        })
        .collect())
}

#[test]
fn every_measured_row_and_only_those_are_written() {
    // Left out: mesh's time alone (none), multiview (NaN median; its time in flight's p10
    // above the median), geometry (infinite p90), many-objects' ray-query (p10 above the
    // median, NaN FLIP) and plain (no FLIP figure).
    let expected = document(&[
        (
            "many-objects/rung-distance-exact/512/llvmpipe",
            &[(Measure::SensorFlipMean, single(0.01))],
        ),
        (
            "many-objects/six-pass/512/llvmpipe",
            &[(Measure::CubeUpdateMs, spread(10.0, 12.5, 20.0))],
        ),
        (
            "thesis-room/mesh/64/llvmpipe",
            &[(Measure::CubeUpdateInFlightMs, spread(3.5, 4.0, 4.5))],
        ),
        (
            "thesis-room/rung-box/64/llvmpipe",
            &[
                (Measure::FrameCostMs, spread(6.0, 7.0, 8.0)),
                (Measure::SensorFlipMean, single(0.25)),
            ],
        ),
        (
            "thesis-room/rung-ray-query/64/llvmpipe",
            &[(Measure::FrameCostMs, spread(9.0, 10.0, 11.0))],
        ),
        (
            "thesis-room/six-pass/64/llvmpipe",
            &[(Measure::CubeUpdateMs, spread(1.5, 2.0, 3.0))],
        ),
    ]);
    assert_eq!(bmf(&mixed()).unwrap(), expected);
}

#[test]
fn the_text_is_the_documented_layout() {
    // The example in docs/benchmarks.md ("Bencher Metric Format") is this text.
    let r = record(
        vec![method_row(ROOM, "six-pass", 64, stats(1.5, 2.0, 3.0))],
        vec![rung_row(
            ROOM,
            "box",
            64,
            stats(6.0, 7.0, 8.0),
            Some(Some(0.25)),
        )],
    );
    let expected = r#"{
  "thesis-room/rung-box/64/llvmpipe": {
    "frame-cost-ms": {
      "value": 7.0,
      "lower_value": 6.0,
      "upper_value": 8.0
    },
    "sensor-flip-mean": {
      "value": 0.25
    }
  },
  "thesis-room/six-pass/64/llvmpipe": {
    "cube-update-ms": {
      "value": 2.0,
      "lower_value": 1.5,
      "upper_value": 3.0
    }
  }
}
"#;
    assert_eq!(json(&bmf(&r).unwrap()).unwrap(), expected);
    let docs = include_str!("../../../docs/benchmarks.md");
    let shown = format!("```json\n{expected}```");
    assert!(
        docs.contains(&shown),
        "docs/benchmarks.md (\"Bencher Metric Format\") shows this example"
    );
}

#[test]
fn the_text_reads_back_as_the_same_document() {
    let doc = bmf(&mixed()).unwrap();
    let back: Bmf = serde_json::from_str(&json(&doc).unwrap()).unwrap();
    assert_eq!(back, doc);
}

#[test]
fn an_empty_run_is_an_empty_object() {
    let r = record(Vec::new(), Vec::new());
    assert_eq!(json(&bmf(&r).unwrap()).unwrap(), "{}\n");
}

#[test]
fn two_scenes_with_one_stem_are_refused_naming_both_rows() {
    let r = record(
        vec![
            method_row("a/room.toml", "six-pass", 64, stats(1.0, 2.0, 3.0)),
            // No times: it would write nothing, but it still may not share the name.
            method_row("b/room.toml", "six-pass", 64, None),
        ],
        Vec::new(),
    );
    let e = bmf(&r).unwrap_err().to_string();
    assert!(
        e.contains("`room/six-pass/64/llvmpipe`")
            && e.contains("a/room.toml / six-pass / 64²")
            && e.contains("b/room.toml / six-pass / 64²"),
        "{e}"
    );
}

#[test]
fn device_names_lose_what_drivers_put_in_parentheses() {
    let mut d = template().device;
    for (name, short, expected) in [
        ("llvmpipe (LLVM 15.0.6, 256 bits)", "lavapipe", "llvmpipe"),
        (
            "SwiftShader Device (Subzero) (0x0000C0DE)",
            "swiftshader",
            "swiftshader-device",
        ),
        ("NVIDIA H100 80GB HBM3", "nvidia", "nvidia-h100-80gb-hbm3"),
        (
            "AMD Radeon RX 7900 XTX (RADV NAVI31)",
            "radv",
            "amd-radeon-rx-7900-xtx",
        ),
        // A parenthesis without a space before it is part of the name.
        (
            "Intel(R) Arc(tm) A770 Graphics (DG2)",
            "intel",
            "intel-r-arc-tm-a770-graphics",
        ),
        // Nothing before the parenthesis: the whole name; no letter at all: the short name.
        ("(Software Rasterizer)", "x", "software-rasterizer"),
        ("∆ ∇", "My Driver", "my-driver"),
        ("∆", "", "device"),
    ] {
        d.name = name.into();
        d.short_name = short.into();
        assert_eq!(device_slug(&d), expected, "{name}");
    }
}

#[test]
fn scene_names_are_the_file_stem() {
    for (scene, expected) in [
        ("scenes/thesis-room.toml", "thesis-room"),
        ("/home/x/My Scenes/Big Room.v2.toml", "big-room-v2"),
        ("room", "room"),
        ("../--.toml", "toml"),
        ("", "scene"),
    ] {
        assert_eq!(scene_slug(scene), expected, "{scene:?}");
    }
}

#[test]
fn method_names_and_rung_labels_are_kept_as_the_table_prints_them() {
    // So a benchmark name can be read against the table, and a rung never takes a method's.
    for m in Method::all() {
        assert_eq!(slug(m.name()), m.name());
        assert!(!m.name().starts_with("rung-"), "{}", m.name());
    }
    for r in ladder() {
        assert_eq!(slug(r.label), r.label);
    }
}

#[test]
fn the_module_documentation_lists_every_measure() {
    let source = include_str!("../bmf.rs");
    for m in Measure::ALL {
        assert!(
            source.contains(&format!("//! | `{}` |", m.slug())),
            "{} is not in the table",
            m.slug()
        );
    }
}

#[test]
fn a_nan_that_got_past_the_writer_would_be_caught() {
    // serde_json writes a non-finite f64 as null; Bencher would refuse the whole report.
    let mut doc = bmf(&mixed()).unwrap();
    let name = "thesis-room/six-pass/64/llvmpipe";
    doc.0
        .get_mut(name)
        .unwrap()
        .insert(Measure::CubeUpdateMs.slug().to_owned(), single(f64::NAN));
    let v = violations(&json(&doc).unwrap());
    assert!(v.iter().any(|v| v.contains("is null")), "{v:?}");
}

#[test]
fn the_written_documents_follow_every_rule() {
    let baseline: Record = serde_json::from_str(include_str!("../../baselines/quick.json"))
        .expect("bench/baselines/quick.json is a record");
    for (what, r) in [
        ("mixed rows", mixed()),
        ("the committed baseline", baseline),
    ] {
        let text = json(&bmf(&r).unwrap()).unwrap();
        assert_eq!(violations(&text), Vec::<String>::new(), "{what}");
        // Only the measures this module documents.
        let doc: Value = serde_json::from_str(&text).unwrap();
        for measures in doc.as_object().unwrap().values() {
            for slug in measures.as_object().unwrap().keys() {
                assert!(Measure::ALL.iter().any(|m| m.slug() == slug), "{slug}");
            }
        }
    }
}

/// An animated scene's frames: 64² faces; frame 0 without motion (left out), then three
/// frames whose rectangles, whole faces and full updates took known times and texels.
fn dynamic_row() -> Dynamic {
    let frame = |moved: bool, k: f64, texels_rects: u64| DynamicFrame {
        time_s: k,
        faces_incremental: u32::from(moved),
        faces_full: if moved { 6 } else { 0 },
        texels_rects,
        texels_full: if moved { 6 * 64 * 64 } else { 0 },
        rects_ms: k,
        whole_faces_ms: 10.0 * k,
        full_ms: 100.0 * k,
    };
    Dynamic {
        scene: "scenes/moving-objects.toml".into(),
        method: Method::SIX_PASS,
        cube_size: 64,
        from_s: 0.0,
        frames: vec![
            frame(false, 9.0, 0),
            frame(true, 1.0, 100),
            frame(true, 2.0, 300),
            frame(true, 3.0, 200),
        ],
        changed_frames: 3,
        faces_incremental_median: Some(1.0),
        texels_rects_median: Some(200.0),
        rects_ms_median: Some(2.0),
        whole_faces_ms_median: Some(20.0),
        full_ms_median: Some(200.0),
        ratio: Some(0.01),
        whole_faces_ratio: Some(0.1),
        texels_ratio: None,
    }
}

/// Each kind of update is a benchmark of its own with its times and texels over the frames
/// with motion (nearest rank: of three values p10 is the least, p90 the greatest).
#[test]
fn an_animated_scenes_updates_are_three_benchmarks() {
    let mut r = record(vec![], vec![]);
    r.dynamic = vec![dynamic_row()];
    let full = (6 * 64 * 64) as f64;
    let expected = document(&[
        (
            "moving-objects/update-full/64/llvmpipe",
            &[
                (Measure::UpdateMs, spread(100.0, 200.0, 300.0)),
                (Measure::TexelsRendered, spread(full, full, full)),
            ],
        ),
        (
            "moving-objects/update-rects/64/llvmpipe",
            &[
                (Measure::UpdateMs, spread(1.0, 2.0, 3.0)),
                (Measure::TexelsRendered, spread(100.0, 200.0, 300.0)),
            ],
        ),
        (
            "moving-objects/update-whole-faces/64/llvmpipe",
            &[
                (Measure::UpdateMs, spread(10.0, 20.0, 30.0)),
                (Measure::TexelsRendered, spread(4096.0, 4096.0, 4096.0)),
            ],
        ),
    ]);
    let doc = bmf(&r).unwrap();
    assert_eq!(doc, expected);
    assert_eq!(violations(&json(&doc).unwrap()), Vec::<String>::new());
}

/// A traced rung's walk is written per ray, from its exact counts; a walk of no rays writes no
/// ratio (0/0), and a rung without a walk none of the three.
#[test]
fn a_traced_rungs_walk_is_written_per_ray() {
    let walk = |rays, nodes, instances, triangles| {
        Some(specchio::bvh::Work {
            rays,
            nodes,
            instances,
            triangles,
        })
    };
    let mut bvh = rung_row(
        MANY,
        "bvh",
        512,
        stats(30.0, 34.5, 40.0),
        Some(Some(1.2e-4)),
    );
    bvh.work.trace = walk(200, 2074, 243, 574);
    let mut empty = rung_row(ROOM, "bvh", 64, None, None);
    empty.work.trace = walk(0, 0, 0, 0);
    let boxed = rung_row(ROOM, "box", 64, None, Some(Some(0.25)));
    let r = record(vec![], vec![bvh, empty, boxed]);
    let expected = document(&[
        (
            "many-objects/rung-bvh/512/llvmpipe",
            &[
                (Measure::FrameCostMs, spread(30.0, 34.5, 40.0)),
                (Measure::SensorFlipMean, single(1.2e-4)),
                (Measure::TraceNodesPerRay, single(10.37)),
                (Measure::TraceObjectsPerRay, single(1.215)),
                (Measure::TraceTrianglesPerRay, single(2.87)),
            ],
        ),
        (
            "thesis-room/rung-box/64/llvmpipe",
            &[(Measure::SensorFlipMean, single(0.25))],
        ),
    ]);
    let doc = bmf(&r).unwrap();
    assert_eq!(doc, expected);
    assert_eq!(violations(&json(&doc).unwrap()), Vec::<String>::new());
}
