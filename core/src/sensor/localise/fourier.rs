//! The Fourier signature (Menegatti et al. 2004; Payá et al. 2010): per panorama row, the
//! first `k` coefficients of the discrete Fourier transform along the row.
//!
//! A row is a function of azimuth on a circle. Turning the robot by `h` shifts every row by
//! the same `s = h N / (2 pi)` columns, and a shift only multiplies coefficient `X_k` by
//! `exp(-2 pi i k s / N)`: the *magnitudes* do not change, so they describe the place whatever
//! the heading, and the *phases* carry the heading. Low frequencies hold most of a room's
//! appearance (walls, large objects), so a few coefficients per row are enough to tell places
//! apart.
//!
//! Matching compares magnitudes (Euclidean distance over all rows and coefficients). The turn
//! between two matched panoramas is the shift `s` that maximises their circular
//! cross-correlation restricted to the stored harmonics,
//! `C(s) = sum_k Re(P_k exp(2 pi i k s / N))` with `P_k = sum_rows conj(L_k) Q_k`: a
//! column-shift search done in the Fourier domain, with sub-column resolution.

use std::f64::consts::TAU;

use super::{luminance, Descriptor, Signature};
use crate::image::RgbaImage;

/// The per-row DFT magnitudes (the descriptor) and phases (the heading) of a panorama.
#[derive(Debug, Clone, Copy)]
pub struct FourierSignature {
    /// Coefficients kept per row, `X_0 .. X_{k-1}` (the mean brightness included).
    pub coefficients: u32,
}

/// Samples of `C(s)` over the circle before refining: `C` holds at most `k - 1` cycles, so
/// 32 samples per cycle always bracket the highest peak's hill.
const SAMPLES_PER_HARMONIC: usize = 32;

impl FourierSignature {
    /// Coefficient `k` of row `r` as (re, im).
    fn coefficient(sig: &Signature, kept: usize, r: usize, k: usize) -> (f64, f64) {
        let i = 2 * (r * kept + k);
        (f64::from(sig.values[i]), f64::from(sig.values[i + 1]))
    }

    fn kept(&self, columns: u32) -> usize {
        // Beyond N / 2 coefficients only repeat (a real row's spectrum is conjugate-symmetric).
        (self.coefficients as usize).min(columns as usize / 2 + 1)
    }
}

impl Descriptor for FourierSignature {
    fn name(&self) -> &'static str {
        "fourier"
    }

    fn describe(&self, panorama: &RgbaImage) -> Signature {
        let n = panorama.width as usize;
        let kept = self.kept(panorama.width);
        // The DFT's twiddles exp(-2 pi i k j / N), shared by every row.
        let twiddles: Vec<(f64, f64)> = (0..kept * n)
            .map(|i| {
                let (k, j) = (i / n, i % n);
                let a = -TAU * ((k * j) % n) as f64 / n as f64;
                (a.cos(), a.sin())
            })
            .collect();
        let mut values = Vec::with_capacity(panorama.height as usize * kept * 2);
        for row in panorama.pixels.chunks_exact(n) {
            let grey: Vec<f64> = row.iter().map(|&p| f64::from(luminance(p))).collect();
            for k in 0..kept {
                let t = &twiddles[k * n..(k + 1) * n];
                let (re, im) = grey
                    .iter()
                    .zip(t)
                    .fold((0.0, 0.0), |(re, im), (g, (c, s))| (re + g * c, im + g * s));
                values.extend([re as f32, im as f32]);
            }
        }
        Signature {
            columns: panorama.width,
            values,
        }
    }

    fn distance(&self, a: &Signature, b: &Signature) -> f64 {
        let sum: f64 = a
            .values
            .chunks_exact(2)
            .zip(b.values.chunks_exact(2))
            .map(|(p, q)| {
                let m = f64::from(p[0]).hypot(f64::from(p[1]));
                let n = f64::from(q[0]).hypot(f64::from(q[1]));
                (m - n) * (m - n)
            })
            .sum();
        sum.sqrt()
    }

    fn shape(&self, width: u32, height: u32) -> (u32, usize) {
        (width, height as usize * self.kept(width) * 2)
    }

    /// One magnitude per stored coefficient.
    fn pair_cost(&self, width: u32, height: u32) -> u64 {
        self.shape(width, height).1 as u64 / 2
    }

    fn turn(&self, landmark: &Signature, query: &Signature) -> f64 {
        let kept = self.kept(landmark.columns);
        let rows = landmark.values.len() / (2 * kept);
        // P_k = sum over rows of conj(L_k) Q_k: the cross-power spectrum.
        let p: Vec<(f64, f64)> = (0..kept)
            .map(|k| {
                (0..rows).fold((0.0, 0.0), |(re, im), r| {
                    let (a, b) = Self::coefficient(landmark, kept, r, k);
                    let (c, d) = Self::coefficient(query, kept, r, k);
                    (re + a * c + b * d, im + a * d - b * c)
                })
            })
            .collect();
        // C(phi) at turn angle phi (radians): the correlation with the landmark turned by phi.
        let c = |phi: f64| -> f64 {
            (1..kept)
                .map(|k| {
                    let (s, co) = (k as f64 * phi).sin_cos();
                    p[k].0 * co - p[k].1 * s
                })
                .sum()
        };
        let samples = SAMPLES_PER_HARMONIC * kept.max(2);
        let step = TAU / samples as f64;
        let best = (0..samples)
            .map(|i| i as f64 * step)
            .max_by(|&a, &b| c(a).total_cmp(&c(b)))
            .expect("at least one sample");
        // Golden-section search on the bracketing hill [best - step, best + step].
        let (mut lo, mut hi) = (best - step, best + step);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..60 {
            let (x1, x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if c(x1) < c(x2) {
                lo = x1;
            } else {
                hi = x2;
            }
        }
        // The search ends within some 1e-8 rad of the peak (the hill is flat at its top), on
        // either side: a peak at 0 found at -3e-9 would wrap to just under a full turn (2 pi
        // for no turn at all), so a turn that close to a full one is none.
        let turn = (0.5 * (lo + hi)).rem_euclid(TAU);
        match TAU - turn < FULL_TURN_TOLERANCE {
            true => 0.0,
            false => turn,
        }
    }
}

/// How close to a full turn a found turn is taken as none: far above the search's precision
/// (1e-8 rad) and far below a column of any panorama (a 100,000-column one's is 6e-5 rad).
const FULL_TURN_TOLERANCE: f64 = 1e-6;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::localise::test_panorama as panorama;

    fn magnitudes(s: &Signature) -> Vec<f64> {
        s.values
            .chunks_exact(2)
            .map(|p| f64::from(p[0]).hypot(f64::from(p[1])))
            .collect()
    }

    /// Known answers: a row `a + b cos(az) + c cos(3 az + 1)` over N columns has magnitudes
    /// N a, N b / 2, 0, N c / 2 (grey = the value, since the luminance weights sum to 1).
    #[test]
    fn magnitudes_are_the_rows_harmonics() {
        let n = 64;
        let pano = panorama(n, 1, |_, az| {
            (0.5 + 0.25 * az.cos() + 0.125 * (3.0 * az + 1.0).cos()) as f32
        });
        let m = magnitudes(&FourierSignature { coefficients: 4 }.describe(&pano));
        let want = [32.0, 8.0, 0.0, 4.0];
        for (k, (got, want)) in m.iter().zip(want).enumerate() {
            assert!((got - want).abs() < 1e-3, "X_{k}: {got} vs {want}");
        }
    }

    /// Turning a panorama (a circular shift of its columns) leaves the magnitudes unchanged:
    /// the distance to the unturned one is 0 (to rounding), while another place's is not.
    #[test]
    fn magnitudes_are_invariant_to_a_column_shift() {
        let n = 90;
        let place = |r: u32, az: f64| ((az * f64::from(r + 1)).sin() + az.cos().powi(3)) as f32;
        let a = panorama(n, 5, place);
        let mut shifted = a.clone();
        for row in shifted.pixels.chunks_exact_mut(n as usize) {
            row.rotate_right(17);
        }
        let other = panorama(n, 5, |r, az| place(r, az) + 0.3 * (2.0 * az).cos() as f32);
        let d = FourierSignature { coefficients: 8 };
        let (sa, ss, so) = (d.describe(&a), d.describe(&shifted), d.describe(&other));
        for (x, y) in magnitudes(&sa).iter().zip(magnitudes(&ss)) {
            assert!((x - y).abs() < 1e-3 * (1.0 + x.abs()), "{x} vs {y}");
        }
        assert!(d.distance(&sa, &ss) < 1e-3);
        assert!(d.distance(&sa, &so) > 1.0);
    }

    /// The turn comes back from the phases: a whole-column shift exactly, and a smooth
    /// panorama turned by a fraction of a column to a small part of a column.
    #[test]
    fn turn_is_recovered_from_the_phases() {
        let n = 120u32;
        let col = TAU / f64::from(n);
        let place = |az: f64| az.cos() + 0.5 * (2.0 * az + 0.3).sin() + 0.2 * (5.0 * az).cos();
        let d = FourierSignature { coefficients: 8 };
        let base = d.describe(&panorama(n, 3, |_, az| place(az) as f32));
        for turn in [0.0, 17.0 * col, 100.25 * col, 3.3] {
            // The query at azimuth az shows what the landmark shows at az - turn.
            let q = d.describe(&panorama(n, 3, |_, az| place(az - turn) as f32));
            let got = d.turn(&base, &q);
            let err = (got - turn + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
            assert!(err.abs() < 0.01 * col, "turn {turn}: got {got}");
        }
    }

    /// A panorama against itself has turned by nothing: 0, not the full turn just under 2 pi
    /// that a search ending a hair below 0 wrapped to (6.2831853 at every width tried).
    #[test]
    fn no_turn_is_zero_not_a_full_turn() {
        let d = FourierSignature { coefficients: 8 };
        for n in [64, 128, 360, 1000] {
            let p = d.describe(&panorama(n, 3, |r, az| (az.cos() + 0.1 * r as f64) as f32));
            assert_eq!(d.turn(&p, &p), 0.0, "{n} columns");
        }
    }

    /// Asking for more coefficients than a row has keeps N / 2 + 1 of them.
    #[test]
    fn coefficients_are_capped_at_half_the_row() {
        let pano = panorama(6, 2, |_, az| az.sin() as f32);
        let s = FourierSignature { coefficients: 50 }.describe(&pano);
        assert_eq!(s.values.len(), 2 * 2 * 4);
    }
}
