//! A position between the landmarks, from the descriptor distances around the best match.
//!
//! The best match alone places the robot on the grid: a query near the midpoint of two
//! landmarks is then a coin toss, and more so where the descriptor changes faster along one
//! axis of the floor than along the other (near a wall, the view changes faster towards it).
//! Locally the descriptor is close to linear in the position, `D(p) ~ D(p*) + J (p - p*)` with
//! `p*` the query's position, so the squared descriptor distance of a landmark at `p` is close
//! to the quadratic `(p - p*)^T J^T J (p - p*)`: its minimum is the query's position, however
//! anisotropic `J^T J` is. [`fit_position`] fits that quadratic to the squared distances of the
//! best match and its grid neighbours and returns its minimum. It uses only the descriptor's
//! distances, so it serves every descriptor.

use glam::Vec3;

use crate::sensor::solve::least_squares;

/// Landmarks within this many grid spacings of the best match (on the floor) enter the fit:
/// the best match's 3 x 3 block of the grid.
const NEIGHBOURHOOD: f64 = 1.5;
/// The fitted position stays within this many spacings of the best match along each floor
/// axis, in the best match's cell of the grid: the fit refines the match, it does not
/// overrule it. (Measured: letting it reach into the neighbouring cells raised the median
/// error and the p90, as ill-conditioned fits ran to the edge of their reach; docs/sensor.md.)
const REACH: f64 = 0.5;

/// The floor position (x, z; y kept) of the minimum of the quadratic fitted to `distance`s
/// (one per landmark, in `positions`' order) around the best match `best`, the landmarks
/// `spacing` metres apart. The best match's own position when the fit is not determined:
/// fewer than six neighbours (a corner of the free floor), points on a line, or a fitted
/// surface with no minimum (noise larger than the signal).
pub fn fit_position(positions: &[Vec3], distance: &[f64], best: usize, spacing: f64) -> Vec3 {
    let origin = positions[best];
    // Floor coordinates relative to the best match, in spacings (well-conditioned sums).
    let local = |p: Vec3| {
        (
            f64::from(p.x - origin.x) / spacing,
            f64::from(p.z - origin.z) / spacing,
        )
    };
    let points: Vec<((f64, f64), f64)> = positions
        .iter()
        .zip(distance)
        .map(|(&p, &d)| (local(p), d * d))
        .filter(|&((x, z), _)| x.hypot(z) <= NEIGHBOURHOOD)
        .collect();
    match quadratic_minimum(&points) {
        Some((x, z)) => Vec3::new(
            origin.x + (x.clamp(-REACH, REACH) * spacing) as f32,
            origin.y,
            origin.z + (z.clamp(-REACH, REACH) * spacing) as f32,
        ),
        None => origin,
    }
}

/// The minimum of `f(x, z) = a + b x + c z + d x^2 + e x z + g z^2` fitted to the points
/// `((x, z), f)` by least squares, if the fit is determined and has a minimum.
fn quadratic_minimum(points: &[((f64, f64), f64)]) -> Option<(f64, f64)> {
    if points.len() < 6 {
        return None;
    }
    // Least squares over the six monomials, by the sensor's QR solver.
    let (mut a, mut f) = (
        Vec::with_capacity(6 * points.len()),
        Vec::with_capacity(points.len()),
    );
    for &((x, z), value) in points {
        a.extend([1.0, x, z, x * x, x * z, z * z]);
        f.push(value);
    }
    let coefficients = least_squares(&a, &f, points.len(), 6)?;
    let &[_, b, c, d, e, g] = coefficients.as_slice() else {
        return None;
    };
    // The gradient (b + 2 d x + e z, c + e x + 2 g z) vanishes at the stationary point; it is
    // a minimum when the Hessian [[2d, e], [e, 2g]] is positive definite.
    let det = 4.0 * d * g - e * e;
    if d <= 0.0 || det <= 0.0 {
        return None;
    }
    let x = (e * c - 2.0 * g * b) / det;
    let z = (e * b - 2.0 * d * c) / det;
    Some((x, z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Landmarks on a 5 x 5 grid, `spacing` apart, centred on the origin.
    fn grid(spacing: f32) -> Vec<Vec3> {
        (-2..=2)
            .flat_map(|i| {
                (-2..=2).map(move |j| Vec3::new(i as f32 * spacing, 1.0, j as f32 * spacing))
            })
            .collect()
    }

    /// Distances of a descriptor linear in the position with an anisotropic Jacobian.
    fn distances(positions: &[Vec3], query: Vec3) -> Vec<f64> {
        positions
            .iter()
            .map(|p| {
                let (dx, dz) = (f64::from(p.x - query.x), f64::from(p.z - query.z));
                // J = [[3, 1], [0, 0.5]]: the view changes six times faster along x.
                (3.0 * dx + dz).hypot(0.5 * dz)
            })
            .collect()
    }

    fn best(distance: &[f64]) -> usize {
        (0..distance.len())
            .min_by(|&a, &b| distance[a].total_cmp(&distance[b]))
            .unwrap()
    }

    #[test]
    fn a_linear_descriptor_gives_the_query_position_exactly() {
        let positions = grid(0.5);
        // Queries whose best match is their nearest landmark, (0, 0).
        for query in [
            Vec3::new(-0.1, 1.0, 0.24),
            Vec3::new(-0.05, 1.0, 0.1),
            Vec3::new(0.0, 1.0, 0.0),
        ] {
            let d = distances(&positions, query);
            let found = fit_position(&positions, &d, best(&d), 0.5);
            assert!(found.distance(query) < 1e-5, "{query} -> {found}");
        }
    }

    #[test]
    fn the_fit_moves_towards_the_query_within_the_best_matchs_cell() {
        // The nearest landmark is (0, 0), 0.245 m away; (0, 0.5) is 0.265 m away, but the
        // Jacobian's x-z coupling makes its descriptor distance 0.17 against 0.41: the best
        // match is (0, 0.5). The fit finds the query just outside that landmark's cell and
        // stops on the cell's edge, 0.01 m from the query.
        let positions = grid(0.5);
        let query = Vec3::new(0.05, 1.0, 0.24);
        let d = distances(&positions, query);
        let raw = best(&d);
        assert_eq!(positions[raw], Vec3::new(0.0, 1.0, 0.5));
        let found = fit_position(&positions, &d, raw, 0.5);
        assert!(found.distance(Vec3::new(0.05, 1.0, 0.25)) < 1e-5, "{found}");
    }

    #[test]
    fn too_few_neighbours_or_no_minimum_keep_the_best_match() {
        let positions = grid(0.5);
        // A corner landmark with only its 3 neighbours in reach.
        let corner: Vec<Vec3> = positions
            .iter()
            .copied()
            .filter(|p| p.x <= -0.5 && p.z <= -0.5)
            .collect();
        let d = distances(&corner, Vec3::new(-0.9, 1.0, -0.9));
        let b = best(&d);
        assert_eq!(fit_position(&corner, &d, b, 0.5), corner[b]);
        // Distances that fall away from the centre (a maximum, not a minimum).
        let d: Vec<f64> = positions
            .iter()
            .map(|p| (10.0 - f64::from(p.x * p.x + p.z * p.z)).sqrt())
            .collect();
        let centre = 12; // (0, 0)
        assert_eq!(fit_position(&positions, &d, centre, 0.5), positions[centre]);
    }
}
