//! The two small solvers the sensor's fits need (the central models, the localisation's
//! position refinement), in f64: linear least squares by Householder QR
//! (stable for the ill-conditioned polynomial bases of OCamCalib's `invpol`, where the normal
//! equations would square the condition number) and Levenberg–Marquardt with a numeric
//! Jacobian (nine parameters at most, so a dense normal-equation step is cheap and exact
//! enough). No crate: both fit on a page and are tested against known answers below.

/// Least-squares solution of `A x ≈ b` for the `rows x cols` matrix `a` (row-major), or None
/// when `a` is rank deficient (a column with no component left after the earlier ones).
pub fn least_squares(a: &[f64], b: &[f64], rows: usize, cols: usize) -> Option<Vec<f64>> {
    assert_eq!(a.len(), rows * cols, "the matrix holds rows * cols values");
    assert_eq!(b.len(), rows, "one right-hand side value per row");
    let (mut a, mut b) = (a.to_vec(), b.to_vec());
    let at = |r: usize, c: usize| r * cols + c;
    // A column counts as dependent when less than this fraction of its norm is left once the
    // earlier columns are taken out.
    const RANK_TOLERANCE: f64 = 1e-12;
    let original: Vec<f64> = (0..cols)
        .map(|c| (0..rows).map(|r| a[at(r, c)].powi(2)).sum::<f64>().sqrt())
        .collect();
    for k in 0..cols {
        // The Householder reflection that zeroes column k below the diagonal.
        let norm = (k..rows).map(|r| a[at(r, k)].powi(2)).sum::<f64>().sqrt();
        if norm == 0.0 || norm <= RANK_TOLERANCE * original[k] {
            return None;
        }
        let alpha = if a[at(k, k)] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = (k..rows).map(|r| a[at(r, k)]).collect();
        v[0] -= alpha;
        let vv: f64 = v.iter().map(|x| x * x).sum();
        if vv == 0.0 {
            continue;
        }
        for c in k..cols {
            let dot: f64 = (k..rows).map(|r| v[r - k] * a[at(r, c)]).sum();
            let f = 2.0 * dot / vv;
            (k..rows).for_each(|r| a[at(r, c)] -= f * v[r - k]);
        }
        let dot: f64 = (k..rows).map(|r| v[r - k] * b[r]).sum();
        let f = 2.0 * dot / vv;
        (k..rows).for_each(|r| b[r] -= f * v[r - k]);
    }
    // Back substitution on the upper triangle R x = Q^T b.
    let mut x = vec![0.0; cols];
    for k in (0..cols).rev() {
        let s: f64 = (k + 1..cols).map(|c| a[at(k, c)] * x[c]).sum();
        x[k] = (b[k] - s) / a[at(k, k)];
    }
    Some(x)
}

/// Solves the small square system `m x = v` (row-major) by the same QR; None when singular.
pub fn solve_square(m: &[f64], v: &[f64]) -> Option<Vec<f64>> {
    let n = v.len();
    least_squares(m, v, n, n)
}

/// When Levenberg–Marquardt stops.
#[derive(Debug, Clone, Copy)]
pub struct LmSettings {
    /// Iterations at most (each one a Jacobian and one or more trial steps).
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub relative_tolerance: f64,
}

impl Default for LmSettings {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            relative_tolerance: 1e-14,
        }
    }
}

/// What a Levenberg–Marquardt run did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmReport {
    pub iterations: usize,
    /// Sum of squared residuals at the start and at the end.
    pub initial_cost: f64,
    pub final_cost: f64,
}

/// Minimises the sum of squares of `residuals(params)` from the start `params` (updated in
/// place). `residuals` fills its output vector, always of the same length. The Jacobian is
/// taken by central differences with a step relative to each parameter (`scales` gives each
/// parameter's typical magnitude, so a parameter that starts at 0 still gets a sensible step),
/// and the damping is Marquardt's, scaled by the Jacobian's diagonal, which makes the step
/// independent of the parameters' units.
pub fn levenberg_marquardt(
    params: &mut [f64],
    scales: &[f64],
    settings: LmSettings,
    residuals: impl Fn(&[f64], &mut Vec<f64>),
) -> LmReport {
    let mut r = Vec::new();
    residuals(params, &mut r);
    let mut cost = sum_sq(&r);
    let initial_cost = cost;
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let mut scratch = Differences::default();
    while iterations < settings.max_iterations {
        iterations += 1;
        let jac = jacobian(params, scales, &residuals, &mut scratch);
        let (jtj, jtr) = normal_equations(&jac, &r);
        let Some(accepted) = damped_step(params, &jtj, &jtr, cost, &mut lambda, &residuals) else {
            break;
        };
        let gain = (cost - accepted.cost) / cost.max(f64::MIN_POSITIVE);
        params.copy_from_slice(&accepted.params);
        r = accepted.residuals;
        cost = accepted.cost;
        if gain < settings.relative_tolerance || cost == 0.0 {
            break;
        }
    }
    LmReport {
        iterations,
        initial_cost,
        final_cost: cost,
    }
}

/// Residual buffers for the two sides of a central difference, kept across iterations.
#[derive(Default)]
struct Differences {
    plus: Vec<f64>,
    minus: Vec<f64>,
}

/// The Jacobian, column by column, by central differences.
fn jacobian(
    params: &[f64],
    scales: &[f64],
    residuals: &impl Fn(&[f64], &mut Vec<f64>),
    scratch: &mut Differences,
) -> Vec<Vec<f64>> {
    let n = params.len();
    let mut jac: Vec<Vec<f64>> = Vec::with_capacity(n);
    for i in 0..n {
        let h = 1e-6 * params[i].abs().max(scales[i]);
        let mut p = params.to_vec();
        p[i] = params[i] + h;
        residuals(&p, &mut scratch.plus);
        p[i] = params[i] - h;
        residuals(&p, &mut scratch.minus);
        jac.push(
            scratch
                .plus
                .iter()
                .zip(&scratch.minus)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect(),
        );
    }
    jac
}

/// `J^T J` (row-major, `n x n`) and `J^T r` from the Jacobian's columns `jac`.
fn normal_equations(jac: &[Vec<f64>], r: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = jac.len();
    let mut jtj = vec![0.0; n * n];
    let mut jtr = vec![0.0; n];
    for i in 0..n {
        jtr[i] = dot(&jac[i], r);
        for j in 0..=i {
            let v = dot(&jac[i], &jac[j]);
            jtj[i * n + j] = v;
            jtj[j * n + i] = v;
        }
    }
    (jtj, jtr)
}

/// A trial point that lowered the cost, with its residuals and cost.
struct Accepted {
    params: Vec<f64>,
    residuals: Vec<f64>,
    cost: f64,
}

/// Damped trial steps until one lowers the cost (or the damping says we are done), adjusting
/// `lambda` as Marquardt does; None when no step within the damping limit helps.
fn damped_step(
    params: &[f64],
    jtj: &[f64],
    jtr: &[f64],
    cost: f64,
    lambda: &mut f64,
    residuals: &impl Fn(&[f64], &mut Vec<f64>),
) -> Option<Accepted> {
    let n = params.len();
    while *lambda < 1e12 {
        let mut damped = jtj.to_vec();
        for i in 0..n {
            damped[i * n + i] += *lambda * jtj[i * n + i].max(1e-30);
        }
        let neg: Vec<f64> = jtr.iter().map(|v| -v).collect();
        let Some(step) = solve_square(&damped, &neg) else {
            *lambda *= 10.0;
            continue;
        };
        let trial: Vec<f64> = params.iter().zip(&step).map(|(p, s)| p + s).collect();
        let mut tr = Vec::new();
        residuals(&trial, &mut tr);
        let trial_cost = sum_sq(&tr);
        if trial_cost.is_finite() && trial_cost < cost {
            *lambda = (*lambda / 10.0).max(1e-12);
            return Some(Accepted {
                params: trial,
                residuals: tr,
                cost: trial_cost,
            });
        }
        *lambda *= 10.0;
    }
    None
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn sum_sq(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An overdetermined line fit with a known answer: y = 2 - 3x exactly.
    #[test]
    fn least_squares_recovers_an_exact_line() {
        let xs = [0.0, 1.0, 2.0, 5.0];
        let a: Vec<f64> = xs.iter().flat_map(|&x| [1.0, x]).collect();
        let b: Vec<f64> = xs.iter().map(|x| 2.0 - 3.0 * x).collect();
        let x = least_squares(&a, &b, 4, 2).unwrap();
        assert!(
            (x[0] - 2.0).abs() < 1e-12 && (x[1] + 3.0).abs() < 1e-12,
            "{x:?}"
        );
        // Two equal columns: rank deficient, no answer rather than a made-up one.
        let a: Vec<f64> = xs.iter().flat_map(|&x| [x, x]).collect();
        assert!(least_squares(&a, &b, 4, 2).is_none());
    }

    /// Rosenbrock's valley as residuals (10 (y - x^2), 1 - x): minimum 0 at (1, 1).
    #[test]
    fn levenberg_marquardt_finds_rosenbrocks_minimum() {
        let mut p = [-1.2, 1.0];
        let report = levenberg_marquardt(&mut p, &[1.0, 1.0], LmSettings::default(), |p, r| {
            r.clear();
            r.extend([10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]]);
        });
        assert!(
            (p[0] - 1.0).abs() < 1e-7 && (p[1] - 1.0).abs() < 1e-7,
            "{p:?}"
        );
        assert!(report.final_cost < 1e-14 && report.initial_cost > 1.0);
    }
}
