//! The regression gate's rules against known verdicts (`gate.rs`).

use super::*;
use crate::record::{Efficiency, RungWork, Work};

fn row(method: &str, wall: f64, vertices: u64) -> MethodRow {
    MethodRow {
        scene: "s.toml".into(),
        method: Method::parse(method).unwrap(),
        cube_size: 64,
        updates: 5,
        wall_ms: Some(Stats {
            median: wall,
            p10: wall,
            p90: wall,
        }),
        run_medians_ms: vec![wall],
        in_flight_ms: None,
        cpu_record_ms: None,
        gpu_fill_ms: None,
        gpu_fill_and_mips_ms: None,
        gpu_face_ms: None,
        fill_stats: None,
        triangles: 12,
        objects: 0,
        work: Work {
            vertex_invocations: Some(vertices),
            clipping_primitives: Some(1),
            fragment_invocations: Some(2),
            task_invocations: None,
            mesh_invocations: None,
            faces_rendered: 30,
            objects_drawn: 40,
        },
        efficiency: Efficiency {
            vs_geometry_plus_fill: None,
            vs_clear: None,
        },
    }
}

/// A baseline that would gate nothing, or whose times make every ratio a nonsense, is
/// refused on reading, naming the field: an empty `results`, a six-pass time of 0, of
/// 5e-324 (every ratio infinite: the time gate off), negative or not a number.
#[test]
fn a_baseline_that_cannot_gate_is_refused() {
    let e = check_baseline(&[]).unwrap_err();
    assert!(e.contains("`results` is empty"), "{e}");
    for bad in [0.0, 5e-324, -3.0, f64::NAN, f64::INFINITY] {
        let rows = [row("six-pass", bad, 1), row("instanced", 2.0, 1)];
        let e = check_baseline(&rows).unwrap_err();
        assert!(
            e.contains("results[0].wall_ms.median") && e.contains("no measured time"),
            "{bad}: {e}"
        );
    }
    assert!(check_baseline(&[row("six-pass", 1e-3, 1)]).is_ok());
    // A run whose own time makes no ratio fails, never passes unseen.
    let base = [row("six-pass", 1.0, 1), row("instanced", 2.0, 1)];
    let run = [row("six-pass", 0.0, 1), row("instanced", 2.0, 1)];
    let f = check(&base, &run, Some(10.0));
    assert!(f.iter().any(|l| l.contains("no ratio to compare")), "{f:?}");
}

/// A case twice in a list is refused, naming both places: the gate read only the first.
#[test]
fn a_baseline_holding_a_case_twice_is_refused() {
    let rows = [
        row("six-pass", 1.0, 1),
        row("instanced", 2.0, 1),
        row("six-pass", 1.0, 999),
    ];
    let e = once_each("results", &rows, MethodRow::case).unwrap_err();
    assert!(
        e.starts_with("results[2] is the case of results[0] again"),
        "{e}"
    );
    assert!(once_each("results", &rows[..2], MethodRow::case).is_ok());
}

#[test]
fn identical_results_pass() {
    let base = vec![row("six-pass", 10.0, 100), row("instanced", 11.0, 100)];
    assert!(check(&base, &base, Some(10.0)).is_empty());
}

#[test]
fn a_changed_counter_fails_and_names_the_case() {
    let base = vec![row("six-pass", 10.0, 100)];
    let new = vec![row("six-pass", 10.0, 101)];
    let f = check(&base, &new, None);
    assert_eq!(f.len(), 1);
    assert!(
        f[0].contains("s.toml / six-pass / 64²") && f[0].contains("vertex_invocations 101"),
        "{f:?}"
    );
}

#[test]
fn a_slower_method_fails_only_beyond_the_limit_and_relative_to_six_pass() {
    let base = vec![row("six-pass", 10.0, 100), row("instanced", 11.0, 100)];
    // The whole machine twice as slow: ratios unchanged, passes.
    let slow_machine = vec![row("six-pass", 20.0, 100), row("instanced", 22.0, 100)];
    assert!(check(&base, &slow_machine, Some(10.0)).is_empty());
    // Instanced 20 % worse relative to six-pass: fails at 10 %, passes at 25 %.
    let worse = vec![row("six-pass", 10.0, 100), row("instanced", 13.2, 100)];
    assert_eq!(check(&base, &worse, Some(10.0)).len(), 1);
    assert!(check(&base, &worse, Some(25.0)).is_empty());
    // Without --max-regression times are not gated.
    assert!(check(&base, &worse, None).is_empty());
}

/// `row` with a time per frame in flight.
fn in_flight(mut r: MethodRow, ms: f64) -> MethodRow {
    r.in_flight_ms = Some(Stats {
        median: ms,
        p10: ms,
        p90: ms,
    });
    r
}

#[test]
fn the_time_in_flight_is_gated_like_the_time_alone_where_both_runs_have_it() {
    let base = vec![
        in_flight(row("six-pass", 10.0, 100), 6.0),
        in_flight(row("instanced", 11.0, 100), 6.0),
    ];
    // Instanced's frame alone unchanged, but 50 % slower among frames in flight.
    let worse = vec![
        in_flight(row("six-pass", 10.0, 100), 6.0),
        in_flight(row("instanced", 11.0, 100), 9.0),
    ];
    let f = check(&base, &worse, Some(10.0));
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(
        f[0].contains("instanced")
            && f[0].contains("1.500x six-pass time with frames in flight (baseline 1.000x)"),
        "{f:?}"
    );
    // A baseline from before the time in flight was measured: that time is not gated.
    let old = vec![row("six-pass", 10.0, 100), row("instanced", 11.0, 100)];
    assert!(check(&old, &worse, Some(10.0)).is_empty());
    // Nor one that kept another number of frames in flight.
    let baseline = Baseline {
        results: base,
        tradeoff: Vec::new(),
        dynamic: Vec::new(),
        driver_name: "llvmpipe".into(),
        driver_info: String::new(),
        frames_in_flight: Some(2),
        bvh_layout: BvhLayout::Cwbvh,
    };
    let (rows, note) = rows_for(&baseline, Some(3));
    assert!(check(&rows, &worse, Some(10.0)).is_empty());
    assert!(note.is_some_and(|n| n.contains("kept 2") && n.contains("this run 3")));
    let (rows, note) = rows_for(&baseline, Some(2));
    assert_eq!(check(&rows, &worse, Some(10.0)).len(), 1);
    assert!(note.is_none());
}

fn rung(label: &str, sensor_fragments: u64) -> RungRow {
    RungRow {
        scene: "s.toml".into(),
        cube_size: 64,
        rung: label.into(),
        lookup: Some(specchio::scene::Lookup::Box),
        frames: 5,
        frame_cost_ms: None,
        gpu_cube_ms: None,
        gpu_sensor_ms: None,
        cpu_lookup_ms: None,
        wall_ms: None,
        work: RungWork {
            faces_rendered: 30,
            fill_vertex_invocations: Some(100),
            fill_fragment_invocations: Some(200),
            sensor_fragment_invocations: Some(sensor_fragments),
            trace: None,
        },
        sensor_traced_fraction: None,
        sensor: None,
        observer: None,
        pareto: None,
    }
}

#[test]
fn rungs_pass_unchanged_and_fail_on_a_changed_or_missing_counter() {
    let base = vec![rung("plain", 50), rung("box", 60)];
    assert!(check_rungs(&base, &base).is_empty());
    let changed = vec![rung("plain", 50), rung("box", 61)];
    let f = check_rungs(&base, &changed);
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(
        f[0].contains("s.toml / rung box / 64²")
            && f[0].contains("sensor_fragment_invocations 61 (baseline 60)"),
        "{f:?}"
    );
    let mut absent = rung("box", 60);
    absent.work.fill_fragment_invocations = None;
    let f = check_rungs(&base, &[rung("plain", 50), absent]);
    assert!(f[0].contains("fill_fragment_invocations null"), "{f:?}");
    let f = check_rungs(&base, &[rung("plain", 50)]);
    assert_eq!(
        f,
        ["s.toml / rung box / 64²: in the baseline but not measured"]
    );
}

/// A traced rung's walk (nodes, objects, triangles) is gated like every counter: the
/// trees or the walk changed.
#[test]
fn a_changed_trace_count_fails() {
    let traced = |nodes| {
        let mut r = rung("bvh", 40);
        r.work.trace = Some(specchio::bvh::Work {
            rays: 100,
            nodes,
            instances: 7,
            triangles: 30,
        });
        r
    };
    assert!(check_rungs(&[traced(250)], &[traced(250)]).is_empty());
    let f = check_rungs(&[traced(250)], &[traced(251)]);
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].contains("trace_nodes 251 (baseline 250)"), "{f:?}");
}

/// A baseline whose bvh rung counted another layout's walk is refused, naming both
/// layouts; one without a counted walk, one in the same layout, and a run without the bvh
/// rung are taken.
#[test]
fn a_baseline_counted_in_another_layout_is_refused() {
    let mut traced = rung("bvh", 100);
    traced.work.trace = Some(specchio::bvh::Work::default());
    let baseline = |tradeoff: Vec<RungRow>, layout: BvhLayout| Baseline {
        results: Vec::new(),
        tradeoff,
        dynamic: Vec::new(),
        driver_name: "llvmpipe".into(),
        driver_info: String::new(),
        frames_in_flight: None,
        bvh_layout: layout,
    };
    let path = Path::new("base.json");
    let other = baseline(vec![traced.clone()], BvhLayout::Cwbvh);
    let err = same_layout(&other, Some(BvhLayout::Bvh4), path);
    assert_eq!(
        err.unwrap_err().to_string(),
        "base.json counted the bvh rung's walk in the cwbvh layout, this run walks bvh4: its \
         trace counters compare only in the same layout (pick it with --bvh-layout, or record \
         a baseline with this one)"
    );
    assert!(same_layout(&other, Some(BvhLayout::Cwbvh), path).is_ok());
    assert!(same_layout(&other, None, path).is_ok());
    let uncounted = baseline(vec![rung("box", 100)], BvhLayout::Cwbvh);
    assert!(same_layout(&uncounted, Some(BvhLayout::Bvh4), path).is_ok());
}

/// An animated scene's update counters are gated where both runs measured it from the
/// same time; one only the run (or only the baseline) has is not compared.
#[test]
fn dynamic_counters_fail_when_changed_and_only_where_both_measured() {
    let dynamic = |from_s: f64, texels: u64| crate::record::Dynamic {
        scene: "s.toml".into(),
        method: Method::SIX_PASS,
        cube_size: 64,
        from_s,
        frames: vec![crate::record::DynamicFrame {
            time_s: from_s,
            faces_incremental: 1,
            faces_full: 6,
            texels_rects: texels,
            texels_full: 6 * 64 * 64,
            rects_ms: 1.0,
            whole_faces_ms: 2.0,
            full_ms: 3.0,
        }],
        changed_frames: 1,
        faces_incremental_median: Some(1.0),
        texels_rects_median: Some(texels as f64),
        rects_ms_median: Some(1.0),
        whole_faces_ms_median: Some(2.0),
        full_ms_median: Some(3.0),
        ratio: None,
        whole_faces_ratio: None,
        texels_ratio: None,
    };
    assert!(check_dynamic(&[dynamic(0.0, 90)], &[dynamic(0.0, 90)]).is_empty());
    let f = check_dynamic(&[dynamic(0.0, 90)], &[dynamic(0.0, 91)]);
    assert_eq!(
        f,
        ["s.toml / dynamic 64² from 0 s: texels_rects 91 (baseline 90)"]
    );
    assert!(check_dynamic(&[dynamic(0.0, 90)], &[dynamic(4.2, 91)]).is_empty());
    assert!(check_dynamic(&[], &[dynamic(0.0, 91)]).is_empty());
}

/// A baseline's scene under another spelling of this run's (`./`, `a/..`, a link) is this
/// run's scene, and gates it; a case only this run measured is named, not passed unseen.
#[test]
fn a_scene_is_matched_by_its_file_and_new_cases_are_named() {
    let dir = std::env::temp_dir().join(format!("specchio-gate-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let file = dir.join("s.toml");
    std::fs::write(&file, "").unwrap();
    let link = dir.join("link.toml");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(&file, &link).unwrap();
    let run = file.display().to_string();
    let d = dir.display();
    let other = dir.join("other.toml").display().to_string();
    std::fs::write(&other, "").unwrap();
    let spellings = [
        (format!("{d}/./s.toml"), &run),
        (format!("{d}/sub/../s.toml"), &run),
        (link.display().to_string(), &run),
        (other.clone(), &other),
    ];
    for (spelt, becomes) in spellings {
        let mut b = baseline_of(vec![MethodRow {
            scene: spelt.clone(),
            ..row("six-pass", 1.0, 1)
        }]);
        spell_as_run(&mut b, std::slice::from_ref(&run));
        assert_eq!(&b.results[0].scene, becomes, "{spelt}");
    }
    // Files that are not there are compared by their spelling without `.` and `a/..`.
    assert_eq!(lexical("./a/b/../c.toml"), Path::new("a/c.toml"));
    assert_eq!(lexical("../x/./y.toml"), Path::new("../x/y.toml"));
    let mut b = baseline_of(vec![MethodRow {
        scene: "./gone/../missing.toml".into(),
        ..row("six-pass", 1.0, 1)
    }]);
    spell_as_run(&mut b, &["missing.toml".into()]);
    assert_eq!(b.results[0].scene, "missing.toml");
    // What the baseline lacks is named.
    let measured = [row("six-pass", 1.0, 1), row("instanced", 1.0, 1)];
    let base = baseline_of(vec![row("six-pass", 1.0, 1)]);
    let new = ungated(&base, (&measured, &[], &[]));
    assert_eq!(new, ["s.toml / instanced / 64²"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A baseline of `results` alone.
fn baseline_of(results: Vec<MethodRow>) -> Baseline {
    Baseline {
        results,
        tradeoff: Vec::new(),
        dynamic: Vec::new(),
        driver_name: "llvmpipe".into(),
        driver_info: String::new(),
        frames_in_flight: None,
        bvh_layout: BvhLayout::Cwbvh,
    }
}
