//! The benchmark's answer, printed before its tables: per scene and face size, which fill
//! method was fastest and by how much against six-pass and the floors (the thesis's question:
//! six passes or one), and the trade-off ladder's Pareto front in one line with what the most
//! accurate rung costs against `box` (the design's other question: cost against error), and
//! for an animated scene what its dirty rectangles cost against a full update.
//! Everything comes from the record; nothing here measures.

use super::record::{FloorRow, MethodRow, Record, RungRow};
use specchio::render::floors::Floor;
use specchio::render::methods::Method;

/// The answer's lines: a heading, then per scene and face size a fill line, a ladder line and
/// an updates line (each left out when its part did not run).
pub fn lines(record: &Record) -> Vec<String> {
    let d = &record.device;
    let mut out = vec![format!(
        "the answer on {} ({}{}), median times:",
        d.name,
        d.short_name,
        d.mesa_version
            .as_deref()
            .map_or(String::new(), |v| format!(" {v}")),
    )];
    for scene in &record.settings.scenes {
        // The dynamic face size is always among the run's sizes.
        for &size in &record.settings.cube_sizes {
            let fill = fill_line(record, scene, size);
            let ladder = ladder_line(record, scene, size);
            let updates = updates_line(record, scene, size);
            if fill.is_none() && ladder.is_none() && updates.is_none() {
                continue;
            }
            out.push(format!("  {scene}, {size}² faces:"));
            out.extend(fill.map(|l| format!("    fill:    {l}")));
            out.extend(ladder.map(|l| format!("    ladder:  {l}")));
            out.extend(updates.map(|l| format!("    updates: {l}")));
        }
    }
    out
}

/// `dirty rectangles 1.3 ms, 0.11x a full update (12.3 ms), 0.3% of its texels; whole dirty
/// faces 0.21x`: what the animated scene's on-change updates cost (six-pass), from the frames
/// with motion.
fn updates_line(record: &Record, scene: &str, size: u32) -> Option<String> {
    let d = (record.dynamic.iter()).find(|d| d.scene == scene && d.cube_size == size)?;
    let (ratio, whole, texels) = (d.ratio?, d.whole_faces_ratio?, d.texels_ratio?);
    Some(format!(
        "dirty rectangles {:.1} ms, {ratio:.2}x a full update ({:.1} ms), {:.1}% of its \
         texels; whole dirty faces {whole:.2}x",
        d.rects_ms_median?,
        d.full_ms_median?,
        100.0 * texels
    ))
}

/// `multiview is fastest: 41.2 ms a cube update, 0.78x six-pass (52.8 ms), 1.9x the floors`.
fn fill_line(record: &Record, scene: &str, size: u32) -> Option<String> {
    let rows: Vec<(&MethodRow, f64)> = record
        .results
        .iter()
        .filter(|r| r.scene == scene && r.cube_size == size)
        .filter_map(|r| Some((r, r.wall_ms?.median)))
        .collect();
    let &(fastest, ms) = rows.iter().min_by(|a, b| a.1.total_cmp(&b.1))?;
    let mut line = if rows.len() == 1 {
        format!("{} alone: {ms:.1} ms a cube update", fastest.method)
    } else {
        format!("{} is fastest: {ms:.1} ms a cube update", fastest.method)
    };
    let six = rows.iter().find(|(r, _)| r.method == Method::SIX_PASS);
    match six {
        Some((_, six_ms)) if fastest.method != Method::SIX_PASS => {
            line += &format!(", {:.2}x six-pass ({six_ms:.1} ms)", ms / six_ms);
        }
        Some(_) if rows.len() > 1 => line += " (every one-pass method is slower)",
        _ => {}
    }
    if let Some(x) = fastest.efficiency.vs_geometry_plus_fill {
        let floors = floor_ms(record, scene, size, Floor::Geometry)
            .zip(floor_ms(record, scene, size, Floor::Fill))
            .map(|(g, f)| g + f);
        line += &format!(", {x:.2}x the floors");
        if let Some(f) = floors {
            line += &format!(" (geometry + fill {f:.1} ms)");
        }
    }
    let identical = record
        .accuracy
        .iter()
        .filter(|a| a.scene == scene && a.cube_size == size)
        .map(|a| a.methods_identical)
        .reduce(|a, b| a && b);
    match identical {
        Some(true) if rows.len() > 1 => line += "; same pixels",
        Some(false) => line += "; the methods' pixels DIFFER (see the tables)",
        _ => {}
    }
    Some(line)
}

fn floor_ms(record: &Record, scene: &str, size: u32, floor: Floor) -> Option<f64> {
    record
        .floors
        .iter()
        .find(|f: &&FloorRow| f.scene == scene && f.cube_size == size && f.floor == floor)
        .and_then(|f| Some(f.wall_ms?.median))
}

/// `front plain 6.0 ms FLIP 0.300 → box 7.0 ms 0.200 → ray-query 9.0 ms 3.0e-4; most
/// accurate: ray-query, 1.29x box's frame cost`, or, when one rung is the whole front, that
/// it is both the cheapest and the most accurate; then what the host's tracer costs against
/// the device ([`host_clause`]). Costs are ms per sensor frame.
fn ladder_line(record: &Record, scene: &str, size: u32) -> Option<String> {
    let rungs: Vec<(&RungRow, f64, f64)> = record
        .tradeoff
        .iter()
        .filter(|r| r.scene == scene && r.cube_size == size)
        .filter_map(|r| Some((r, r.frame_cost_ms?.median, r.sensor.as_ref()?.flip_mean?)))
        .collect();
    // The device's own front: the host's tracer, exact by construction, is weighed against
    // it apart ([`host_clause`]).
    let device: Vec<&(&RungRow, f64, f64)> =
        rungs.iter().filter(|p| p.0.lookup.is_some()).collect();
    let points: Vec<(f64, f64)> = device.iter().map(|p| (p.1, p.2)).collect();
    let on_front = crate::tradeoff::pareto_front(&points);
    let mut front: Vec<&(&RungRow, f64, f64)> = (device.into_iter().zip(on_front))
        .filter_map(|(p, on)| on.then_some(p))
        .collect();
    front.sort_by(|a, b| a.1.total_cmp(&b.1));
    if front.is_empty() {
        return None;
    }
    let vs_box = |rung: &RungRow, ms: f64| match rungs.iter().find(|p| p.0.rung == "box") {
        Some(&(_, box_ms, _)) if rung.rung != "box" => {
            format!(", {:.2}x box's frame cost", ms / box_ms)
        }
        _ => String::new(),
    };
    // The most accurate rung is the front's last (dearest) point.
    let &&(best, best_ms, best_flip) = front.last()?;
    let tie = tied_clause(&rungs, best, best_flip);
    if front.len() == 1 {
        let line = format!(
            "{} is both the cheapest and the most accurate rung{tie}: {best_ms:.1} ms, FLIP {}{}",
            best.rung,
            flip_text(best_flip),
            vs_box(best, best_ms)
        );
        return Some(line + &host_clause(&rungs));
    }
    let steps: Vec<String> = front
        .iter()
        .enumerate()
        .map(|(i, (r, ms, flip))| {
            let flip = if i == 0 {
                format!("FLIP {}", flip_text(*flip))
            } else {
                flip_text(*flip)
            };
            format!("{} {ms:.1} ms {flip}", r.rung)
        })
        .collect();
    let line = format!(
        "front {}; most accurate: {}{tie}{}",
        steps.join(" → "),
        best.rung,
        vs_box(best, best_ms)
    );
    Some(line + &host_clause(&rungs))
}

/// ` (tied in error with box)`: the other device rungs whose sensor error is `best`'s to the
/// last bit, or nothing. A rung dearer at the same error is off the front, and the front's
/// rung would otherwise be called the most accurate alone where it only ties (box-footprint's
/// images are box's, bit for bit, and which of the two costs less is often the machine's
/// noise).
fn tied_clause(rungs: &[(&RungRow, f64, f64)], best: &RungRow, best_flip: f64) -> String {
    let tied: Vec<&str> = (rungs.iter())
        .filter(|p| p.0.lookup.is_some() && p.0.rung != best.rung && p.2 == best_flip)
        .map(|p| p.0.rung.as_str())
        .collect();
    if tied.is_empty() {
        return String::new();
    }
    format!(" (tied in error with {})", tied.join(", "))
}

/// Whether `row` is a device rung that traces every mirror ray (exact as the host's tracer
/// is, its image differing from the reference only where the device rasterizes the room).
fn traced_on_device(row: &RungRow) -> bool {
    (row.lookup).is_some_and(|l| !specchio::render::lookups::plugin(l).uses_cube())
}

/// `; cpu 120.3 ms, 3.47x bvh, the cheapest exact rung on the device`, or `; cpu 120.3 ms,
/// 0.41x bvh: the host wins` when the host's tracer (exact by construction) costs less than
/// every device rung that traces ([`traced_on_device`]); `: the only exact rung here` when
/// none was measured; empty when the host's tracer was not measured.
fn host_clause(rungs: &[(&RungRow, f64, f64)]) -> String {
    let Some(&(_, host_ms, _)) = rungs.iter().find(|p| p.0.lookup.is_none()) else {
        return String::new();
    };
    let exact = (rungs.iter())
        .filter(|p| traced_on_device(p.0))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    match exact {
        Some(&(device, ms, _)) if host_ms < ms => format!(
            "; {} {host_ms:.1} ms, {:.2}x {}: the host wins",
            crate::host::LABEL,
            host_ms / ms,
            device.rung
        ),
        Some(&(device, ms, _)) => format!(
            "; {} {host_ms:.1} ms, {:.2}x {}, the cheapest exact rung on the device",
            crate::host::LABEL,
            host_ms / ms,
            device.rung
        ),
        None => format!(
            "; {} {host_ms:.1} ms: the only exact rung here",
            crate::host::LABEL
        ),
    }
}

/// A FLIP value with the digits it needs (errors span 0.3 to 0.0002).
fn flip_text(v: f64) -> String {
    if v == 0.0 {
        "0".to_owned()
    } else if v >= 0.01 {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
}

#[cfg(test)]
mod tests;
