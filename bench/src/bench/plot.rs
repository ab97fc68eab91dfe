//! `--plot FILE.svg`: speed against error, one row of two panels per scene (cube update time
//! against mean FLIP, and against mean angular lookup error), one point per method, face size
//! and lookup mode. Plain SVG, written by hand: no plotting dependency.

use std::fmt::Write as _;

/// One point: a method at a face size with a lookup mode.
pub struct Point {
    pub method: String,
    pub cube_size: u32,
    pub lookup: String,
    pub ms: f64,
    pub flip_mean: f64,
    pub angular_mean_deg: f64,
}

const PANEL_W: f64 = 420.0;
const PANEL_H: f64 = 260.0;
const MARGIN: (f64, f64, f64, f64) = (60.0, 20.0, 30.0, 45.0); // left, right, top, bottom
const COLOURS: [&str; 6] = [
    "#1b6ca8", "#d1495b", "#2a9d8f", "#e9a23b", "#6a4c93", "#555555",
];

/// A value axis: linear from 0, or logarithmic (decades).
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
}

impl Axis {
    fn fit(values: &[f64], log: bool) -> Axis {
        let finite: Vec<f64> = values
            .iter()
            .copied()
            .filter(|v| v.is_finite() && (!log || *v > 0.0))
            .collect();
        let max = finite.iter().copied().fold(f64::MIN, f64::max);
        let min = finite.iter().copied().fold(f64::MAX, f64::min);
        if finite.is_empty() {
            return Axis {
                lo: if log { 1.0 } else { 0.0 },
                hi: 10.0,
                log,
            };
        }
        if log {
            let lo = 10f64.powf(min.log10().floor());
            let hi = 10f64.powf(max.log10().ceil()).max(lo * 10.0);
            Axis { lo, hi, log }
        } else {
            Axis {
                lo: 0.0,
                hi: if max > 0.0 { max * 1.1 } else { 1.0 },
                log,
            }
        }
    }

    /// Position in [0, 1] along the axis.
    fn at(&self, v: f64) -> f64 {
        if self.log {
            (v.max(self.lo).log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        }
    }

    fn ticks(&self) -> Vec<f64> {
        if self.log {
            let mut t = Vec::new();
            let mut v = self.lo;
            while v <= self.hi * 1.0001 {
                t.push(v);
                v *= 10.0;
            }
            t
        } else {
            (0..=4)
                .map(|i| self.lo + (self.hi - self.lo) * f64::from(i) / 4.0)
                .collect()
        }
    }
}

fn label(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

/// Escapes text for SVG.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[allow(clippy::too_many_arguments)]
fn panel(
    out: &mut String,
    (ox, oy): (f64, f64),
    points: &[Point],
    y: fn(&Point) -> f64,
    y_log: bool,
    title: &str,
    y_label: &str,
    methods: &[String],
) {
    let (l, r, t, b) = MARGIN;
    let (w, h) = (PANEL_W - l - r, PANEL_H - t - b);
    let xs: Vec<f64> = points.iter().map(|p| p.ms).collect();
    let ys: Vec<f64> = points.iter().map(y).collect();
    let (ax, ay) = (Axis::fit(&xs, true), Axis::fit(&ys, y_log));
    let px = |v: f64| ox + l + ax.at(v) * w;
    let py = |v: f64| oy + t + (1.0 - ay.at(v)) * h;
    let _ = writeln!(
        out,
        r##"<text x="{:.1}" y="{:.1}" font-size="13" font-weight="bold">{}</text>"##,
        ox + l,
        oy + t - 10.0,
        esc(title)
    );
    let _ = writeln!(
        out,
        r##"<rect x="{:.1}" y="{:.1}" width="{w:.1}" height="{h:.1}" fill="none" stroke="#999"/>"##,
        ox + l,
        oy + t
    );
    for v in ax.ticks() {
        let x = px(v);
        let _ = writeln!(
            out,
            r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" font-size="10" text-anchor="middle">{}</text>"##,
            oy + t,
            oy + t + h,
            oy + t + h + 14.0,
            label(v)
        );
    }
    for v in ay.ticks() {
        let yy = py(v);
        let _ = writeln!(
            out,
            r##"<line x1="{:.1}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" font-size="10" text-anchor="end">{}</text>"##,
            ox + l,
            ox + l + w,
            ox + l - 4.0,
            yy + 3.0,
            label(v)
        );
    }
    let _ = writeln!(
        out,
        r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">cube update, ms (log)</text>"##,
        ox + l + w / 2.0,
        oy + t + h + 32.0
    );
    let _ = writeln!(
        out,
        r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle" transform="rotate(-90 {:.1} {:.1})">{}</text>"##,
        ox + 14.0,
        oy + t + h / 2.0,
        ox + 14.0,
        oy + t + h / 2.0,
        esc(y_label)
    );
    for p in points {
        let (x, yv) = (p.ms, y(p));
        if !(x.is_finite() && yv.is_finite()) || (y_log && yv <= 0.0) {
            continue;
        }
        let colour =
            COLOURS[methods.iter().position(|m| *m == p.method).unwrap_or(0) % COLOURS.len()];
        let (cx, cy) = (px(x), py(yv));
        let tip = format!(
            "{} {}² {}: {:.2} ms, {:.4}",
            p.method, p.cube_size, p.lookup, x, yv
        );
        let shape = if p.lookup == "box" {
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="8" height="8" fill="{colour}" fill-opacity="0.8">"##,
                cx - 4.0,
                cy - 4.0
            )
        } else {
            format!(
                r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="4.5" fill="{colour}" fill-opacity="0.8">"##
            )
        };
        let end = if p.lookup == "box" {
            "</rect>"
        } else {
            "</circle>"
        };
        let _ = writeln!(out, "{shape}<title>{}</title>{end}", esc(&tip));
        let _ = writeln!(
            out,
            r##"<text x="{:.1}" y="{:.1}" font-size="9" fill="#444">{}</text>"##,
            cx + 6.0,
            cy - 4.0,
            p.cube_size
        );
    }
}

/// The whole figure: `scenes` in order, each with its points.
pub fn svg(scenes: &[(String, Vec<Point>)]) -> String {
    let mut methods: Vec<String> = Vec::new();
    for (_, pts) in scenes {
        for p in pts {
            if !methods.contains(&p.method) {
                methods.push(p.method.clone());
            }
        }
    }
    let legend_h = 30.0;
    let (width, height) = (
        2.0 * PANEL_W,
        legend_h + PANEL_H * scenes.len().max(1) as f64,
    );
    let mut out = String::new();
    let _ = writeln!(
        out,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif">"##
    );
    let _ = writeln!(out, r##"<rect width="100%" height="100%" fill="white"/>"##);
    let mut x = 10.0;
    for (i, m) in methods.iter().enumerate() {
        let _ = writeln!(
            out,
            r##"<circle cx="{:.1}" cy="15" r="5" fill="{}"/><text x="{:.1}" y="19" font-size="12">{}</text>"##,
            x + 5.0,
            COLOURS[i % COLOURS.len()],
            x + 14.0,
            esc(m)
        );
        x += 24.0 + 8.0 * m.len() as f64;
    }
    let _ = writeln!(
        out,
        r##"<text x="{:.1}" y="19" font-size="12">circle: plain lookup, square: box lookup; labels: face size</text>"##,
        x + 10.0
    );
    for (row, (scene, pts)) in scenes.iter().enumerate() {
        let oy = legend_h + PANEL_H * row as f64;
        panel(
            &mut out,
            (0.0, oy),
            pts,
            |p| p.flip_mean,
            false,
            &format!("{scene}: FLIP"),
            "mean FLIP (sensor view)",
            &methods,
        );
        panel(
            &mut out,
            (PANEL_W, oy),
            pts,
            |p| p.angular_mean_deg,
            true,
            &format!("{scene}: lookup direction"),
            "mean angular error, degrees (log)",
            &methods,
        );
    }
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(method: &str, size: u32, lookup: &str, ms: f64, flip: f64, deg: f64) -> Point {
        Point {
            method: method.into(),
            cube_size: size,
            lookup: lookup.into(),
            ms,
            flip_mean: flip,
            angular_mean_deg: deg,
        }
    }

    #[test]
    fn svg_has_a_mark_per_point_and_is_well_formed() {
        let pts = vec![
            point("six-pass", 128, "plain", 3.0, 0.25, 7.6),
            point("six-pass", 512, "box", 30.0, 0.03, 0.02),
            point("instanced", 512, "plain", 28.0, 0.25, 7.6),
        ];
        let s = svg(&[("thesis-room".into(), pts)]);
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        // Two panels, three points each: 4 circles + 2 squares, plus 2 legend circles.
        assert_eq!(s.matches("<circle").count(), 4 + 2);
        assert_eq!(
            s.matches("<rect x=").count(),
            2 + 2,
            "2 squares + 2 panel frames"
        );
        assert!(s.contains("<title>six-pass 512² box: 30.00 ms, 0.0300</title>"));
    }

    #[test]
    fn axes_fit_their_data() {
        let a = Axis::fit(&[3.0, 30.0], true);
        assert_eq!((a.lo, a.hi), (1.0, 100.0));
        assert!((a.at(10.0) - 0.5).abs() < 1e-12);
        let b = Axis::fit(&[0.5, 1.0], false);
        assert_eq!(b.lo, 0.0);
        assert!(b.hi > 1.0);
        // Non-positive values are left out of a log axis, not a panic.
        let c = Axis::fit(&[0.0, -1.0], true);
        assert!(c.lo > 0.0);
    }
}
