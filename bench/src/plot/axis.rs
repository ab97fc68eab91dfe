//! The log axes' ranges and ticks, and the tick labels' numbers.
//!
//! plotters' own log ticks are the powers of ten plus, on a short range, every integer
//! multiple: 10, 100, 1000 on 8..2000 ms, 10, 20, .. 60 on 8..60. These are the densest of
//! the usual series whose labels keep apart: on a 500-pixel axis 10, 20, 50, .. 2000 and
//! 10, 20, 30, 50.

use std::ops::Range;

/// The least ratio a log axis spans, so that even a single point gets two ticks (any range
/// wider than 3 holds two of 1 to 9 times a power of ten).
const MIN_SPAN: f64 = 4.0;

/// A log axis's range covering `values` (the positive, finite ones) with `room` on each side
/// as a factor, at least [`MIN_SPAN`] wide; 0.1..10 when there is no such value.
pub fn log_range(values: impl Iterator<Item = f64>, room: f64) -> Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return 0.1..10.0;
    }
    let widen = (MIN_SPAN / (hi / lo * room * room)).sqrt().max(1.0);
    lo / room / widen..hi * room * widen
}

/// A log axis's ticks: the densest of the usual series (1 to 9, 1-2-3-5, 1-2-5, 1 times the
/// powers of ten) whose neighbours stay apart on an axis `axis_px` long, by `gap_px` and by
/// half of each one's label (`label_px` long along the axis) and air; the sparsest with two
/// ticks if none does.
pub fn log_ticks(
    range: &Range<f64>,
    axis_px: f64,
    gap_px: f64,
    label_px: impl Fn(f64) -> f64,
) -> Vec<f64> {
    const SERIES: [&[f64]; 4] = [
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
        &[1.0, 2.0, 3.0, 5.0],
        &[1.0, 2.0, 5.0],
        &[1.0],
    ];
    const AIR_PX: f64 = 12.0;
    let px_per_ln = axis_px / (range.end / range.start).ln();
    let need = |a: f64, b: f64| gap_px.max((label_px(a) + label_px(b)) / 2.0 + AIR_PX);
    let apart = |t: &Vec<f64>| {
        t.windows(2)
            .all(|w| (w[1] / w[0]).ln() * px_per_ln >= need(w[0], w[1]))
    };
    let all: Vec<Vec<f64>> = SERIES.iter().map(|m| series(range, m)).collect();
    let pick = all.iter().find(|t| t.len() >= 2 && apart(t));
    pick.or_else(|| all.iter().rev().find(|t| t.len() >= 2))
        .unwrap_or(&all[0])
        .clone()
}

/// `mantissas` times every power of ten, within `range`.
fn series(range: &Range<f64>, mantissas: &[f64]) -> Vec<f64> {
    let (first, last) = (range.start.log10().floor(), range.end.log10().ceil());
    // The bounds are the range's own with a rounding error's slack (0.3 is 0.30000000000000004).
    let within = |v: f64| v >= range.start * (1.0 - 1e-9) && v <= range.end * (1.0 + 1e-9);
    (first as i32..=last as i32)
        .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
        .filter(|&v| within(v))
        .collect()
}

/// A short number for a tick label: three significant digits at most, no trailing zeros.
pub fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".to_owned();
    }
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.0e}");
    }
    let decimals = (2 - a.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ranges_cover_positive_values_only() {
        let r = log_range([0.0, 0.01, 1.0, f64::NAN].into_iter(), 2.0);
        assert_eq!(r, 0.005..2.0);
        assert_eq!(log_range(std::iter::empty(), 2.0), 0.1..10.0);
        let none = [0.0, -3.0, f64::NAN, f64::INFINITY];
        assert_eq!(log_range(none.into_iter(), 1.3), 0.1..10.0);
    }

    #[test]
    fn the_cost_range_covers_the_points_with_room() {
        // The crowded scene's spread: cube rungs near 10 ms, tracing near 2 s.
        let costs = [9.7, 12.0, 31.0, 33.5, 36.0, 180.0, 1900.0];
        let r = log_range(costs.into_iter(), 1.3);
        assert!((r.start - 9.7 / 1.3).abs() < 1e-9 && (r.end - 1900.0 * 1.3).abs() < 1e-9);
        // One point, or equal ones: centred on it, MIN_SPAN wide (room alone is 1.69).
        for values in [&[20.0][..], &[20.0, 20.0, 0.0]] {
            let r = log_range(values.iter().copied(), 1.3);
            assert!(
                (r.start - 10.0).abs() < 1e-9 && (r.end - 40.0).abs() < 1e-9,
                "{r:?}"
            );
        }
    }

    #[test]
    fn ticks_are_round_and_apart() {
        // A 500-pixel axis, as the panels have; labels 8 px a character.
        let label = |v: f64| tick(v).len() as f64 * 8.0;
        let ticks = |r: Range<f64>, px, gap| log_ticks(&r, px, gap, label);
        assert_eq!(ticks(8.0..60.0, 500.0, 40.0), [10.0, 20.0, 30.0, 50.0]);
        let wide = ticks(8.0..2000.0, 500.0, 40.0);
        assert_eq!(
            wide,
            [10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0]
        );
        // Too short for 1-2-5 between decades: the powers of ten.
        assert_eq!(ticks(8.0..2000.0, 150.0, 40.0), [10.0, 100.0, 1000.0]);
        // A short range on a long axis: every integer multiple, as wide labels allow.
        assert_eq!(ticks(2.1..8.5, 465.0, 40.0), [3.0, 4.0, 5.0, 6.0, 7.0, 8.0]);
        let wide_labels = log_ticks(&(2.1..8.5), 465.0, 40.0, |_| 80.0);
        assert_eq!(wide_labels, [3.0, 5.0]);
        // FLIP on a 300-pixel axis, a line of text apart.
        let flip: Vec<String> = log_ticks(&(1e-4..0.7), 300.0, 30.0, |_| 0.0)
            .into_iter()
            .map(tick)
            .collect();
        assert_eq!(flip, ["1e-4", "0.001", "0.01", "0.1"]);
        // No series fits on a tiny axis: the sparsest with two ticks.
        assert_eq!(ticks(5.0..20.0, 20.0, 40.0), [5.0, 10.0, 20.0]);
    }

    #[test]
    fn tick_labels_are_short() {
        let labels: Vec<String> = [0.0, 2000.0, 50.0, 1.5, 0.3, 0.005, 1e-4, 2e5]
            .map(tick)
            .to_vec();
        assert_eq!(
            labels,
            ["0", "2000", "50", "1.5", "0.3", "0.005", "1e-4", "2e5"]
        );
    }
}
