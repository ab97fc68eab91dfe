//! `--plot FILE.svg`, drawn with `plotters` (its SVG backend; no font is read: the text goes
//! into the SVG as `<text>` and the viewer's default sans-serif draws it). One row per scene:
//!
//! - left, **the trade-off**: every rung as a labelled point, x = frame cost (GPU ms per
//!   sensor frame), y = sensor mean FLIP against the reference; one colour per face size,
//!   that size's Pareto front as a line through its points in order of cost, filled markers
//!   on the front, hollow ones off it;
//! - right, **the fill methods**: each method's median cube update time per face size (the
//!   methods give the same images, so only their times differ).
//!
//! Every axis is logarithmic. The rungs span orders of magnitude in error, and on crowded
//! scenes in cost too (ray-query and distance-exact cost 10 to 20 times the cube rungs, which
//! a linear axis squashed into one corner). The methods panel is log for the same two
//! reasons: its face sizes differ by orders of magnitude in fill work, and what one reads off
//! it is a ratio ("multiview takes 0.8 of six-pass"), which a log axis shows as the same
//! distance at every size. Ticks are round numbers that keep apart (`axis`).
//!
//! Labels never overlap one another, a marker or the plotting area's edge: `labels` places
//! them, beside their points where there is room, further out with a leader line where not,
//! and as a last resort lists them in the legend strip. The legend is that strip, drawn by
//! us between the caption and the plot (`legend`): outside the plotting area, so it can cover
//! no point and take no label's room, and of a height we compute (plotters' own legend sits
//! inside the plot, where it covered points, at a size it only estimates).

mod axis;
mod labels;
mod legend;

use std::ops::Range;

use anyhow::{anyhow, Result};
use plotters::coord::combinators::{LogCoord, WithKeyPoints};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::record::{Record, RungRow};
use axis::{log_range, log_ticks, tick};
use labels::{Align, Label, Rect, Spot, MARKER_RADIUS_PX};
use legend::{draw_legend, strip_height, strip_width, Entry, Swatch};

const WIDTH: u32 = 1200;
const ROW_HEIGHT: u32 = 420;
const PALETTE: [RGBColor; 6] = [
    RGBColor(0x1b, 0x6c, 0xa8),
    RGBColor(0xd1, 0x49, 0x5b),
    RGBColor(0x2a, 0x9d, 0x8f),
    RGBColor(0xe9, 0xa2, 0x3b),
    RGBColor(0x6a, 0x4c, 0x93),
    RGBColor(0x55, 0x55, 0x55),
];
/// Font sizes as plotters takes them (it draws text at 1/1.24 of the size given).
const LABEL_PX: u32 = 16;
const TITLE_PX: u32 = 19;
/// The label font's size as drawn, which the label boxes are measured in.
const LABEL_DRAWN_PX: f64 = LABEL_PX as f64 / 1.24;
/// The title suffix of each scene's trade-off panel (the tests count panels by it).
pub const TRADEOFF_TITLE: &str = "frame cost against sensor error";
/// Air around each chart, and the room of the axes' tick labels (the methods panel's y labels
/// are method names, wider than numbers).
const MARGIN_PX: u32 = 12;
const X_LABEL_AREA_PX: u32 = 50;
const TRADEOFF_Y_LABEL_AREA_PX: u32 = 70;
const METHODS_Y_LABEL_AREA_PX: u32 = 110;
/// Room around the points on the log axes, as factors: the cost axis a little (a label that
/// does not fit beside the outermost point goes to its other side), the error axis more (the
/// labels above the worst point need a line).
const COST_ROOM: f64 = 1.3;
const ERROR_ROOM: f64 = 2.0;
/// The least distance between neighbouring ticks: across, enough that the axis does not read
/// as a ruler (and at least their labels' half widths and air, see `axis::log_ticks`); up, a
/// line of text and air.
const X_TICK_GAP_PX: f64 = 40.0;
const Y_TICK_GAP_PX: f64 = 30.0;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type LogAxis = WithKeyPoints<LogCoord<f64>>;
type LogChart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogAxis, LogAxis>>;

/// plotters' errors carry the backend's type; the message is what matters here.
fn drawing<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing the plot: {e}")
}

/// The whole plot as SVG text.
pub fn svg(record: &Record) -> Result<String> {
    let scenes = &record.settings.scenes;
    let mut text = String::new();
    {
        let rows = u32::try_from(scenes.len().max(1))?;
        let root =
            SVGBackend::with_string(&mut text, (WIDTH, ROW_HEIGHT * rows)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        let panels = root.split_evenly((scenes.len().max(1), 2));
        for (scene, pair) in scenes.iter().zip(panels.chunks(2)) {
            let rungs: Vec<&RungRow> = record
                .tradeoff
                .iter()
                .filter(|r| &r.scene == scene)
                .collect();
            tradeoff_panel(&pair[0], scene, &rungs, &record.settings.cube_sizes)?;
            methods_panel(&pair[1], scene, record)?;
        }
        root.present().map_err(drawing)?;
    }
    Ok(text)
}

/// The colour of a face size: its place in the run's list.
fn size_colour(sizes: &[u32], size: u32) -> RGBColor {
    let i = sizes.iter().position(|&s| s == size).unwrap_or(0);
    PALETTE[i % PALETTE.len()]
}

/// A chart's frame in `plot`: margins and the axes' label areas.
fn frame<'a, 'b>(plot: &'a Area<'b>, y_label_px: u32) -> ChartBuilder<'a, 'a, SVGBackend<'b>> {
    let mut builder = ChartBuilder::on(plot);
    builder
        .margin(MARGIN_PX)
        .x_label_area_size(X_LABEL_AREA_PX)
        .y_label_area_size(y_label_px);
    builder
}

/// The plotting area's size inside [`frame`], in pixels, measured by plotters itself.
fn plot_size(plot: &Area, y_label_px: u32) -> Result<(f64, f64)> {
    let probe = frame(plot, y_label_px)
        .build_cartesian_2d(0.0..1.0, 0.0..1.0)
        .map_err(drawing)?;
    let (w, h) = probe.plotting_area().dim_in_pixel();
    Ok((f64::from(w), f64::from(h)))
}

/// A cost axis's ticks, their labels side by side.
fn x_ticks(range: &Range<f64>, axis_px: f64) -> Vec<f64> {
    let label_px = |v: f64| f64::from(labels::text_box(tick(v).len(), LABEL_DRAWN_PX).0);
    log_ticks(range, axis_px, X_TICK_GAP_PX, label_px)
}

/// A chart with log axes over these ranges, ticked for its size.
fn log_chart<'a, 'b>(
    plot: &'a Area<'b>,
    y_label_px: u32,
    xs: &Range<f64>,
    ys: &Range<f64>,
) -> Result<LogChart<'a, 'b>> {
    let (w, h) = plot_size(plot, y_label_px)?;
    let x = (xs.clone().log_scale()).with_key_points(x_ticks(xs, w));
    let y = (ys.clone().log_scale()).with_key_points(log_ticks(ys, h, Y_TICK_GAP_PX, |_| 0.0));
    frame(plot, y_label_px)
        .build_cartesian_2d(x, y)
        .map_err(drawing)
}

/// A rung's point on the trade-off panel.
struct Point {
    size: u32,
    cost_ms: f64,
    /// The sensor's mean FLIP; 0 is drawn at the axis's floor.
    flip: f64,
    front: bool,
    text: String,
    colour: RGBColor,
}

/// The rungs with both a cost and an error, the Pareto front's first (their labels are placed
/// first, nearest their points).
fn trade_points(rungs: &[&RungRow], sizes: &[u32]) -> Vec<Point> {
    let mut points: Vec<Point> = sizes
        .iter()
        .flat_map(|&size| rungs.iter().filter(move |r| r.cube_size == size))
        .filter_map(|r| {
            let flip = r.sensor.as_ref()?.flip_mean?;
            let zero = if flip == 0.0 { " (FLIP 0)" } else { "" };
            Some(Point {
                size: r.cube_size,
                cost_ms: r.frame_cost_ms?.median,
                flip,
                front: r.pareto == Some(true),
                text: format!("{} {}²{zero}", r.rung, r.cube_size),
                colour: size_colour(sizes, r.cube_size),
            })
        })
        .collect();
    points.sort_by_key(|p| !p.front);
    points
}

fn tradeoff_panel(area: &Area, scene: &str, rungs: &[&RungRow], sizes: &[u32]) -> Result<()> {
    let title = format!("{scene}: {TRADEOFF_TITLE}");
    let mut points = trade_points(rungs, sizes);
    let body = area
        .titled(&title, ("sans-serif", TITLE_PX))
        .map_err(drawing)?;
    if points.is_empty() {
        return body
            .draw(&Text::new(
                "no trade-off point: the rungs' error was not measured (--no-accuracy), \
                 or no rung ran (--no-tradeoff)",
                (20, 30),
                ("sans-serif", LABEL_PX),
            ))
            .map_err(drawing);
    }
    let xs = log_range(points.iter().map(|p| p.cost_ms), COST_ROOM);
    let ys = log_range(points.iter().map(|p| p.flip), ERROR_ROOM);
    // A FLIP of exactly 0 cannot sit on a log axis: it is drawn at the floor (its label says 0).
    for p in &mut points {
        p.flip = p.flip.max(ys.start);
    }
    let legend = tradeoff_legend(&points, sizes);
    let width = strip_width(&body, TRADEOFF_Y_LABEL_AREA_PX);
    // The labels with no room in the plot are listed in the strip, which then takes rows from
    // the plot, where the labels are placed again: until the strip holds its list. A list
    // that would take half the panel is drawn as it is, overflowing.
    let mut strip_px = strip_height(&legend, width);
    loop {
        let (strip, plot) = body.split_vertically(strip_px);
        let chart = log_chart(&plot, TRADEOFF_Y_LABEL_AREA_PX, &xs, &ys)?;
        let spots = place_labels(&chart, &points);
        let mut entries = legend.clone();
        entries.extend(listed(&points, &spots));
        let need = strip_height(&entries, width);
        if need <= strip_px || need > body.dim_in_pixel().1 as i32 / 2 {
            draw_tradeoff(area, chart, &points, &spots)?;
            return draw_legend(&strip, &entries, TRADEOFF_Y_LABEL_AREA_PX);
        }
        strip_px = need;
    }
}

/// Every point's label spot, in the plotting area.
fn place_labels(chart: &LogChart, points: &[Point]) -> Vec<Spot> {
    let labels: Vec<Label> = points
        .iter()
        .map(|p| Label {
            at: chart.backend_coord(&(p.cost_ms, p.flip)),
            size: labels::text_box(p.text.chars().count(), LABEL_DRAWN_PX),
        })
        .collect();
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    labels::place(&labels, Rect(xr.start, yr.start, xr.end, yr.end), &[])
}

/// The trade-off's mesh, leaders, fronts, markers and labels (leaders first, under the rest).
fn draw_tradeoff(area: &Area, mut chart: LogChart, points: &[Point], spots: &[Spot]) -> Result<()> {
    chart
        .configure_mesh()
        .x_desc("ms per sensor frame (GPU: cube update + sensor view; cpu: the host)")
        .y_desc("sensor mean FLIP")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", LABEL_PX))
        .axis_desc_style(("sans-serif", LABEL_PX))
        .draw()
        .map_err(drawing)?;
    let (bx, by) = area.get_base_pixel();
    for (p, spot) in points.iter().zip(spots) {
        if let Spot::Leader(_, a, b) = *spot {
            let path = [(a.0 - bx, a.1 - by), (b.0 - bx, b.1 - by)];
            area.draw(&PathElement::new(path, p.colour.mix(0.5).stroke_width(1)))
                .map_err(drawing)?;
        }
    }
    let mut sizes: Vec<u32> = points.iter().map(|p| p.size).collect();
    sizes.sort_unstable();
    sizes.dedup();
    for size in sizes {
        let here = || points.iter().filter(move |p| p.size == size);
        let Some(colour) = here().next().map(|p| p.colour) else {
            continue;
        };
        let mut front: Vec<(f64, f64)> = here()
            .filter(|p| p.front)
            .map(|p| (p.cost_ms, p.flip))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(front, colour.stroke_width(2)))
            .map_err(drawing)?;
        chart
            .draw_series(here().map(|p| {
                let style = if p.front {
                    colour.filled()
                } else {
                    colour.stroke_width(2)
                };
                Circle::new((p.cost_ms, p.flip), MARKER_RADIUS_PX, style)
            }))
            .map_err(drawing)?;
    }
    for (p, spot) in points.iter().zip(spots) {
        if let Some(r) = spot.rect() {
            let (at, align) = r.text_anchor(chart.backend_coord(&(p.cost_ms, p.flip)));
            area_root_text(area, &p.text, at, align, p.colour)?;
        }
    }
    Ok(())
}

/// The trade-off's legend: each face size's front, and the hollow marker.
fn tradeoff_legend(points: &[Point], sizes: &[u32]) -> Vec<Entry> {
    let mut entries: Vec<Entry> = sizes
        .iter()
        .filter(|&&s| points.iter().any(|p| p.size == s))
        .map(|&s| {
            let text = format!("{s}² faces: Pareto front");
            Entry::new(Swatch::Front, text, size_colour(sizes, s))
        })
        .collect();
    if points.iter().any(|p| !p.front) {
        let grey = PALETTE[5];
        entries.push(Entry::new(Swatch::Hollow, "off the front".to_owned(), grey));
    }
    entries
}

/// The labels that found no room, as entries after a heading (none when all found room).
fn listed(points: &[Point], spots: &[Spot]) -> Vec<Entry> {
    let out: Vec<Entry> = points
        .iter()
        .zip(spots)
        .filter(|(_, s)| **s == Spot::Listed)
        .map(|(p, _)| Entry::new(Swatch::None, p.text.clone(), p.colour))
        .collect();
    if out.is_empty() {
        return out;
    }
    let heading = Entry::new(
        Swatch::None,
        "no room beside their points:".to_owned(),
        BLACK,
    );
    std::iter::once(heading).chain(out).collect()
}

fn methods_panel(area: &Area, scene: &str, record: &Record) -> Result<()> {
    let title = format!("{scene}: cube update per fill method");
    let methods = &record.settings.methods;
    let sizes = &record.settings.cube_sizes;
    let rows: Vec<_> = record
        .results
        .iter()
        .filter(|r| r.scene == scene)
        .filter_map(|r| {
            let i = methods.iter().position(|m| *m == r.method)?;
            Some((i, r.cube_size, r.wall_ms?.median))
        })
        .collect();
    let body = area
        .titled(&title, ("sans-serif", TITLE_PX))
        .map_err(drawing)?;
    let legend: Vec<Entry> = sizes
        .iter()
        .filter(|&&s| rows.iter().any(|r| r.1 == s))
        .map(|&s| Entry::new(Swatch::Dot, format!("{s}² faces"), size_colour(sizes, s)))
        .collect();
    let strip_px = strip_height(&legend, strip_width(&body, METHODS_Y_LABEL_AREA_PX));
    let (strip, plot) = body.split_vertically(strip_px);
    let n = methods.len().max(1);
    let xs = log_range(rows.iter().map(|r| r.2), COST_ROOM);
    let (w, _) = plot_size(&plot, METHODS_Y_LABEL_AREA_PX)?;
    let x = (xs.clone().log_scale()).with_key_points(x_ticks(&xs, w));
    let mut chart = frame(&plot, METHODS_Y_LABEL_AREA_PX)
        .build_cartesian_2d(x, -0.5..n as f64 - 0.5)
        .map_err(drawing)?;
    chart
        .configure_mesh()
        .x_desc("median ms per full cube update (submit to fence)")
        .x_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", LABEL_PX))
        .axis_desc_style(("sans-serif", LABEL_PX))
        .y_labels(n)
        .y_label_formatter(&|v| {
            let i = v.round();
            match methods.get(i as usize) {
                Some(m) if (v - i).abs() < 1e-6 && i >= 0.0 => m.name().to_owned(),
                _ => String::new(),
            }
        })
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(drawing)?;
    for (k, &size) in sizes.iter().enumerate() {
        let colour = size_colour(sizes, size);
        // Sizes side by side within a method's row, so that equal times do not hide each other.
        let dy = (k as f64 - (sizes.len() as f64 - 1.0) / 2.0) * 0.18;
        chart
            .draw_series(rows.iter().filter(|r| r.1 == size).map(|&(i, _, ms)| {
                Circle::new((ms, i as f64 + dy), MARKER_RADIUS_PX, colour.filled())
            }))
            .map_err(drawing)?;
    }
    draw_legend(&strip, &legend, METHODS_Y_LABEL_AREA_PX)
}

/// Draws `text` with the top of its `align` end at the absolute pixel `at`.
fn area_root_text(
    area: &Area,
    text: &str,
    at: (i32, i32),
    align: Align,
    colour: RGBColor,
) -> Result<()> {
    let (bx, by) = area.get_base_pixel();
    let h = match align {
        Align::Left => HPos::Left,
        Align::Centre => HPos::Center,
        Align::Right => HPos::Right,
    };
    let style = TextStyle::from(("sans-serif", LABEL_PX).into_font())
        .color(&colour)
        .pos(Pos::new(h, VPos::Top));
    area.draw(&Text::new(text.to_owned(), (at.0 - bx, at.1 - by), style))
        .map_err(drawing)
}

#[cfg(test)]
mod tests;
