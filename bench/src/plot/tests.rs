//! The whole plot, drawn from a hand-made record and read back as SVG.

use super::*;
use serde_json::{json, Value};

const RUNGS: [&str; 10] = [
    "plain",
    "box",
    "box-footprint",
    "distance-8",
    "distance-16",
    "distance-32",
    "distance-exact",
    "ray-query",
    "bvh",
    "cpu",
];

/// The committed quick baseline (two scenes, 64² faces) with its trade-off rows given these
/// costs and errors, in the ladder's order, per scene, and their Pareto flags.
fn record(points: [[(f64, f64); 10]; 2]) -> Record {
    let mut raw: Value = serde_json::from_str(include_str!("../../baselines/quick.json"))
        .expect("bench/baselines/quick.json is JSON");
    let scenes: Vec<Value> = raw["settings"]["scenes"].as_array().unwrap().clone();
    let rows = raw["tradeoff"].as_array_mut().unwrap();
    for row in rows.iter_mut() {
        let s = scenes.iter().position(|s| *s == row["scene"]).unwrap();
        let r = RUNGS.iter().position(|r| *r == row["rung"]).unwrap();
        let (cost, flip) = points[s][r];
        let dominated = points[s]
            .iter()
            .any(|&(c, e)| c <= cost && e <= flip && (c < cost || e < flip));
        row["frame_cost_ms"] = json!({"median": cost, "p10": cost, "p90": cost});
        row["sensor"] = json!({
            "flip_mean": flip, "flip_p99": flip, "non_finite_pixels": 0,
            "angular": {"pixels": 1, "mean_deg": 0.0, "p99_deg": 0.0, "max_deg": 0.0,
                "face_size_px": 64, "mean_texels": 0.0, "p99_texels": 0.0, "max_texels": 0.0}
        });
        row["pareto"] = json!(!dominated);
    }
    serde_json::from_value(raw).expect("the edited baseline is a record")
}

/// A crowded scene: the cube rungs near 10 and 30 ms (box-footprint at box's error, a little
/// cheaper, as the footprint measures), the distance rungs nearly on one spot,
/// tracing at 300, 1500 and 150 ms, the host's tracer at 800 ms.
const CROWDED: [(f64, f64); 10] = [
    (10.0, 0.3),
    (11.0, 0.2),
    (10.6, 0.2),
    (30.0, 0.150),
    (30.5, 0.149),
    (31.0, 0.148),
    (300.0, 0.03),
    (1500.0, 0.001),
    (150.0, 0.0005),
    (800.0, 0.0001),
];
/// A quick scene whose ray-query is exact (FLIP 0, drawn at the floor).
const QUICK: [(f64, f64); 10] = [
    (6.6, 0.25),
    (7.0, 0.05),
    (7.3, 0.05),
    (17.7, 0.046),
    (22.6, 0.045),
    (31.4, 0.045),
    (23.6, 0.044),
    (9.5, 0.0),
    (5.0, 0.0002),
    (40.0, 0.0001),
];

/// A `<text>` of the plot.
struct Text {
    text: String,
    x: f64,
    y: f64,
    /// `start`, `middle` or `end`: which end of the text `x` is.
    anchor: String,
}

/// Every `<text>`.
fn texts(svg: &str) -> Vec<Text> {
    let doc = roxmltree::Document::parse(svg).expect("the plot is well-formed XML");
    let number = |n: &roxmltree::Node, a| n.attribute(a).unwrap().parse::<f64>().unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| Text {
            text: n.text().unwrap_or("").trim().to_owned(),
            x: number(&n, "x"),
            y: number(&n, "y"),
            anchor: n.attribute("text-anchor").unwrap_or("start").to_owned(),
        })
        .collect()
}

#[test]
fn every_rung_is_labelled_once_per_scene_and_zero_flip_says_so() {
    let svg = svg(&record([CROWDED, QUICK])).unwrap();
    let texts = texts(&svg);
    let count = |t: &str| texts.iter().filter(|x| x.text == t).count();
    let panels = texts.iter().filter(|t| t.text.ends_with(TRADEOFF_TITLE));
    assert_eq!(panels.count(), 2);
    for scene in ["scenes/thesis-room.toml", "scenes/moving-objects.toml"] {
        assert_eq!(count(&format!("{scene}: {TRADEOFF_TITLE}")), 1, "{scene}");
        assert_eq!(count(&format!("{scene}: cube update per fill method")), 1);
    }
    for rung in RUNGS.iter().filter(|&&r| r != "ray-query") {
        assert_eq!(count(&format!("{rung} 64²")), 2, "{rung}");
    }
    assert_eq!(count("ray-query 64²"), 1);
    assert_eq!(count("ray-query 64² (FLIP 0)"), 1);
    assert_eq!(count("64² faces: Pareto front"), 2);
}

#[test]
fn labels_overlap_no_label_and_no_marker() {
    let svg = svg(&record([CROWDED, QUICK])).unwrap();
    let boxes: Vec<Rect> = texts(&svg)
        .into_iter()
        .filter(|t| {
            RUNGS
                .iter()
                .any(|r| t.text.starts_with(&format!("{r} 64²")))
        })
        .map(|t| {
            let (w, h) = labels::text_box(t.text.chars().count(), LABEL_DRAWN_PX);
            // The text is drawn from its box's padded edge: left, right or the middle.
            let (x, top) = (t.x as i32, t.y as i32 - 2);
            let left = match t.anchor.as_str() {
                "start" => x - 2,
                "end" => x + 2 - w,
                _ => x - w / 2,
            };
            Rect(left, top, left + w, top + h)
        })
        .collect();
    assert_eq!(boxes.len(), 20);
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            assert!(!a.overlaps(b), "{a:?} on {b:?}");
        }
    }
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let circles: Vec<(f64, f64)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("circle"))
        .map(|n| {
            let at = |a| n.attribute(a).unwrap().parse::<f64>().unwrap();
            (at("cx"), at("cy"))
        })
        .collect();
    assert!(circles.len() >= 18, "{} markers", circles.len());
    for r in &boxes {
        for &(cx, cy) in &circles {
            // The nearest point of the box to the marker's centre, outside its radius and stroke.
            let dx = (f64::from(r.0) - cx).max(cx - f64::from(r.2)).max(0.0);
            let dy = (f64::from(r.1) - cy).max(cy - f64::from(r.3)).max(0.0);
            assert!(dx.hypot(dy) >= 6.0, "{r:?} on the marker at {cx}, {cy}");
        }
    }
}

#[test]
fn the_cost_axis_is_logarithmic_with_round_ticks() {
    let svg = svg(&record([CROWDED, QUICK])).unwrap();
    // The crowded scene's trade-off panel: the top-left one.
    let ticks: Vec<(String, f64)> = texts(&svg)
        .into_iter()
        .filter(|t| t.x < f64::from(WIDTH / 2) && t.y < f64::from(ROW_HEIGHT))
        .map(|t| (t.text, t.x))
        .collect();
    let x = |label: &str| {
        let found = ticks.iter().find(|t| t.0 == label);
        found
            .unwrap_or_else(|| panic!("no tick {label} in {ticks:?}"))
            .1
    };
    for label in ["20", "50", "200", "500"] {
        x(label);
    }
    // Each decade is as wide as the next; no tick at 0 (the old linear axis started there).
    let (a, b) = (x("100") - x("10"), x("1000") - x("100"));
    assert!(
        a > 100.0 && (a - b).abs() <= 1.0,
        "decades {a} and {b} px wide"
    );
    assert!(ticks.iter().all(|t| t.0 != "0"));
}
