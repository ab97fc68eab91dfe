//! The answer's lines from a real record (the committed quick baseline) with known times and
//! errors written into it.

use super::lines;
use crate::record::{self, FloorRow, Record, Stats, ViewError};
use specchio::reference::angular::AngularError;
use specchio::render::floors::Floor;
use specchio::render::methods::Method;

const SCENE: &str = "scenes/thesis-room.toml";

fn baseline() -> Record {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/baselines/quick.json");
    record::parse(&std::fs::read_to_string(path).expect("the quick baseline")).expect("a record")
}

fn stats(median: f64) -> Option<Stats> {
    Some(Stats {
        median,
        p10: median * 0.9,
        p90: median * 1.1,
    })
}

fn error(flip_mean: f64) -> Option<ViewError> {
    Some(ViewError {
        flip_mean: Some(flip_mean),
        flip_p99: Some(flip_mean),
        non_finite_pixels: 0,
        angular: AngularError {
            pixels: 1,
            mean_deg: 0.0,
            p99_deg: 0.0,
            max_deg: 0.0,
            face_size_px: 64,
            mean_texels: 0.0,
            p99_texels: 0.0,
            max_texels: 0.0,
        },
    })
}

/// The thesis room's methods at 10, 8, 12, 12, 12 ms and floors of 2 + 3 ms; the ladder with
/// plain, box and ray-query on the device's front, and the host's tracer exact at 30 ms.
fn known() -> Record {
    let mut r = baseline();
    for row in r.results.iter_mut().filter(|row| row.scene == SCENE) {
        let ms = match row.method.name() {
            "six-pass" => 10.0,
            "multiview" => 8.0,
            _ => 12.0,
        };
        row.wall_ms = stats(ms);
        row.efficiency.vs_geometry_plus_fill = Some(ms / 5.0);
    }
    for (floor, ms) in [(Floor::Geometry, 2.0), (Floor::Fill, 3.0)] {
        r.floors.push(FloorRow {
            scene: SCENE.to_owned(),
            floor,
            cube_size: 64,
            updates: 5,
            wall_ms: stats(ms),
            run_medians_ms: vec![ms],
            gpu_fill_ms: None,
            fill_stats: None,
        });
    }
    for rung in r.tradeoff.iter_mut().filter(|row| row.scene == SCENE) {
        let (ms, flip, front) = match rung.rung.as_str() {
            "plain" => (6.0, 0.3, true),
            "box" => (7.0, 0.2, true),
            "ray-query" => (9.0, 0.0003, true),
            "cpu" => (30.0, 0.0, true),
            _ => (20.0, 0.25, false),
        };
        rung.frame_cost_ms = stats(ms);
        rung.sensor = error(flip);
        rung.pareto = Some(front);
    }
    r
}

#[test]
fn the_answer_names_the_fastest_method_and_the_front() {
    let text = lines(&known());
    assert!(text[0].starts_with("the answer on "), "{text:?}");
    let at = text
        .iter()
        .position(|l| l == "  scenes/thesis-room.toml, 64² faces:")
        .expect("the scene's heading");
    assert_eq!(
        text[at + 1],
        "    fill:    multiview is fastest: 8.0 ms a cube update, 0.80x six-pass (10.0 ms), \
         1.60x the floors (geometry + fill 5.0 ms)"
    );
    assert_eq!(
        text[at + 2],
        "    ladder:  front plain 6.0 ms FLIP 0.300 → box 7.0 ms 0.200 → ray-query 9.0 ms \
         3.0e-4; most accurate: ray-query, 1.29x box's frame cost; cpu 30.0 ms, 3.33x \
         ray-query, the cheapest exact rung on the device"
    );
}

/// The host's tracer is weighed against the cheapest device rung that traces: cheaper, it
/// wins; with no such rung measured, it is the only exact one.
#[test]
fn the_host_tracer_is_said_to_win_or_to_be_the_only_exact_rung() {
    let ladder = |r: &Record| {
        let text = lines(r);
        let at = (text.iter())
            .position(|l| l == "  scenes/thesis-room.toml, 64² faces:")
            .expect("the scene's heading");
        text[at + 2].clone()
    };
    let mut r = known();
    for rung in r.tradeoff.iter_mut().filter(|row| row.scene == SCENE) {
        if rung.rung == "cpu" {
            rung.frame_cost_ms = stats(4.5);
        }
    }
    let line = ladder(&r);
    assert!(
        line.ends_with("; cpu 4.5 ms, 0.50x ray-query: the host wins"),
        "{line}"
    );
    r.tradeoff
        .retain(|row| !["ray-query", "bvh"].contains(&row.rung.as_str()));
    let line = ladder(&r);
    assert!(
        line.ends_with("; cpu 4.5 ms: the only exact rung here"),
        "{line}"
    );
}

#[test]
fn six_pass_fastest_and_parts_not_run_are_said_as_such() {
    let mut r = known();
    for row in r.results.iter_mut().filter(|row| row.scene == SCENE) {
        if row.method == Method::SIX_PASS {
            row.wall_ms = stats(4.0);
            row.efficiency.vs_geometry_plus_fill = None;
        }
    }
    // No rung's error measured (--no-accuracy): no ladder line.
    for rung in &mut r.tradeoff {
        rung.sensor = None;
    }
    let text = lines(&r);
    let at = text
        .iter()
        .position(|l| l == "  scenes/thesis-room.toml, 64² faces:")
        .expect("the scene's heading");
    assert_eq!(
        text[at + 1],
        "    fill:    six-pass is fastest: 4.0 ms a cube update (every one-pass method is slower)"
    );
    assert!(!text.iter().any(|l| l.contains("ladder:")), "{text:?}");
}

#[test]
fn a_front_of_one_rung_is_said_to_be_cheapest_and_most_accurate() {
    let mut r = known();
    for rung in r.tradeoff.iter_mut().filter(|row| row.scene == SCENE) {
        rung.pareto = Some(rung.rung == "ray-query");
        if rung.rung == "ray-query" {
            rung.frame_cost_ms = stats(3.5);
        }
    }
    let text = lines(&r);
    assert!(
        text.contains(
            &"    ladder:  ray-query is both the cheapest and the most accurate rung: 3.5 ms, \
              FLIP 3.0e-4, 0.50x box's frame cost; cpu 30.0 ms, 8.57x ray-query, the \
              cheapest exact rung on the device"
                .to_owned()
        ),
        "{text:?}"
    );
}

/// A rung whose error another rung equals exactly (box-footprint's images are box's) is not
/// called the most accurate alone, on a front of one rung or of several.
#[test]
fn a_rung_that_ties_in_error_is_named_beside_the_most_accurate() {
    let mut r = known();
    for rung in r.tradeoff.iter_mut().filter(|row| row.scene == SCENE) {
        match rung.rung.as_str() {
            "box-footprint" => {
                rung.frame_cost_ms = stats(6.5);
                rung.sensor = error(0.2);
            }
            "ray-query" | "plain" => {
                rung.frame_cost_ms = stats(8.0);
                rung.sensor = error(0.5);
            }
            _ => {}
        }
    }
    let text = lines(&r);
    assert!(
        text.contains(
            &"    ladder:  box-footprint is both the cheapest and the most accurate rung \
              (tied in error with box): 6.5 ms, FLIP 0.200, 0.93x box's frame cost; cpu 30.0 \
              ms, 3.75x ray-query, the cheapest exact rung on the device"
                .to_owned()
        ),
        "{text:?}"
    );
    for rung in r.tradeoff.iter_mut().filter(|row| row.scene == SCENE) {
        if rung.rung == "plain" {
            rung.frame_cost_ms = stats(6.0);
            rung.sensor = error(0.3);
        }
    }
    let text = lines(&r);
    let ladder = text.iter().find(|l| l.contains("ladder:")).unwrap();
    assert!(
        ladder.contains(
            "→ box-footprint 6.5 ms 0.200; most accurate: box-footprint (tied in \
             error with box), 0.93x box's frame cost"
        ),
        "{ladder}"
    );
}

/// An animated scene's updates: the dirty rectangles' time and share of the texels against
/// a full update's, and the whole faces' ratio, under the scene's heading.
#[test]
fn the_dirty_rectangles_are_weighed_against_a_full_update() {
    let mut r = known();
    let d = (r.dynamic.iter_mut())
        .find(|d| d.scene == SCENE)
        .expect("the quick baseline measures the thesis room's updates");
    (d.rects_ms_median, d.full_ms_median) = (Some(1.5), Some(12.0));
    (d.ratio, d.whole_faces_ratio, d.texels_ratio) = (Some(0.125), Some(0.25), Some(0.004));
    let text = lines(&r);
    let at = (text.iter())
        .position(|l| l == "  scenes/thesis-room.toml, 64² faces:")
        .expect("the scene's heading");
    assert_eq!(
        text[at + 3],
        "    updates: dirty rectangles 1.5 ms, 0.12x a full update (12.0 ms), 0.4% of its \
         texels; whole dirty faces 0.25x"
    );
    // Without motion (no ratio) there is no line.
    for d in &mut r.dynamic {
        d.ratio = None;
    }
    assert!(!lines(&r).iter().any(|l| l.contains("updates:")));
}
