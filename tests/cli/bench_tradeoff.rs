//! What `tests/cli/bench.rs` checks of the trade-off ladder's outputs: its rows in the JSON and
//! the plot.

/// The ladder, in its order.
const RUNGS: [&str; 7] = [
    "plain",
    "box",
    "distance-8",
    "distance-16",
    "distance-32",
    "distance-exact",
    "ray-query",
];

/// The trade-off rows of a quick run on lavapipe: every rung on every scene, with its costs,
/// counters and both views' errors, and the Pareto flags of the measured points.
pub fn check_tradeoff(r: &serde_json::Value) {
    let rows = r["tradeoff"].as_array().expect("`tradeoff` array");
    assert_eq!(r["settings"]["rungs"], serde_json::json!(RUNGS));
    assert_eq!(r["rungs_not_run"], serde_json::json!([]));
    for scene in ["scenes/thesis-room.toml", "scenes/moving-objects.toml"] {
        let here: Vec<&serde_json::Value> = rows.iter().filter(|t| t["scene"] == scene).collect();
        let labels: Vec<&str> = here.iter().map(|t| t["rung"].as_str().unwrap()).collect();
        assert_eq!(labels, RUNGS, "{scene}");
        let mut points = Vec::new();
        for t in &here {
            let rung = t["rung"].as_str().unwrap();
            assert_eq!(t["frames"], 5, "{scene} {rung}");
            let cost = t["frame_cost_ms"]["median"].as_f64().unwrap();
            let parts = t["gpu_cube_ms"]["median"].as_f64().unwrap()
                + t["gpu_sensor_ms"]["median"].as_f64().unwrap();
            assert!(
                cost > 0.0 && cost <= 2.0 * parts,
                "{scene} {rung}: {cost} vs {parts}"
            );
            // The cube lookups fill all six faces every frame; ray-query fills none.
            let faces = if rung == "ray-query" { 0 } else { 30 };
            assert_eq!(t["work"]["faces_rendered"], faces, "{scene} {rung}");
            assert!(t["work"]["sensor_fragment_invocations"].as_u64().unwrap() > 0);
            for view in ["sensor", "observer"] {
                assert_eq!(t[view]["non_finite_pixels"], 0, "{scene} {rung} {view}");
                assert!(t[view]["angular"]["pixels"].as_u64().unwrap() > 0);
            }
            // Only distance-exact keeps a tally of the rays it traced: a share, not all.
            let traced = t["sensor_traced_fraction"].as_f64();
            if rung == "distance-exact" {
                let f = traced.expect("distance-exact's traced fraction");
                assert!((0.0..1.0).contains(&f), "{scene}: traced {f}");
            } else {
                assert_eq!(traced, None, "{scene} {rung}");
            }
            points.push((cost, t["sensor"]["flip_mean"].as_f64().unwrap()));
        }
        // Each rung nearer the exact answer than the one before it, in both views.
        for view in ["sensor", "observer"] {
            let flip: Vec<f64> = here
                .iter()
                .map(|t| t[view]["flip_mean"].as_f64().unwrap())
                .collect();
            let (plain, boxed, exact) = (flip[0], flip[1], flip[RUNGS.len() - 1]);
            assert!(plain > boxed && boxed > exact, "{scene} {view}: {flip:?}");
            // The distance search: better than the plain lookup, not as good as tracing.
            for f in &flip[2..RUNGS.len() - 1] {
                assert!(plain > *f && *f > exact, "{scene} {view}: {flip:?}");
            }
        }
        // The flags are the front of these very points: on it when nothing is at most as
        // dear and at most as wrong, and better in one.
        for (t, &(c, e)) in here.iter().zip(&points) {
            let dominated = points
                .iter()
                .any(|&(c2, e2)| c2 <= c && e2 <= e && (c2 < c || e2 < e));
            assert_eq!(t["pareto"], !dominated, "{scene} {}", t["rung"]);
        }
        // The least wrong point is always on the front.
        assert!(here
            .iter()
            .any(|t| t["rung"] == "ray-query" && t["pareto"] == true));
    }
}

/// The plot is well-formed SVG with one trade-off panel (and one method panel) per scene, and
/// every rung labelled.
pub fn check_plot(text: &str) {
    let doc = roxmltree::Document::parse(text).expect("the plot is well-formed XML");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let texts: Vec<String> = doc
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").trim().to_owned())
        .collect();
    for scene in ["scenes/thesis-room.toml", "scenes/moving-objects.toml"] {
        for panel in [
            "frame cost against sensor error",
            "cube update per fill method",
        ] {
            let title = format!("{scene}: {panel}");
            assert_eq!(texts.iter().filter(|t| **t == title).count(), 1, "{title}");
        }
    }
    assert_eq!(
        texts
            .iter()
            .filter(|t| t.ends_with("frame cost against sensor error"))
            .count(),
        2
    );
    for rung in RUNGS.map(|r| format!("{r} 64²")) {
        assert_eq!(texts.iter().filter(|t| **t == rung).count(), 2, "{rung}");
    }
}
