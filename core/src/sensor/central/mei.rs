//! Mei's unified model (C. Mei and P. Rives, ICRA 2007), as OpenCV's `omnidir` module and
//! Kalibr's `omni` camera implement it: a point is put on the unit sphere around the single
//! viewpoint, seen from a second centre `xi` behind the sphere's centre (which lets one model
//! cover parabolic, hyperbolic and, approximately, other mirrors), then radial–tangential
//! distortion and a pinhole matrix K map it to pixels.
//!
//! Pixel coordinates here are OpenCV's: the centre of the top-left pixel is (0, 0).

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::{FitError, Sample};
use crate::sensor::solve::{levenberg_marquardt, LmReport, LmSettings};

/// The parameters, named as OpenCV names them (K = [fx s cx; 0 fy cy; 0 0 1], xi,
/// D = [k1 k2 p1 p2]); Kalibr's `[xi, fu, fv, pu, pv]` and radtan `[k1, k2, r1, r2]` are the
/// same numbers without the skew.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeiModel {
    pub fx: f64,
    pub fy: f64,
    /// K's skew; 0 in our fits (the sensor's pixel grid is square and Kalibr has no skew).
    pub skew: f64,
    pub cx: f64,
    pub cy: f64,
    pub xi: f64,
    pub k1: f64,
    pub k2: f64,
    pub p1: f64,
    pub p2: f64,
}

/// Newton steps at most when undoing the distortion (it converges in a handful).
const UNDISTORT_ITERATIONS: usize = 50;

/// A projection that fails (the point behind the second centre) costs this many pixels in
/// the fit, so the solver backs away from parameters that lose points.
const LOST_POINT_PX: f64 = 1e4;

impl MeiModel {
    /// The pixel of the point `p` (any length, in the model's frame), as OpenCV's
    /// `omnidir::projectPoints` computes it; None when it lies behind the second centre.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        let s = p.normalize();
        let w = s.z + self.xi;
        // NaN (a zero-length point) is refused with the points behind the second centre.
        if w.is_nan() || w <= 0.0 {
            return None;
        }
        let d = self.distort(DVec2::new(s.x / w, s.y / w));
        Some(DVec2::new(
            self.fx * d.x + self.skew * d.y + self.cx,
            self.fy * d.y + self.cy,
        ))
    }

    /// The unit direction the model gives pixel `px`; None outside the model's image (a
    /// distortion that does not invert, or a radius beyond the sphere's horizon when xi > 1).
    pub fn unproject(&self, px: DVec2) -> Option<DVec3> {
        let yd = (px.y - self.cy) / self.fy;
        let xd = (px.x - self.cx - self.skew * yd) / self.fx;
        let m = self.undistort(DVec2::new(xd, yd))?;
        // Back onto the unit sphere: the near root of |(eta m, eta - xi)| = 1.
        let r2 = m.length_squared();
        let disc = 1.0 + (1.0 - self.xi * self.xi) * r2;
        if disc < 0.0 {
            return None;
        }
        let eta = (self.xi + disc.sqrt()) / (1.0 + r2);
        Some(DVec3::new(eta * m.x, eta * m.y, eta - self.xi))
    }

    /// Radial–tangential distortion of a normalised point (OpenCV's and Kalibr's formula).
    fn distort(&self, u: DVec2) -> DVec2 {
        let r2 = u.length_squared();
        let radial = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
        DVec2::new(
            u.x * radial + 2.0 * self.p1 * u.x * u.y + self.p2 * (r2 + 2.0 * u.x * u.x),
            u.y * radial + self.p1 * (r2 + 2.0 * u.y * u.y) + 2.0 * self.p2 * u.x * u.y,
        )
    }

    /// Inverts [`Self::distort`] by Newton's method with the analytic 2x2 Jacobian.
    fn undistort(&self, d: DVec2) -> Option<DVec2> {
        let (k1, k2, p1, p2) = (self.k1, self.k2, self.p1, self.p2);
        let mut u = d;
        for _ in 0..UNDISTORT_ITERATIONS {
            let e = self.distort(u) - d;
            if e.length() < 1e-15 {
                return Some(u);
            }
            let (x, y) = (u.x, u.y);
            let r2 = u.length_squared();
            let radial = 1.0 + k1 * r2 + k2 * r2 * r2;
            // d(radial)/dx = (2 k1 + 4 k2 r2) x, likewise for y.
            let g = 2.0 * k1 + 4.0 * k2 * r2;
            let (a, b) = (
                radial + g * x * x + 2.0 * p1 * y + 6.0 * p2 * x,
                g * x * y + 2.0 * p1 * x + 2.0 * p2 * y,
            );
            let (c, dd) = (
                g * x * y + 2.0 * p1 * x + 2.0 * p2 * y,
                radial + g * y * y + 6.0 * p1 * y + 2.0 * p2 * x,
            );
            let det = a * dd - b * c;
            if det.abs() < 1e-300 {
                return None;
            }
            u -= DVec2::new((dd * e.x - b * e.y) / det, (a * e.y - c * e.x) / det);
        }
        ((self.distort(u) - d).length() < 1e-9 * (1.0 + d.length())).then_some(u)
    }

    fn from_params(p: &[f64]) -> Self {
        Self {
            fx: p[0],
            fy: p[1],
            skew: 0.0,
            cx: p[2],
            cy: p[3],
            xi: p[4],
            k1: p[5],
            k2: p[6],
            p1: p[7],
            p2: p[8],
        }
    }

    /// Fits the model (skew fixed at 0, as OpenCV's `CALIB_FIX_SKEW`) to the samples by
    /// minimising the reprojection error in pixels, the objective of OpenCV's and Kalibr's
    /// calibrations. Starts from xi = 1 (a parabolic mirror), the principal point at the image
    /// centre, no distortion, and the focal length that fits best under those.
    pub fn fit(samples: &[Sample], width: u32, height: u32) -> Result<(Self, LmReport), FitError> {
        if samples.len() < 9 {
            return Err(FitError::TooFewPixels(samples.len()));
        }
        let (cx, cy) = ((width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0);
        let start = Self {
            fx: 1.0,
            fy: 1.0,
            skew: 0.0,
            cx,
            cy,
            xi: 1.0,
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
        };
        // With f = 1 the projection is the normalised point; the best f is then linear.
        let (mut num, mut den) = (0.0, 0.0);
        for s in samples {
            if let Some(m) = start.project(s.direction) {
                let m = m - DVec2::new(cx, cy);
                num += m.dot(s.pixel - DVec2::new(cx, cy));
                den += m.length_squared();
            }
        }
        if den.is_nan() || den <= 0.0 {
            return Err(FitError::NoStart("no sample projects with xi = 1"));
        }
        let f = num / den;
        let residuals = |p: &[f64], r: &mut Vec<f64>| {
            let model = Self::from_params(p);
            r.clear();
            for s in samples {
                let e = model
                    .project(s.direction)
                    .map_or(DVec2::splat(LOST_POINT_PX), |px| px - s.pixel);
                r.extend([e.x, e.y]);
            }
        };
        let scales = [f, f, cx, cy, 1.0, 0.1, 0.1, 0.01, 0.01];
        // First without distortion. A central mirror at its camera's focus is exactly this
        // model (Geyer and Daniilidis; Mei and Rives's table 1), and there the distortion
        // terms could only trade off against xi along a valley of nearly equal cost, moving
        // xi away from the mirror's own value for a gain far below any pixel.
        let mut plain = [f, f, cx, cy, 1.0];
        let plain_fit =
            levenberg_marquardt(&mut plain, &scales[..5], LmSettings::default(), |p, r| {
                residuals(&[p[0], p[1], p[2], p[3], p[4], 0.0, 0.0, 0.0, 0.0], r)
            });
        let mut p = [
            plain[0], plain[1], plain[2], plain[3], plain[4], 0.0, 0.0, 0.0, 0.0,
        ];
        let pairs = 2.0 * samples.len() as f64;
        if (plain_fit.final_cost / pairs).sqrt() <= DISTORTION_FREE_RMS_PX {
            return Ok((Self::from_params(&p), plain_fit));
        }
        let mut report = levenberg_marquardt(&mut p, &scales, LmSettings::default(), residuals);
        report.iterations += plain_fit.iterations;
        report.initial_cost = plain_fit.initial_cost;
        Ok((Self::from_params(&p), report))
    }
}

/// The reprojection error (RMS, pixels) below which the fit keeps the model without
/// distortion: a thousandth of a pixel, a hundred times below what corner detection resolves
/// in a real calibration, so the terms it would add model nothing a user can measure.
pub const DISTORTION_FREE_RMS_PX: f64 = 1e-3;

#[cfg(test)]
mod tests {
    use super::*;

    /// A model like the ones the sensor gives (xi near 1, strong barrel distortion), with
    /// tangential terms and unequal focal lengths so every parameter matters.
    fn known() -> MeiModel {
        MeiModel {
            fx: 210.0,
            fy: 205.0,
            skew: 0.0,
            cx: 250.3,
            cy: 262.8,
            xi: 1.02,
            k1: -0.21,
            k2: 0.035,
            p1: 0.0012,
            p2: -0.0008,
        }
    }

    /// Directions over the sphere down to 140 degrees from the axis (the sensor sees to
    /// about 156), on a deterministic spiral.
    fn directions(n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let t = (i as f64 + 0.5) / n as f64;
                let theta = t.sqrt() * 140f64.to_radians();
                let phi = i as f64 * 2.399963229728653; // the golden angle
                DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                )
            })
            .collect()
    }

    #[test]
    fn projection_and_unprojection_are_inverse() {
        let m = known();
        for d in directions(500) {
            let px = m.project(d * 3.7).expect("in the model's field of view");
            let back = m.unproject(px).expect("the pixel unprojects");
            assert!((back - d).length() < 1e-10, "{d} -> {px} -> {back}");
        }
    }

    /// Pixels made by a known model are fitted back to that model's parameters.
    #[test]
    fn the_fit_recovers_a_known_model() {
        let truth = known();
        let samples: Vec<Sample> = directions(4000)
            .into_iter()
            .map(|d| Sample {
                pixel: truth.project(d).unwrap(),
                direction: d,
            })
            .collect();
        let (fit, report) = MeiModel::fit(&samples, 512, 512).unwrap();
        let pairs = [
            (fit.fx, truth.fx, 1e-4),
            (fit.fy, truth.fy, 1e-4),
            (fit.cx, truth.cx, 1e-5),
            (fit.cy, truth.cy, 1e-5),
            (fit.xi, truth.xi, 1e-6),
            (fit.k1, truth.k1, 1e-6),
            (fit.k2, truth.k2, 1e-6),
            (fit.p1, truth.p1, 1e-8),
            (fit.p2, truth.p2, 1e-8),
        ];
        for (i, (got, want, tol)) in pairs.into_iter().enumerate() {
            assert!(
                (got - want).abs() < tol,
                "parameter {i}: {got} != {want}\n{fit:?}\n{report:?}"
            );
        }
    }
}
