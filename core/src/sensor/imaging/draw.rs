//! The random draws of a camera's noise: Poisson (photon and dark-current shot noise) and
//! Gaussian (read noise), both from the project's SplitMix64, their logarithms and cosines
//! `libm`'s, so that a seed gives the same frame on every machine and with any dependency's
//! update.

use crate::random::SplitMix64;

/// Below this mean the Poisson draw inverts the distribution directly; at and above it,
/// Hörmann's transformed rejection (PTRS), which needs a mean of at least 10.
const INVERSION_BELOW: f64 = 12.0;

/// A Poisson draw of mean `lambda` (≥ 0, finite).
pub fn poisson(rng: &mut SplitMix64, lambda: f64) -> f64 {
    if lambda <= 0.0 {
        return 0.0;
    }
    if lambda < INVERSION_BELOW {
        return inversion(rng, lambda);
    }
    ptrs(rng, lambda)
}

/// Sequential search from 0: P(0) = e^-λ, P(k) = P(k - 1) λ / k. Cheap for a small mean; the
/// search stops after 1000 steps, where the remaining mass is below f64's reach.
fn inversion(rng: &mut SplitMix64, lambda: f64) -> f64 {
    let mut p = libm::exp(-lambda);
    let mut cumulative = p;
    let u = rng.unit();
    let mut k = 0.0;
    while u > cumulative && k < 1000.0 {
        k += 1.0;
        p *= lambda / k;
        cumulative += p;
    }
    k
}

/// W. Hörmann, "The transformed rejection method for generating Poisson random variables",
/// Insurance: Mathematics and Economics 12 (1993): a uniform is turned into a candidate by a
/// hat function close to the distribution, accepted at once in the hat's body (most draws)
/// and otherwise checked against the exact probability.
fn ptrs(rng: &mut SplitMix64, lambda: f64) -> f64 {
    let slam = lambda.sqrt();
    let loglam = libm::log(lambda);
    let b = 0.931 + 2.53 * slam;
    let a = -0.059 + 0.024_83 * b;
    let inv_alpha = 1.1239 + 1.1328 / (b - 3.4);
    let vr = 0.9277 - 3.6224 / (b - 2.0);
    loop {
        let u = rng.unit() - 0.5;
        let v = rng.unit();
        let us = 0.5 - u.abs();
        let k = ((2.0 * a / us + b) * u + lambda + 0.43).floor();
        if us >= 0.07 && v <= vr {
            return k;
        }
        if k < 0.0 || (us < 0.013 && v > us) {
            continue;
        }
        let lhs = libm::log(v) + libm::log(inv_alpha) - libm::log(a / (us * us) + b);
        if lhs <= -lambda + k * loglam - ln_factorial(k) {
            return k;
        }
    }
}

/// ln k! for a whole k ≥ 0: a table below 10, Stirling's series (error below 1e-10) above.
fn ln_factorial(k: f64) -> f64 {
    const SMALL: [f64; 10] = [
        0.0,
        0.0,
        std::f64::consts::LN_2,
        1.791_759_469_228_055,
        3.178_053_830_347_945_8,
        4.787_491_742_782_046,
        6.579_251_212_010_101,
        8.525_161_361_065_415,
        10.604_602_902_745_25,
        12.801_827_480_081_469,
    ];
    if k < 10.0 {
        return SMALL[k as usize];
    }
    let k2 = k * k;
    (k + 0.5) * libm::log(k) - k
        + 0.5 * libm::log(2.0 * std::f64::consts::PI)
        + (1.0 / 12.0 - (1.0 / 360.0 - 1.0 / (1260.0 * k2)) / k2) / k
}

/// A standard normal draw (Box–Muller, one of its pair: each draw takes two uniforms, so a
/// pixel's draws never depend on whether a neighbour's spare was used).
pub fn normal(rng: &mut SplitMix64) -> f64 {
    let u1 = 1.0 - rng.unit(); // in (0, 1]: ln stays finite
    let u2 = rng.unit();
    (-2.0 * libm::log(u1)).sqrt() * libm::cos(std::f64::consts::TAU * u2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean and variance of `n` draws.
    fn moments(n: usize, mut draw: impl FnMut() -> f64) -> (f64, f64) {
        let xs: Vec<f64> = (0..n).map(|_| draw()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (mean, var)
    }

    #[test]
    fn poisson_draws_have_the_mean_and_variance_of_their_distribution() {
        // On both sides of the switch to PTRS. The bounds are 5 standard errors: of the mean
        // √(λ/n); of the variance λ·√(2/n) (close enough for these λ, whose excess kurtosis
        // 1/λ adds under 10 %).
        let n = 200_000;
        for (i, lambda) in [0.3, 4.0, 11.9, 12.0, 50.0, 1000.0, 30_000.0]
            .iter()
            .enumerate()
        {
            let mut rng = SplitMix64::new(7 + i as u64);
            let (mean, var) = moments(n, || poisson(&mut rng, *lambda));
            let se_mean = (lambda / n as f64).sqrt();
            let se_var = lambda * (2.0 / n as f64).sqrt() * (1.0 + 1.0 / lambda).sqrt();
            assert!(
                (mean - lambda).abs() < 5.0 * se_mean,
                "λ {lambda}: mean {mean}"
            );
            assert!(
                (var - lambda).abs() < 5.0 * se_var,
                "λ {lambda}: variance {var}"
            );
        }
    }

    #[test]
    fn poisson_probabilities_match_at_a_small_mean() {
        // Frequencies of 0..=5 at λ = 2 against e^-2 2^k / k!, within 5 standard errors.
        let n = 200_000;
        let mut rng = SplitMix64::new(3);
        let mut counts = [0usize; 6];
        for _ in 0..n {
            let k = poisson(&mut rng, 2.0) as usize;
            if k < 6 {
                counts[k] += 1;
            }
        }
        for (k, c) in counts.iter().enumerate() {
            let p = (-2.0f64).exp() * 2f64.powi(k as i32) / ln_factorial(k as f64).exp();
            let f = *c as f64 / n as f64;
            assert!(
                (f - p).abs() < 5.0 * (p * (1.0 - p) / n as f64).sqrt(),
                "{k}: {f} vs {p}"
            );
        }
    }

    #[test]
    fn stirlings_series_meets_the_table() {
        let exact = |k: u32| (1..=k).map(|i| f64::from(i).ln()).sum::<f64>();
        for k in [10u32, 11, 20, 170] {
            assert!((ln_factorial(f64::from(k)) - exact(k)).abs() < 1e-9 * exact(k));
        }
    }

    #[test]
    fn normal_draws_are_standard() {
        let n = 200_000;
        let mut rng = SplitMix64::new(11);
        let (mean, var) = moments(n, || normal(&mut rng));
        assert!(mean.abs() < 5.0 / (n as f64).sqrt(), "{mean}");
        assert!((var - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt(), "{var}");
    }
}
