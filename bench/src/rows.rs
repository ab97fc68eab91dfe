//! The record's timing rows, made from the timed updates, and their lines in the table.

use specchio::render::floors::Floor;
use specchio::render::methods::Method;
use specchio::scene::Scene;
use specchio::vk::queries::PipelineStats;

use super::record::{Efficiency, FloorRow, MethodRow, Stats, Work};
use super::timing::Timed;

/// Medians of the (clear, fill, geometry) floors' wall times, where measured.
pub type FloorMedians = (Option<f64>, Option<f64>, Option<f64>);

/// The row of one method at one size.
pub fn method_row(
    scene_name: &str,
    scene: &Scene,
    method: Method,
    size: u32,
    timed: &Timed,
    (clear, fill, geometry): FloorMedians,
) -> MethodRow {
    let reports = &timed.reports;
    let wall = Stats::of(reports.iter().map(|r| r.submit_wait_ms).collect());
    // Summed over the updates; `None` where the driver has no pipeline statistics
    // (SwiftShader): such counters are reported absent (null), never zero.
    let work = reports
        .iter()
        .map(|r| r.fill_stats)
        .sum::<Option<PipelineStats>>();
    let per_face = (method == Method::SIX_PASS).then(|| {
        (0..6)
            .map(|f| {
                Stats::of(
                    reports
                        .iter()
                        .filter_map(|r| r.gpu_face_ms.map(|m| m[f]))
                        .collect(),
                )
            })
            .collect()
    });
    let median = wall.map(|w| w.median);
    MethodRow {
        scene: scene_name.to_owned(),
        method,
        cube_size: size,
        updates: reports.len(),
        wall_ms: wall,
        run_medians_ms: timed.run_medians_ms.clone(),
        in_flight_ms: Stats::of(timed.in_flight_ms.clone()),
        cpu_record_ms: Stats::of(reports.iter().map(|r| r.cpu_record_ms).collect()),
        gpu_fill_ms: Stats::of(reports.iter().filter_map(|r| r.gpu_fill_ms).collect()),
        gpu_fill_and_mips_ms: Stats::of(reports.iter().filter_map(|r| r.gpu_cube_ms).collect()),
        gpu_face_ms: per_face,
        fill_stats: reports.last().and_then(|r| r.fill_stats),
        // The room's box adds 12 triangles to the objects'.
        triangles: scene
            .objects
            .iter()
            .map(|o| scene.meshes[o.mesh].triangle_count())
            .sum::<usize>()
            + 12,
        objects: scene.objects.len(),
        work: Work {
            vertex_invocations: work.map(|w| w.vertex_invocations),
            clipping_primitives: work.map(|w| w.clipping_primitives),
            fragment_invocations: work.map(|w| w.fragment_invocations),
            task_invocations: work.and_then(|w| w.task_invocations),
            mesh_invocations: work.and_then(|w| w.mesh_invocations),
            faces_rendered: reports.iter().map(|r| u64::from(r.faces_rendered)).sum(),
            objects_drawn: reports
                .iter()
                .flat_map(|r| r.draws_per_face.iter().map(|&d| u64::from(d)))
                .sum(),
        },
        efficiency: Efficiency {
            vs_geometry_plus_fill: median
                .zip(geometry.zip(fill))
                .map(|(m, (g, f))| m / (g + f)),
            vs_clear: median.zip(clear).map(|(m, c)| m / c),
        },
    }
}

/// The row of one floor at one size.
pub fn floor_row(scene_name: &str, floor: Floor, size: u32, timed: &Timed) -> FloorRow {
    let reports = &timed.reports;
    FloorRow {
        scene: scene_name.to_owned(),
        floor,
        cube_size: size,
        updates: reports.len(),
        wall_ms: Stats::of(reports.iter().map(|r| r.submit_wait_ms).collect()),
        run_medians_ms: timed.run_medians_ms.clone(),
        gpu_fill_ms: Stats::of(reports.iter().filter_map(|r| r.gpu_fill_ms).collect()),
        fill_stats: reports.last().and_then(|r| r.fill_stats),
    }
}

/// The table's header for [`table_row`].
pub fn table_header() -> String {
    format!(
        "  {:<16} {:>9} {:>9} {:>9} {:>10} {:>11} {:>12} {:>14} {:>9}",
        "method",
        "median ms",
        "p10",
        "p90",
        "in flight",
        "GPU fill ms",
        "vertex inv.",
        "fragment inv.",
        "vs floors"
    )
}

/// One line of the table: a method's or a floor's times, counters and efficiency.
pub fn table_row(
    label: &str,
    (wall, in_flight): (Option<Stats>, Option<Stats>),
    gpu_fill: Option<Stats>,
    stats: Option<PipelineStats>,
    vs_floors: Option<f64>,
) -> String {
    let f = |v: Option<f64>| v.map_or("n/a".into(), |x| format!("{x:.2}"));
    let count = |c: Option<u64>| c.map_or("n/a".into(), |c| c.to_string());
    // A mesh pipeline has no vertex shader: its vertex work is its mesh invocations (a pass
    // that ran neither, the clear floor, shows its 0 vertices).
    let vertices = match stats {
        Some(PipelineStats {
            vertex_invocations: 0,
            mesh_invocations: Some(m),
            ..
        }) if m > 0 => format!("{m} mesh"),
        _ => count(stats.map(|s| s.vertex_invocations)),
    };
    format!(
        "  {:<16} {:>9} {:>9} {:>9} {:>10} {:>11} {:>12} {:>14} {:>9}",
        label,
        f(wall.map(|w| w.median)),
        f(wall.map(|w| w.p10)),
        f(wall.map(|w| w.p90)),
        in_flight.map_or(String::new(), |w| format!("{:.2}", w.median)),
        f(gpu_fill.map(|g| g.median)),
        vertices,
        count(stats.map(|s| s.fragment_invocations)),
        vs_floors.map_or(String::new(), |x| format!("{x:.2}x")),
    )
}
