//! The column-shift descriptor: a low-resolution panorama matched by searching the heading.
//!
//! The appearance-based localisation literature measures the Fourier signature against
//! descriptors that keep the image itself (Payá et al. compare it with rotational PCA, HOG
//! and gist on panoramas; the simplest baseline of all is the panorama at low resolution).
//! A heading only shifts a panorama's columns, so instead of a descriptor that *forgets* the
//! heading (the Fourier magnitudes), this one *searches* it: the distance between two places
//! is the smallest difference of their low-resolution panoramas over every circular column
//! shift, and the shift that gives it is the turn.
//!
//! What this buys over the Fourier signature: the magnitudes of each row's harmonics throw
//! away the phases, so two different places whose rows have the same spectra (the same
//! walls in another order, a pattern mirrored) look alike; the shift search compares the
//! rows' actual layout, and it compares all the rows at *one common* turn, where the
//! magnitudes let every row turn on its own. What it costs: a search of `C` shifts per
//! comparison instead of one subtraction (`C` columns, `C` times `rows` cells each).
//!
//! The panorama is box-filtered to `C = 16 k` columns (`k` the command's `--k`, so that
//! `k = 8` gives 128 columns of 2.8 degrees) and as many rows as keep its aspect ratio, in
//! grey levels like the Fourier signature. The turn is refined below one column by fitting a
//! parabola through the difference at the best shift and its two neighbours.
//!
//! Why 128 columns: measured on two rooms with 600 queries each (docs/sensor.md,
//! "Localisation"), recall@1 rose from 86 % (furnished room) and 92 % (thesis room) at 64
//! columns to 94 % on both at 128, and no further at 192. The misses left are near-ties
//! between neighbouring landmarks; a finer panorama tells the nearer one apart until the
//! descriptor's change over half a grid step is resolved.

use std::f64::consts::TAU;

use super::{luminance, Descriptor, Signature};
use crate::image::RgbaImage;

/// Low-resolution columns per unit of `--k`.
pub const COLUMNS_PER_K: u32 = 16;

/// A panorama box-filtered to a few columns, compared over every circular column shift.
#[derive(Debug, Clone, Copy)]
pub struct ColumnShift {
    /// Columns of the low-resolution panorama (at least 1, at most the panorama's width).
    pub columns: u32,
}

impl ColumnShift {
    /// The descriptor for `--k`: `16 k` columns.
    pub fn for_k(k: u32) -> Self {
        Self {
            columns: k.saturating_mul(COLUMNS_PER_K),
        }
    }

    /// Mean squared difference between `query` and `landmark` turned by `shift` columns
    /// (the query's column `c` against the landmark's column `c - shift`, circularly).
    ///
    /// This is the whole cost of matching (`C` shifts of `C x rows` cells per pair), so each
    /// row is compared as two contiguous runs, without a circular index per cell. Squares
    /// are summed in `f64` (as before the runs were split), so that a turn by whole columns
    /// gives its neighbours' differences equal to within `f64` rounding and the parabola
    /// keeps the turn on the column (to 1e-9 of a turn; an `f32` sum missed that).
    fn difference(landmark: &Signature, query: &Signature, shift: usize) -> f64 {
        let n = query.columns as usize;
        let run = |q: &[f32], l: &[f32]| -> f64 {
            q.iter()
                .zip(l)
                .map(|(&a, &b)| {
                    let d = f64::from(a - b);
                    d * d
                })
                .sum()
        };
        let sum: f64 = landmark
            .values
            .chunks_exact(n)
            .zip(query.values.chunks_exact(n))
            .map(|(l, q)| {
                // Query columns [0, shift) meet the landmark's [n - shift, n), the rest its
                // [0, n - shift).
                let (q_head, q_tail) = q.split_at(shift);
                let (l_head, l_tail) = l.split_at(n - shift);
                run(q_head, l_tail) + run(q_tail, l_head)
            })
            .sum();
        sum / query.values.len().max(1) as f64
    }

    /// The low-resolution panorama's columns and rows for a `width` x `height` one: at most
    /// its own columns, and as many rows as keep its aspect ratio (cells stay about square).
    fn cells(&self, width: u32, height: u32) -> (usize, usize) {
        let (w, h) = (width as usize, height as usize);
        let columns = (self.columns as usize).clamp(1, w.max(1));
        let rows = ((h * columns) as f64 / w.max(1) as f64)
            .round()
            .clamp(1.0, h.max(1) as f64) as usize;
        (columns, rows)
    }

    /// The difference at every shift `0 .. columns`.
    fn differences(landmark: &Signature, query: &Signature) -> Vec<f64> {
        (0..query.columns as usize)
            .map(|s| Self::difference(landmark, query, s))
            .collect()
    }
}

/// The mean of `values` over `[start, end)` of a line of `values.len()` cells, each cell
/// weighted by how much of it the interval covers: a box filter with fractional edges.
fn box_average(values: &[f64], start: f64, end: f64) -> f64 {
    let first = start.floor() as usize;
    let last = (end.ceil() as usize).min(values.len());
    let mut sum = 0.0;
    for (i, v) in values.iter().enumerate().take(last).skip(first) {
        let cover = (end.min(i as f64 + 1.0) - start.max(i as f64)).max(0.0);
        sum += cover * v;
    }
    sum / (end - start)
}

/// `line` box-filtered to `cells` equal cells.
fn resample(line: &[f64], cells: usize) -> Vec<f64> {
    let step = line.len() as f64 / cells as f64;
    (0..cells)
        .map(|c| box_average(line, c as f64 * step, (c + 1) as f64 * step))
        .collect()
}

impl Descriptor for ColumnShift {
    fn name(&self) -> &'static str {
        "column-shift"
    }

    fn describe(&self, panorama: &RgbaImage) -> Signature {
        let w = panorama.width as usize;
        let (columns, rows) = self.cells(panorama.width, panorama.height);
        // Columns first (each full-resolution row to `columns` cells), then rows.
        let narrow: Vec<Vec<f64>> = panorama
            .pixels
            .chunks_exact(w)
            .map(|row| {
                let grey: Vec<f64> = row.iter().map(|&p| f64::from(luminance(p))).collect();
                resample(&grey, columns)
            })
            .collect();
        let mut values = vec![0.0f32; rows * columns];
        for c in 0..columns {
            let column: Vec<f64> = narrow.iter().map(|r| r[c]).collect();
            for (r, v) in resample(&column, rows).into_iter().enumerate() {
                values[r * columns + c] = v as f32;
            }
        }
        Signature {
            columns: columns as u32,
            values,
        }
    }

    /// Root-mean-square grey difference at the best turn.
    fn distance(&self, a: &Signature, b: &Signature) -> f64 {
        Self::differences(a, b)
            .into_iter()
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }

    fn shape(&self, width: u32, height: u32) -> (u32, usize) {
        let (columns, rows) = self.cells(width, height);
        (columns as u32, columns * rows)
    }

    /// Every cell at every shift.
    fn pair_cost(&self, width: u32, height: u32) -> u64 {
        let (columns, rows) = self.cells(width, height);
        (columns * columns * rows) as u64
    }

    fn turn(&self, landmark: &Signature, query: &Signature) -> f64 {
        let d = Self::differences(landmark, query);
        let n = d.len();
        let best = (0..n)
            .min_by(|&a, &b| d[a].total_cmp(&d[b]).then(a.cmp(&b)))
            .expect("at least one column");
        // The parabola through the best shift and its neighbours puts the minimum between
        // columns; a flat or one-column search keeps the whole shift.
        let (before, at, after) = (d[(best + n - 1) % n], d[best], d[(best + 1) % n]);
        let curvature = before - 2.0 * at + after;
        let offset = if n >= 3 && curvature > 0.0 {
            (0.5 * (before - after) / curvature).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        ((best as f64 + offset) / n as f64 * TAU).rem_euclid(TAU)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::localise::test_panorama as panorama;

    /// A known small example: a 12 x 3 panorama of column index values, box-filtered to 4
    /// columns and 1 row (3 x 4 aspect), holds the means of each run of three columns.
    #[test]
    fn describe_box_filters_to_the_known_means() {
        let pano = panorama(12, 3, |r, az| {
            let j = (az / TAU * 12.0 - 0.5).round() as f32;
            j + r as f32
        });
        let s = ColumnShift { columns: 4 }.describe(&pano);
        assert_eq!(s.columns, 4);
        // Column means 1, 4, 7, 10, plus the mean row index 1.
        assert_eq!(s.values, vec![2.0, 5.0, 8.0, 11.0]);
    }

    /// Fractional cells: 3 values into 2 cells of 1.5 each.
    #[test]
    fn resample_weights_partly_covered_cells() {
        assert_eq!(resample(&[0.0, 3.0, 6.0], 2), vec![1.0, 5.0]);
    }

    /// Turning the robot by whole low-resolution columns leaves the distance at 0 and gives
    /// back exactly that turn; another place is farther.
    #[test]
    fn a_column_shift_is_invisible_to_the_distance_and_found_by_the_turn() {
        let (width, cols) = (240u32, 24u32);
        let place = |r: u32, az: f64| ((az * f64::from(r + 1)).sin() + az.cos().powi(3)) as f32;
        let a = panorama(width, 40, place);
        let d = ColumnShift { columns: cols };
        let sa = d.describe(&a);
        for cells in [0usize, 1, 7, 23] {
            let mut turned = a.clone();
            for row in turned.pixels.chunks_exact_mut(width as usize) {
                row.rotate_right(cells * (width / cols) as usize);
            }
            let st = d.describe(&turned);
            assert!(d.distance(&sa, &st) < 1e-6, "{cells} cells");
            let want = cells as f64 / f64::from(cols) * TAU;
            let got = d.turn(&sa, &st);
            let err = (got - want + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
            assert!(err.abs() < 1e-9, "{cells} cells: turn {got} vs {want}");
        }
        let other = d.describe(&panorama(width, 40, |r, az| {
            place(r, az) + 0.3 * (2.0 * az).cos() as f32
        }));
        assert!(d.distance(&sa, &other) > 0.05);
    }

    /// A turn between columns comes back to a fraction of a column: the parabola refines it.
    #[test]
    fn a_fractional_turn_is_refined_below_a_column() {
        let cols = 64u32;
        let col = TAU / f64::from(cols);
        let place = |az: f64| az.cos() + 0.5 * (2.0 * az + 0.3).sin();
        let d = ColumnShift { columns: cols };
        let base = d.describe(&panorama(640, 10, |_, az| place(az) as f32));
        for turn in [10.3 * col, 40.5 * col, 1.0] {
            let q = d.describe(&panorama(640, 10, |_, az| place(az - turn) as f32));
            let got = d.turn(&base, &q);
            let err = (got - turn + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
            assert!(err.abs() < 0.1 * col, "turn {turn}: got {got}");
        }
    }

    /// Two places whose every row has the same harmonic magnitudes but another layout (one
    /// row turned against the others) are the same to the Fourier signature and different
    /// here: the shift search compares all rows at one common turn.
    #[test]
    fn rows_turned_independently_are_told_apart_where_fourier_cannot() {
        use super::super::fourier::FourierSignature;
        let place = |r: u32, az: f64, twist: f64| {
            let az = if r == 0 { az - twist } else { az };
            (az.cos() + 0.5 * (3.0 * az).sin()) as f32
        };
        let a = panorama(128, 8, |r, az| place(r, az, 0.0));
        let b = panorama(128, 8, |r, az| place(r, az, 1.5));
        let f = FourierSignature { coefficients: 8 };
        assert!(f.distance(&f.describe(&a), &f.describe(&b)) < 1e-3);
        let s = ColumnShift { columns: 32 };
        assert!(s.distance(&s.describe(&a), &s.describe(&b)) > 0.1);
    }
}
