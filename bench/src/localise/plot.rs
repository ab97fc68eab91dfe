//! `localise.svg`: the floor map of one experiment row, drawn with `plotters` (its SVG backend
//! reads no font: text goes into the SVG as `<text>`). Seen from above with equal scales on
//! both axes (x to the right, z down the page, as a plan of the room looks from +Y): the room's
//! outline, every landmark as a small grey dot, every query as a triangle at its true position
//! with a line to the landmark it was matched to, green when that is the nearest landmark
//! (correct at recall@1), red otherwise. Only the queries are triangles (the tests count them).

use anyhow::{anyhow, Result};
use glam::Vec3;
use plotters::prelude::*;
use specchio::scene::Scene;

use super::report::Row;

/// Width of the drawing in pixels; the height follows the room's aspect.
const WIDTH: u32 = 900;
const LABEL_PX: u32 = 16;
const TITLE_PX: u32 = 18;
/// Space for the axis labels and the title around the floor.
const LEFT_PX: u32 = 60;
const BOTTOM_PX: u32 = 50;
const TOP_PX: u32 = 60;
const MARGIN_PX: u32 = 15;
const CORRECT: RGBColor = RGBColor(0x2a, 0x9d, 0x3f);
const WRONG: RGBColor = RGBColor(0xd1, 0x2a, 0x3b);
const LANDMARK: RGBColor = RGBColor(0x80, 0x80, 0x80);

fn drawing<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing the floor map: {e}")
}

/// The floor map of `row` as SVG text; `landmarks` are the database's positions.
pub fn svg(scene: &Scene, landmarks: &[Vec3], row: &Row, title: &str) -> Result<String> {
    let room = &scene.room;
    let (lo, hi) = (
        room.center - room.size_m / 2.0,
        room.center + room.size_m / 2.0,
    );
    let (x, z) = (
        f64::from(lo.x)..f64::from(hi.x),
        f64::from(lo.z)..f64::from(hi.z),
    );
    // Equal aspect: the plot area's height is its width times the room's depth / width.
    let plot_w = WIDTH - LEFT_PX - 2 * MARGIN_PX;
    let plot_h = (f64::from(plot_w) * f64::from(room.size_m.z) / f64::from(room.size_m.x))
        .round()
        .clamp(50.0, 4000.0) as u32;
    let height = plot_h + TOP_PX + BOTTOM_PX + 2 * MARGIN_PX;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", TITLE_PX))
            .margin(MARGIN_PX)
            .x_label_area_size(BOTTOM_PX)
            .y_label_area_size(LEFT_PX)
            // z grows down the page: the plan seen from above.
            .build_cartesian_2d(x.clone(), z.end..z.start)
            .map_err(drawing)?;
        chart
            .configure_mesh()
            .x_desc("x (m); dots: landmarks; triangles: queries, green when matched to the nearest landmark, red when not")
            .y_desc("z (m)")
            .label_style(("sans-serif", LABEL_PX))
            .axis_desc_style(("sans-serif", LABEL_PX))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(drawing)?;
        let corners = [
            (x.start, z.start),
            (x.end, z.start),
            (x.end, z.end),
            (x.start, z.end),
        ];
        let mut outline = corners.to_vec();
        outline.push(corners[0]);
        chart
            .draw_series([PathElement::new(outline, BLACK.stroke_width(2))])
            .map_err(drawing)?;
        let plan = |p: Vec3| (f64::from(p.x), f64::from(p.z));
        chart
            .draw_series(
                landmarks
                    .iter()
                    .map(|&p| Circle::new(plan(p), 2, LANDMARK.filled())),
            )
            .map_err(drawing)?;
        for q in &row.per_query {
            let truth = plan(Vec3::from_array(q.position_m));
            let matched = plan(landmarks[q.matches[0]]);
            let colour = if q.matches[0] == q.nearest_landmark {
                CORRECT
            } else {
                WRONG
            };
            chart
                .draw_series([PathElement::new(
                    vec![truth, matched],
                    colour.stroke_width(1),
                )])
                .map_err(drawing)?;
            chart
                .draw_series([TriangleMarker::new(truth, 5, colour.filled())])
                .map_err(drawing)?;
        }
        root.present().map_err(drawing)?;
    }
    Ok(text)
}

/// The map's title: what was matched against what, and how well.
pub fn title(scene: &str, row: &Row) -> String {
    let s = &row.summary;
    format!(
        "{scene}: landmarks {}, queries {} at {} s: recall@1 {:.1} % ({}), median {:.3} m, {:.2}°",
        row.landmarks_from,
        row.queries_from,
        row.query_time_s,
        100.0 * s.recall_at_1,
        s.recall_at_1_on_map.map_or_else(
            || "no query on the map".to_owned(),
            |r| format!("{:.1} % of {} on the map", 100.0 * r, s.on_map_queries)
        ),
        s.median_position_error_m,
        s.median_heading_error_deg
    )
}
