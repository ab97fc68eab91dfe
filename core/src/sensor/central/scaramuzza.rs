//! Scaramuzza's polynomial model (D. Scaramuzza, A. Martinelli, R. Siegwart, ICVS 2006), in
//! the conventions of his OCamCalib toolbox and its C functions `cam2world` / `world2cam`:
//!
//! - image points are (row, column), 0-based with the centre of the top-left pixel at (0, 0)
//!   ("C convention" in `calib_results.txt`); the centre (xc, yc) is (row, column) too;
//! - a pixel (row, col) becomes (x', y') = [c d; e 1]^-1 (row - xc, col - yc), and its ray is
//!   the direction (x', y', f(rho)) with rho = |(x', y')| and f(rho) = ss0 + ss1 rho + ...
//!   (`cam2world`; the toolbox fits with ss1 = 0, and so do we);
//! - the inverse, `world2cam`, evaluates a second polynomial `invpol` in the elevation
//!   theta = atan(z / |(x, y)|) to get rho directly, instead of solving f for its root.
//!
//! So the model's x axis runs along image rows (down), y along columns (right), and the image
//! centre sees -z when ss0 < 0, as in the toolbox's own results.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::{FitError, Sample};
use crate::sensor::solve::{least_squares, levenberg_marquardt, LmReport, LmSettings};

/// The model as `calib_results.txt` holds it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OcamModel {
    /// f's coefficients, constant first (OCamCalib's `ss`, `pol` in the C code).
    pub ss: Vec<f64>,
    /// rho as a polynomial in theta, constant first (`invpol`).
    pub invpol: Vec<f64>,
    /// The centre: row (`xc`) and column (`yc`), pixels.
    pub xc: f64,
    pub yc: f64,
    /// The affine part [c d; e 1] (sensor misalignment and non-square pixels).
    pub c: f64,
    pub d: f64,
    pub e: f64,
    pub height: u32,
    pub width: u32,
}

/// Degree of f, as OCamCalib's default (coefficients ss0..ss4, ss1 = 0).
pub const POLYNOMIAL_DEGREE: usize = 4;

/// `invpol` grows in degree until it reproduces the exact inverse of f to this many pixels
/// over the image's radii (OCamCalib's `findinvpoly` stops at the same 0.01 px).
pub const INVPOL_TOLERANCE_PX: f64 = 0.01;

/// The highest `invpol` degree tried before giving up.
const INVPOL_MAX_DEGREE: usize = 30;

/// Radii sampled when fitting `invpol`.
const INVPOL_SAMPLES: usize = 2000;

impl OcamModel {
    /// OCamCalib's `cam2world`: the unit direction of image point (row, col).
    pub fn cam2world(&self, point: DVec2) -> DVec3 {
        let inv_det = 1.0 / (self.c - self.d * self.e);
        let (r, c) = (point.x - self.xc, point.y - self.yc);
        let xp = inv_det * (r - self.d * c);
        let yp = inv_det * (-self.e * r + self.c * c);
        let rho = (xp * xp + yp * yp).sqrt();
        DVec3::new(xp, yp, polyval(&self.ss, rho)).normalize()
    }

    /// OCamCalib's `world2cam`: the image point (row, col) of the point `p` (model frame).
    pub fn world2cam(&self, p: DVec3) -> DVec2 {
        let norm = (p.x * p.x + p.y * p.y).sqrt();
        if norm == 0.0 {
            return DVec2::new(self.xc, self.yc);
        }
        let theta = (p.z / norm).atan();
        let rho = polyval(&self.invpol, theta);
        let (x, y) = (p.x / norm * rho, p.y / norm * rho);
        DVec2::new(x * self.c + y * self.d + self.xc, x * self.e + y + self.yc)
    }

    /// Fits centre, affine part and f to the samples (pixels as (row, col)) by minimising the
    /// angle between each pixel's ray and its sample direction, then fits `invpol` up to the
    /// largest radius `rho_max(model)` gives (the image's largest in use: the samples may be
    /// every few pixels of the image). Returns the model, the fit's report, and how far
    /// `invpol` is from f's exact inverse at worst over those radii (pixels): within
    /// [`INVPOL_TOLERANCE_PX`] where a degree up to 30 reaches it, else the best one tried.
    pub fn fit(
        samples: &[Sample],
        width: u32,
        height: u32,
        rho_max: impl Fn(&Self) -> f64,
    ) -> Result<(Self, LmReport, f64), FitError> {
        if samples.len() < 9 {
            return Err(FitError::TooFewPixels(samples.len()));
        }
        // f in a normalised radius rho / scale keeps the coefficients of one magnitude.
        let scale = width.min(height) as f64 / 2.0;
        let (xc, yc) = ((height as f64 - 1.0) / 2.0, (width as f64 - 1.0) / 2.0);
        let b = linear_start(samples, xc, yc, scale)?;
        let mut p = [xc, yc, 1.0, 0.0, 0.0, b[0], b[1], b[2], b[3]];
        let scales = [xc, yc, 1.0, 0.01, 0.01, scale, scale, scale, scale];
        let report = levenberg_marquardt(&mut p, &scales, LmSettings::default(), |p, r| {
            let model = Self::from_params(p, scale, width, height);
            r.clear();
            for s in samples {
                let e = model.cam2world(s.pixel) - s.direction;
                r.extend([e.x, e.y, e.z]);
            }
        });
        let mut model = Self::from_params(&p, scale, width, height);
        let sampled = samples.iter().map(|s| model.radius_of(s.pixel));
        let rho_max = sampled.fold(rho_max(&model), f64::max);
        let (invpol, invpol_error_px) = fit_invpol(&model.ss, rho_max)?;
        model.invpol = invpol;
        Ok((model, report, invpol_error_px))
    }

    /// rho of image point (row, col): its distance from the centre after the affine part.
    pub fn radius_of(&self, point: DVec2) -> f64 {
        let inv_det = 1.0 / (self.c - self.d * self.e);
        let (r, c) = (point.x - self.xc, point.y - self.yc);
        DVec2::new(
            inv_det * (r - self.d * c),
            inv_det * (-self.e * r + self.c * c),
        )
        .length()
    }

    fn from_params(p: &[f64], scale: f64, width: u32, height: u32) -> Self {
        let ss = vec![
            p[5],
            0.0,
            p[6] / scale.powi(2),
            p[7] / scale.powi(3),
            p[8] / scale.powi(4),
        ];
        Self {
            ss,
            invpol: Vec::new(),
            xc: p[0],
            yc: p[1],
            c: p[2],
            d: p[3],
            e: p[4],
            height,
            width,
        }
    }
}

/// Scaramuzza's linear start: with the centre fixed and no affine part, (x', y', f(rho)) is
/// parallel to the direction d when f(rho) d.x = x' d.z and f(rho) d.y = y' d.z, linear in
/// f's coefficients (here of rho / scale, without the linear term).
fn linear_start(samples: &[Sample], xc: f64, yc: f64, scale: f64) -> Result<Vec<f64>, FitError> {
    let (mut a, mut rhs) = (Vec::new(), Vec::new());
    for s in samples {
        let (x, y) = (s.pixel.x - xc, s.pixel.y - yc);
        let t = (x * x + y * y).sqrt() / scale;
        let powers = [1.0, t * t, t * t * t, t * t * t * t];
        for (component, offset) in [(s.direction.x, x), (s.direction.y, y)] {
            a.extend(powers.iter().map(|p| p * component));
            rhs.push(offset * s.direction.z);
        }
    }
    least_squares(&a, &rhs, rhs.len(), 4)
        .ok_or(FitError::NoStart("the linear polynomial fit is singular"))
}

/// OCamCalib's `invpol`: rho as a polynomial in theta = atan(f(rho) / rho), of the lowest
/// degree that matches f's exact inverse within [`INVPOL_TOLERANCE_PX`] on [0, rho_max], and
/// its worst error there (pixels). Where no degree up to [`INVPOL_MAX_DEGREE`] does (a 4096²
/// sphere's rim needs 0.01 px of some 1500), the one that comes closest, its error said:
/// the rest of the calibration does not depend on it.
fn fit_invpol(ss: &[f64], rho_max: f64) -> Result<(Vec<f64>, f64), FitError> {
    let samples: Vec<(f64, f64)> = (0..=INVPOL_SAMPLES)
        .map(|i| rho_max * i as f64 / INVPOL_SAMPLES as f64)
        .map(|rho| (polyval(ss, rho).atan2(rho), rho))
        .collect();
    // theta must grow with rho, or no function of theta gives rho back.
    if samples.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(FitError::NotMonotonic);
    }
    let mut best: Option<(Vec<f64>, f64)> = None;
    for degree in 1..=INVPOL_MAX_DEGREE {
        let cols = degree + 1;
        let a: Vec<f64> = samples
            .iter()
            .flat_map(|&(theta, _)| (0..cols as i32).map(move |k| theta.powi(k)))
            .collect();
        let b: Vec<f64> = samples.iter().map(|&(_, rho)| rho).collect();
        let Some(coeffs) = least_squares(&a, &b, b.len(), cols) else {
            continue;
        };
        let worst = samples
            .iter()
            .map(|&(theta, rho)| (polyval(&coeffs, theta) - rho).abs())
            .fold(0.0, f64::max);
        if worst < INVPOL_TOLERANCE_PX {
            return Ok((coeffs, worst));
        }
        // A degree whose error is not a number is never the best.
        let worst = if worst.is_nan() { f64::INFINITY } else { worst };
        if best.as_ref().is_none_or(|(_, e)| worst < *e) {
            best = Some((coeffs, worst));
        }
    }
    best.ok_or(FitError::Invpol(INVPOL_MAX_DEGREE))
}

/// The polynomial with coefficients `coeffs` (constant first) at `x`, by Horner's rule.
pub fn polyval(coeffs: &[f64], x: f64) -> f64 {
    coeffs.iter().rev().fold(0.0, |acc, c| acc * x + c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model like the sensor's: ss0 < 0 (the centre sees -z), off-centre, slightly affine.
    fn known() -> OcamModel {
        let mut m = OcamModel {
            ss: vec![-120.0, 0.0, 2.1e-3, 4.0e-6, 3.0e-8],
            invpol: Vec::new(),
            xc: 258.4,
            yc: 251.7,
            c: 1.002,
            d: 0.0015,
            e: -0.001,
            height: 512,
            width: 512,
        };
        let error_px;
        (m.invpol, error_px) = fit_invpol(&m.ss, 200.0).unwrap();
        assert!(error_px < INVPOL_TOLERANCE_PX, "{m:?}: {error_px}");
        m
    }

    /// Image points inside radius 200 on a deterministic grid.
    fn points(m: &OcamModel) -> Vec<DVec2> {
        (0..60)
            .flat_map(|i| {
                (0..60).map(move |j| DVec2::new(60.0 + 6.7 * i as f64, 55.0 + 6.9 * j as f64))
            })
            .filter(|&p| m.radius_of(p) < 200.0)
            .collect()
    }

    #[test]
    fn world2cam_inverts_cam2world_within_the_invpol_tolerance() {
        let m = known();
        for p in points(&m) {
            let back = m.world2cam(m.cam2world(p) * 2.5);
            assert!((back - p).length() < INVPOL_TOLERANCE_PX, "{p} -> {back}");
        }
    }

    /// Rays made by a known polynomial model are fitted back to that model.
    #[test]
    fn the_fit_recovers_a_known_polynomial() {
        let truth = known();
        let samples: Vec<Sample> = points(&truth)
            .into_iter()
            .map(|p| Sample {
                pixel: p,
                direction: truth.cam2world(p),
            })
            .collect();
        let (fit, report, _) = OcamModel::fit(&samples, 512, 512, |_| 0.0).unwrap();
        let close = |a: f64, b: f64, rel: f64| (a - b).abs() <= rel * b.abs().max(1e-12);
        assert!(
            close(fit.xc, truth.xc, 1e-7) && close(fit.yc, truth.yc, 1e-7),
            "{fit:?} {report:?}"
        );
        assert!(close(fit.c, truth.c, 1e-7), "{fit:?}");
        assert!(
            (fit.d - truth.d).abs() < 1e-8 && (fit.e - truth.e).abs() < 1e-8,
            "{fit:?}"
        );
        for (i, (a, b)) in fit.ss.iter().zip(&truth.ss).enumerate() {
            assert!(close(*a, *b, 1e-5), "ss{i}: {a} != {b}");
        }
    }
}
