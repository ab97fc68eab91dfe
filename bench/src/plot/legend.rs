//! A panel's legend strip: between its caption and its plot, outside the plotting area (so it
//! covers no point and takes no label's room), its entries flowed in rows across the plot's
//! width, and its height computed before the plot is laid out.

use anyhow::Result;
use plotters::prelude::*;

use super::labels::{text_box, Align, MARKER_RADIUS_PX};
use super::{area_root_text, drawing, Area, LABEL_DRAWN_PX, MARGIN_PX};

/// A row of the strip: a line of label text and some air.
const LEGEND_ROW_PX: i32 = 22;

/// One entry of a panel's legend strip: a swatch, then its text.
#[derive(Clone)]
pub struct Entry {
    pub swatch: Swatch,
    pub text: String,
    pub colour: RGBColor,
}

#[derive(Clone, Copy, PartialEq)]
pub enum Swatch {
    /// A Pareto front: a line through a filled marker.
    Front,
    /// A point off the front.
    Hollow,
    /// A method's time.
    Dot,
    /// Text alone (the list of labels with no room beside their points).
    None,
}

impl Entry {
    pub fn new(swatch: Swatch, text: String, colour: RGBColor) -> Entry {
        Entry {
            swatch,
            text,
            colour,
        }
    }
    fn swatch_px(&self) -> i32 {
        match self.swatch {
            Swatch::Front => 28,
            Swatch::Hollow | Swatch::Dot => 16,
            Swatch::None => 0,
        }
    }
    /// Its width in the strip, with the air after it.
    fn width_px(&self) -> i32 {
        let (text_w, _) = text_box(self.text.chars().count(), LABEL_DRAWN_PX);
        self.swatch_px() + text_w + 12
    }
}

/// The strip's width: from the plot's left edge to the panel's right margin.
pub fn strip_width(body: &Area, y_label_px: u32) -> i32 {
    (body.dim_in_pixel().0 - 2 * MARGIN_PX - y_label_px) as i32
}

/// Each entry's place in the strip (from its top-left), flowed in rows `width` wide.
fn flow(entries: &[Entry], width: i32) -> Vec<(i32, i32)> {
    let (mut x, mut y) = (0, 0);
    entries
        .iter()
        .map(|e| {
            if x > 0 && x + e.width_px() > width {
                (x, y) = (0, y + LEGEND_ROW_PX);
            }
            let at = (x, y);
            x += e.width_px();
            at
        })
        .collect()
}

/// The strip's height for these entries.
pub fn strip_height(entries: &[Entry], width: i32) -> i32 {
    let rows = flow(entries, width)
        .last()
        .map_or(0, |l| l.1 / LEGEND_ROW_PX + 1);
    rows * LEGEND_ROW_PX
}

/// The legend strip, aligned with the plot's left edge.
pub fn draw_legend(strip: &Area, entries: &[Entry], y_label_px: u32) -> Result<()> {
    let left = (MARGIN_PX + y_label_px) as i32;
    let width = strip_width(strip, y_label_px);
    for (e, (x, y)) in entries.iter().zip(flow(entries, width)) {
        let (x, mid) = (left + x, y + LEGEND_ROW_PX / 2);
        let r = MARKER_RADIUS_PX;
        let c = e.colour;
        let drawn = match e.swatch {
            Swatch::Front => strip
                .draw(&PathElement::new(
                    [(x, mid), (x + 22, mid)],
                    c.stroke_width(2),
                ))
                .and_then(|_| strip.draw(&Circle::new((x + 11, mid), r, c.filled()))),
            Swatch::Hollow => strip.draw(&Circle::new((x + r, mid), r, c.stroke_width(2))),
            Swatch::Dot => strip.draw(&Circle::new((x + r, mid), r, c.filled())),
            Swatch::None => Ok(()),
        };
        drawn.map_err(drawing)?;
        let (bx, by) = strip.get_base_pixel();
        let top = mid - (LABEL_DRAWN_PX / 2.0).round() as i32;
        let at = (bx + x + e.swatch_px(), by + top);
        area_root_text(strip, &e.text, at, Align::Left, c)?;
    }
    Ok(())
}
