//! What `tests/cli/bench.rs` checks of the trade-off ladder's outputs: its rows in the JSON and
//! the plot.

use specchio::scene::camera::ViewBasis;
use specchio::scene::state::SceneState;

/// The ladder, in its order.
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

/// The rungs that trace every mirror ray: exact, and no cube to fill (the last is the host's
/// tracer, which draws nothing on the device).
const TRACED: [&str; 3] = ["ray-query", "bvh", "cpu"];

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
        let geometry = MirrorGeometry::of(scene);
        let points: Vec<(f64, f64)> = here
            .iter()
            .map(|t| check_rung(t, scene, &geometry))
            .collect();
        check_each_rung_nearer_than_the_last(&here, scene);
        check_pareto_flags(&here, &points, scene);
    }
}

/// One rung's row on `scene`: frames, costs, counters, errors; returns its (cost, error) point.
fn check_rung(t: &serde_json::Value, scene: &str, geometry: &MirrorGeometry) -> (f64, f64) {
    let rung = t["rung"].as_str().unwrap();
    assert_eq!(t["frames"], 5, "{scene} {rung}");
    if rung == "cpu" {
        return check_host_rung(t, scene, geometry);
    }
    check_cost_is_the_sum_of_its_parts(t, 5);
    // The cube lookups fill all six faces every frame; the traced ones fill none.
    let faces = if TRACED.contains(&rung) { 0 } else { 30 };
    assert_eq!(t["work"]["faces_rendered"], faces, "{scene} {rung}");
    // The sensor's eye is inside the room's closed box, so every one of its pixels is
    // covered and shaded at least once a frame (a pixel's colour is a fragment
    // shader's output); overdraw and helper invocations, which the driver decides,
    // only add.
    let [w, h] = geometry.sensor.1;
    let shaded = t["work"]["sensor_fragment_invocations"].as_u64().unwrap();
    assert!(
        shaded >= 5 * u64::from(w) * u64::from(h),
        "{scene} {rung}: {shaded} fragment invocations in 5 frames of {w}x{h}"
    );
    check_view_errors(t, scene, rung, geometry);
    // Only distance-exact keeps a tally of the rays it traced: a share, not all.
    let traced = t["sensor_traced_fraction"].as_f64();
    if rung == "distance-exact" {
        let f = traced.expect("distance-exact's traced fraction");
        assert!((0.0..1.0).contains(&f), "{scene}: traced {f}");
    } else {
        assert_eq!(traced, None, "{scene} {rung}");
    }
    (
        t["frame_cost_ms"]["median"].as_f64().unwrap(),
        t["sensor"]["flip_mean"].as_f64().unwrap(),
    )
}

/// The host's tracer's row: no lookup, nothing drawn on the device, its frame the wall time of
/// its BVH's build and its trace; it is the reference itself, so both views' error is 0.
fn check_host_rung(t: &serde_json::Value, scene: &str, geometry: &MirrorGeometry) -> (f64, f64) {
    assert!(t["lookup"].is_null() && t["gpu_cube_ms"].is_null() && t["gpu_sensor_ms"].is_null());
    let (frame, build) = (&t["frame_cost_ms"], &t["cpu_lookup_ms"]);
    for p in ["p10", "median", "p90"] {
        let (f, b) = (frame[p].as_f64().unwrap(), build[p].as_f64().unwrap());
        assert!(
            0.0 < b && b < f,
            "{scene}: build {b} ms of a {f} ms frame ({p})"
        );
    }
    assert_eq!(t["work"]["faces_rendered"], 0);
    for counter in [
        "fill_vertex_invocations",
        "sensor_fragment_invocations",
        "trace",
    ] {
        assert!(t["work"][counter].is_null(), "{scene}: {counter}");
    }
    check_view_errors(t, scene, "cpu", geometry);
    for view in ["sensor", "observer"] {
        assert_eq!(t[view]["flip_mean"], 0.0, "{scene} {view}");
        assert_eq!(t[view]["angular"]["max_deg"], 0.0, "{scene} {view}");
    }
    (frame["median"].as_f64().unwrap(), 0.0)
}

/// Both views of a rung are finite and measure their error over the pixels that see the mirror.
fn check_view_errors(t: &serde_json::Value, scene: &str, rung: &str, geometry: &MirrorGeometry) {
    for (view, (basis, size)) in [("sensor", geometry.sensor), ("observer", geometry.observer)] {
        assert_eq!(t[view]["non_finite_pixels"], 0, "{scene} {rung} {view}");
        // The angular error covers the pixels that see the mirror in both the raster
        // and the exact image: at t = 0 nothing stands between either camera and the
        // mirror in these scenes, so those are the pixel centres whose ray meets the
        // sphere, counted here in f64, give or take the few that graze it.
        let (hits, grazing) = geometry.mirror_pixels(&basis, size);
        let pixels = t[view]["angular"]["pixels"].as_u64().unwrap();
        assert!(
            pixels.abs_diff(hits) <= grazing,
            "{scene} {rung} {view}: {pixels} pixels, the sphere covers {hits} \
             ({grazing} graze it)"
        );
    }
}

/// Each cube rung is nearer the exact answer than the plain lookup, and each traced rung
/// nearer than every cube rung, in both views.
fn check_each_rung_nearer_than_the_last(here: &[&serde_json::Value], scene: &str) {
    for view in ["sensor", "observer"] {
        let flip = |pick: &dyn Fn(&str) -> bool| -> Vec<f64> {
            (here.iter())
                .filter(|t| pick(t["rung"].as_str().unwrap()))
                .map(|t| t[view]["flip_mean"].as_f64().unwrap())
                .collect()
        };
        let plain = flip(&|r| r == "plain")[0];
        let boxed = flip(&|r| r == "box")[0];
        // The footprint's views are a whole cube's, bit for bit.
        assert_eq!(flip(&|r| r == "box-footprint")[0], boxed, "{scene} {view}");
        let cube = flip(&|r| !TRACED.contains(&r));
        let traced = flip(&|r| TRACED.contains(&r));
        assert!(plain > boxed, "{scene} {view}: plain {plain}, box {boxed}");
        // The distance search: better than the plain lookup, not as good as tracing.
        let worst_trace = traced.iter().copied().fold(0.0, f64::max);
        for f in &cube[1..] {
            assert!(
                plain > *f && *f > worst_trace,
                "{scene} {view}: {cube:?} {traced:?}"
            );
        }
    }
}

/// The rows' Pareto flags are the front of their (cost, error) `points`, the least wrong
/// traced rung always on it.
fn check_pareto_flags(here: &[&serde_json::Value], points: &[(f64, f64)], scene: &str) {
    // The flags are the front of these very points: on it when nothing is at most as
    // dear and at most as wrong, and better in one.
    for (t, &(c, e)) in here.iter().zip(points) {
        let dominated = points
            .iter()
            .any(|&(c2, e2)| c2 <= c && e2 <= e && (c2 < c || e2 < e));
        assert_eq!(t["pareto"], !dominated, "{scene} {}", t["rung"]);
    }
    // The least wrong point, a traced rung's, is always on the front.
    let least = (here.iter().zip(points))
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .map(|(t, _)| *t)
        .unwrap();
    assert!(
        TRACED.contains(&least["rung"].as_str().unwrap()),
        "{scene}: {least}"
    );
    assert_eq!(least["pareto"], true, "{scene}");
}

/// A rung's frame cost is, frame by frame, its cube update plus its sensor view plus the
/// host's work for its lookup, and its three statistics are nearest ranks of `n` frames (p10,
/// median, p90: ranks ceil(0.1 n), ceil(0.5 n), ceil(0.9 n)), so they obey the order-statistic
/// bounds of a sum of m parts: with a_p(i) the i-th smallest of part p, the sum's k-th is at
/// least the sum of a_p(i_p) whenever the i_p sum to at most k + m - 1 (at least
/// n - sum(i_p) + m frames have every part at least that large), and at most that sum whenever
/// the i_p sum to at least k + (m - 1) n (at least sum(i_p) - (m - 1) n frames have every part
/// at most that large). Each bound is an exact consequence of the definition; 1e-9 ms covers
/// the rounding of two additions and of the JSON's decimal digits.
fn check_cost_is_the_sum_of_its_parts(t: &serde_json::Value, n: usize) {
    let rank = |p: f64| (p * n as f64).ceil() as usize;
    let stats = |key: &str| -> Vec<(usize, f64)> {
        [("p10", 0.1), ("median", 0.5), ("p90", 0.9)]
            .map(|(name, p)| (rank(p), t[key][name].as_f64().unwrap()))
            .to_vec()
    };
    let parts = [
        stats("gpu_cube_ms"),
        stats("gpu_sensor_ms"),
        stats("cpu_lookup_ms"),
    ];
    let m = parts.len();
    for &(k, c) in &stats("frame_cost_ms") {
        let (mut below, mut above) = (0, 0);
        for &(i, a) in &parts[0] {
            for &(j, b) in &parts[1] {
                for &(l, d) in &parts[2] {
                    let (ranks, sum) = (i + j + l, a + b + d);
                    if ranks < k + m {
                        assert!(
                            c >= sum - 1e-9,
                            "{}: rank {k} {c} < {a} + {b} + {d}",
                            t["rung"]
                        );
                        below += 1;
                    }
                    if ranks >= k + (m - 1) * n {
                        assert!(
                            c <= sum + 1e-9,
                            "{}: rank {k} {c} > {a} + {b} + {d}",
                            t["rung"]
                        );
                        above += 1;
                    }
                }
            }
        }
        // Not vacuous: with p10 and p90 the extremes of 5 frames, every rank of the cost is
        // bounded from both sides.
        assert!(
            below > 0 && above > 0,
            "rank {k} of {n}: {below} below, {above} above"
        );
    }
}

/// The two views of a scene at t = 0 in render space (the mirror's centre at the origin), with
/// their image sizes, and the mirror's radius.
struct MirrorGeometry {
    sensor: (ViewBasis, [u32; 2]),
    observer: (ViewBasis, [u32; 2]),
    radius: f64,
}

impl MirrorGeometry {
    fn of(scene: &str) -> Self {
        let scene = specchio::scene::load(&super::common::root().join(scene)).unwrap();
        let state = SceneState::at(&scene, 0.0);
        let aspect = |[w, h]: [u32; 2]| w as f32 / h as f32;
        let (s, o) = (scene.sensor.resolution, scene.observer.resolution);
        Self {
            sensor: (state.sensor_view(&scene, aspect(s)), s),
            observer: (state.observer_view(&scene, aspect(o)), o),
            radius: f64::from(scene.mirror.radius_m),
        }
    }

    /// The pixel centres whose ray meets the sphere (f64: the ray's closest approach to the
    /// centre below the radius, in front of the eye), and those within 1e-5 radii of grazing
    /// it, which the renderer's and the reference's f32 arithmetic (a few 1e-7 of the
    /// distances here) may count either way.
    fn mirror_pixels(&self, view: &ViewBasis, [w, h]: [u32; 2]) -> (u64, u64) {
        let eye = view.eye.as_dvec3();
        let (mut hits, mut grazing) = (0, 0);
        let (forward, right, down) = (
            view.forward.as_dvec3(),
            view.right.as_dvec3() * f64::from(view.tan_x),
            view.down.as_dvec3() * f64::from(view.tan_y),
        );
        for y in 0..h {
            for x in 0..w {
                let ndc_x = 2.0 * (f64::from(x) + 0.5) / f64::from(w) - 1.0;
                let ndc_y = 2.0 * (f64::from(y) + 0.5) / f64::from(h) - 1.0;
                let d = (forward + ndc_x * right + ndc_y * down).normalize();
                let along = -eye.dot(d);
                let closest = (eye + along * d).length();
                if along > 0.0 && closest < self.radius {
                    hits += 1;
                }
                if (closest / self.radius - 1.0).abs() < 1e-5 {
                    grazing += 1;
                }
            }
        }
        (hits, grazing)
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
    // Each rung labelled once per scene; an exact point is drawn at the plot's floor, said.
    for rung in RUNGS.map(|r| format!("{r} 64²")) {
        let labels = (texts.iter())
            .filter(|t| **t == rung || **t == format!("{rung} (FLIP 0)"))
            .count();
        assert_eq!(labels, 2, "{rung}");
    }
    assert_eq!(
        texts.iter().filter(|t| *t == "cpu 64² (FLIP 0)").count(),
        2,
        "the host's tracer is the reference: FLIP 0"
    );
}
