//! `--plot FILE.svg`, drawn with `plotters` (its SVG backend; no font is read: the text goes
//! into the SVG as `<text>` and the viewer's default sans-serif draws it). One row per scene:
//!
//! - left, **the trade-off**: every rung as a labelled point, x = frame cost (GPU ms per
//!   sensor frame, linear from 0), y = sensor mean FLIP against the reference, logarithmic
//!   (the rungs span orders of magnitude in error, not in cost); one colour per face size, and that size's Pareto front
//!   as a line through its points in order of cost;
//! - right, **the fill methods**: each method's median cube update time per face size (the
//!   methods give the same images, so only their times differ).
//!
//! Labels are placed greedily beside their points, trying a few positions until one overlaps
//! neither an earlier label nor the panel's edge (the hand-written SVG before it overlapped
//! labels).

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::record::{Record, RungRow};

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
/// The title suffix of each scene's trade-off panel (the tests count panels by it).
pub const TRADEOFF_TITLE: &str = "frame cost against sensor error";

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

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

/// A log axis's range covering `values` (positive ones) with some room.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return 0.1..10.0;
    }
    lo / 2.0..hi * 2.0
}

/// A short number for a tick label.
fn tick(v: f64) -> String {
    match v.abs() {
        0.0 => "0".to_owned(),
        a if a >= 100.0 => format!("{v:.0}"),
        a if a >= 1.0 => format!("{v:.1}"),
        a if a >= 0.01 => format!("{v:.2}"),
        a if a >= 0.001 => format!("{v:.3}"),
        _ => format!("{v:.0e}"),
    }
}

fn tradeoff_panel(area: &Area, scene: &str, rungs: &[&RungRow], sizes: &[u32]) -> Result<()> {
    let title = format!("{scene}: {TRADEOFF_TITLE}");
    // A point needs both a cost and an error; a FLIP of exactly 0 cannot sit on a log axis
    // and is drawn at the axis's floor (its label says 0).
    let points: Vec<(&RungRow, f64, f64)> = rungs
        .iter()
        .filter_map(|r| Some((*r, r.frame_cost_ms?.median, r.sensor.as_ref()?.flip_mean?)))
        .collect();
    if points.is_empty() {
        area.titled(&title, ("sans-serif", TITLE_PX))
            .map_err(drawing)?;
        area.draw(&Text::new(
            "no trade-off point: the rungs' error was not measured (--no-accuracy), \
             or no rung ran (--no-tradeoff)",
            (20, 60),
            ("sans-serif", LABEL_PX),
        ))
        .map_err(drawing)?;
        return Ok(());
    }
    let x_max = points.iter().map(|p| p.1).fold(0.0, f64::max);
    let ys = log_range(points.iter().map(|p| p.2));
    // Headroom above the worst point: the legend sits there, clear of the points and labels.
    let ys = ys.start..ys.end * 8.0;
    let floor = ys.start;
    let mut chart = ChartBuilder::on(area)
        .caption(&title, ("sans-serif", TITLE_PX))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..x_max * 1.15, ys.log_scale())
        .map_err(drawing)?;
    chart
        .configure_mesh()
        .x_desc("GPU ms per sensor frame (cube update + sensor view)")
        .y_desc("sensor mean FLIP")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", LABEL_PX))
        .axis_desc_style(("sans-serif", LABEL_PX))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(drawing)?;
    let mut placed: Vec<Rect> = Vec::new();
    for &size in sizes {
        let colour = size_colour(sizes, size);
        let here: Vec<(&RungRow, f64, f64)> = points
            .iter()
            .filter(|p| p.0.cube_size == size)
            .map(|&(r, x, y)| (r, x, y.max(floor)))
            .collect();
        if here.is_empty() {
            continue;
        }
        let mut front: Vec<(f64, f64)> = here
            .iter()
            .filter(|p| p.0.pareto == Some(true))
            .map(|p| (p.1, p.2))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(front, colour.stroke_width(2)))
            .map_err(drawing)?
            .label(format!("{size}² faces: Pareto front"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2)));
        chart
            .draw_series(here.iter().map(|p| {
                let style = if p.0.pareto == Some(true) {
                    colour.filled()
                } else {
                    colour.stroke_width(2)
                };
                Circle::new((p.1, p.2), 5, style)
            }))
            .map_err(drawing)?;
        for (r, x, y) in &here {
            let zero = r.sensor.as_ref().and_then(|v| v.flip_mean) == Some(0.0);
            let text = format!("{} {size}²{}", r.rung, if zero { " (FLIP 0)" } else { "" });
            let at = chart.backend_coord(&(*x, *y));
            let spot = place(&text, at, &placed, area_rect(area));
            area_root_text(area, &text, spot.origin(), colour)?;
            placed.push(spot);
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font(("sans-serif", LABEL_PX))
        .draw()
        .map_err(drawing)?;
    Ok(())
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
    let max = rows.iter().map(|r| r.2).fold(0.0, f64::max);
    let n = methods.len().max(1);
    let mut chart = ChartBuilder::on(area)
        .caption(&title, ("sans-serif", TITLE_PX))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(110)
        .build_cartesian_2d(0.0..(max * 1.15).max(1e-3), -0.5..n as f64 - 0.5)
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
            .draw_series(
                rows.iter()
                    .filter(|r| r.1 == size)
                    .map(|&(i, _, ms)| Circle::new((ms, i as f64 + dy), 5, colour.filled())),
            )
            .map_err(drawing)?
            .label(format!("{size}² faces"))
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, colour.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font(("sans-serif", LABEL_PX))
        .draw()
        .map_err(drawing)?;
    Ok(())
}

/// A label's box in pixels: left, top, right, bottom.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rect(i32, i32, i32, i32);

impl Rect {
    fn overlaps(&self, o: &Rect) -> bool {
        self.0 < o.2 && o.0 < self.2 && self.1 < o.3 && o.1 < self.3
    }
    fn inside(&self, o: &Rect) -> bool {
        self.0 >= o.0 && self.1 >= o.1 && self.2 <= o.2 && self.3 <= o.3
    }
    /// Where the text is drawn (its top-left corner).
    fn origin(&self) -> (i32, i32) {
        (self.0, self.1)
    }
}

fn area_rect(area: &Area) -> Rect {
    let (x, y) = area.get_base_pixel();
    let (w, h) = area.dim_in_pixel();
    Rect(x, y, x + w as i32, y + h as i32)
}

/// The first of a few spots around the point `at` whose box overlaps no `placed` one and lies
/// within `bounds` (the first spot when none does). The width is estimated: about 0.6 em a
/// character in a sans-serif font.
fn place(text: &str, at: (i32, i32), placed: &[Rect], bounds: Rect) -> Rect {
    let w = (text.chars().count() as f64 * f64::from(LABEL_PX) * 0.6).ceil() as i32;
    let h = LABEL_PX as i32 + 2;
    let (x, y) = at;
    let spots = [
        (x + 8, y - h / 2),
        (x + 8, y - h - 4),
        (x + 8, y + 4),
        (x - w - 8, y - h / 2),
        (x - w - 8, y - h - 4),
        (x - w - 8, y + 4),
        (x - w / 2, y - h - 8),
        (x - w / 2, y + 8),
    ];
    let rect = |(l, t): (i32, i32)| Rect(l, t, l + w, t + h);
    spots
        .iter()
        .map(|&s| rect(s))
        .find(|r| r.inside(&bounds) && placed.iter().all(|p| !p.overlaps(r)))
        .unwrap_or_else(|| rect(spots[0]))
}

/// Draws `text` with its top-left corner at the absolute pixel `at`.
fn area_root_text(area: &Area, text: &str, at: (i32, i32), colour: RGBColor) -> Result<()> {
    let (bx, by) = area.get_base_pixel();
    let style = TextStyle::from(("sans-serif", LABEL_PX).into_font()).color(&colour);
    area.draw(&Text::new(text.to_owned(), (at.0 - bx, at.1 - by), style))
        .map_err(drawing)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_avoid_each_other_and_the_edges() {
        let bounds = Rect(0, 0, 400, 300);
        let first = place("box 64²", (100, 100), &[], bounds);
        assert!(first.0 > 100, "right of the point first: {first:?}");
        // A second point at the same spot takes another place.
        let second = place("plain 64²", (100, 100), &[first], bounds);
        assert!(!second.overlaps(&first), "{first:?} {second:?}");
        // Near the right edge the label goes to the left of the point.
        let left = place("ray-query 512²", (395, 100), &[], bounds);
        assert!(left.2 < 395 && left.inside(&bounds), "{left:?}");
    }

    #[test]
    fn log_ranges_cover_positive_values_only() {
        let r = log_range([0.0, 0.01, 1.0, f64::NAN].into_iter());
        assert_eq!(r, 0.005..2.0);
        assert_eq!(log_range(std::iter::empty()), 0.1..10.0);
    }
}
