//! The one percentile definition every median and percentile of the project uses (the FLIP
//! p99, the angular error's p99, the benchmark's median / p10 / p90, `render.json`'s medians).
//!
//! **Nearest rank**: the `p` percentile of `n` values is the `ceil(p n)`-th smallest (1-based),
//! and the smallest for `p = 0`. Chosen because its answer is always one of the measured values
//! (no interpolation inventing a time nobody measured), it needs no convention for ties, and it
//! is the textbook definition a reader can check by counting. The median of an even count is
//! therefore the lower of the two middle values, not their mean.

/// `p n` closer than this (relative to `n`) to a whole number counts as that number, so that
/// `0.07 * 100` (7.000000000000001 in binary floating point) gives the 7th value, not the 8th.
const WHOLE_RANK_TOLERANCE: f64 = 1e-9;

/// The 0-based index of the nearest-rank `p` percentile in `n` sorted values; `None` when
/// there are no values or `p` is not in [0, 1].
pub fn rank(n: usize, p: f64) -> Option<usize> {
    if n == 0 || !(0.0..=1.0).contains(&p) {
        return None;
    }
    let exact = p * n as f64;
    let whole = exact.round();
    let rank = if (exact - whole).abs() <= WHOLE_RANK_TOLERANCE * n as f64 {
        whole
    } else {
        exact.ceil()
    };
    // rank is in [0, n]; 0 (only for p = 0) means the smallest value.
    Some((rank as usize).clamp(1, n) - 1)
}

/// The `p` percentile of values already sorted in ascending order (see [`rank`]).
pub fn of_sorted<T: Copy>(sorted: &[T], p: f64) -> Option<T> {
    rank(sorted.len(), p).map(|i| sorted[i])
}

/// Sorts `values` (NaN last, by `f64::total_cmp`) and returns their `p` percentile.
pub fn percentile(values: &mut [f64], p: f64) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    of_sorted(values, p)
}

/// The median by the same definition: the lower middle value of an even count.
pub fn median(values: &mut [f64]) -> Option<f64> {
    percentile(values, 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(values: &[f64], p: f64) -> Option<f64> {
        percentile(&mut values.to_vec(), p)
    }

    #[test]
    fn one_value_is_every_percentile() {
        for p in [0.0, 0.1, 0.5, 0.99, 1.0] {
            assert_eq!(at(&[7.0], p), Some(7.0), "p = {p}");
        }
    }

    #[test]
    fn two_values_median_is_the_lower() {
        assert_eq!(at(&[9.0, 3.0], 0.0), Some(3.0));
        assert_eq!(at(&[9.0, 3.0], 0.5), Some(3.0));
        assert_eq!(at(&[9.0, 3.0], 0.51), Some(9.0));
        assert_eq!(at(&[9.0, 3.0], 0.99), Some(9.0));
        assert_eq!(at(&[9.0, 3.0], 1.0), Some(9.0));
    }

    #[test]
    fn odd_and_even_counts() {
        // 1..=5 shuffled: the median is the middle value.
        let odd = [4.0, 1.0, 5.0, 2.0, 3.0];
        assert_eq!(at(&odd, 0.0), Some(1.0));
        assert_eq!(at(&odd, 0.5), Some(3.0));
        assert_eq!(at(&odd, 0.99), Some(5.0));
        assert_eq!(at(&odd, 1.0), Some(5.0));
        // 1..=4: ceil(0.5 * 4) = 2nd value, the lower middle.
        let even = [4.0, 2.0, 1.0, 3.0];
        assert_eq!(at(&even, 0.5), Some(2.0));
        assert_eq!(at(&even, 0.25), Some(1.0));
        assert_eq!(at(&even, 0.26), Some(2.0));
        assert_eq!(at(&even, 0.99), Some(4.0));
    }

    #[test]
    fn hundred_values_give_the_textbook_ranks() {
        let v: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        assert_eq!(at(&v, 0.99), Some(99.0));
        assert_eq!(at(&v, 0.9), Some(90.0));
        assert_eq!(at(&v, 0.1), Some(10.0));
        // 0.07 * 100 is 7.000000000000001 in floating point: still the 7th value.
        assert_eq!(at(&v, 0.07), Some(7.0));
        let v: Vec<f64> = (1..=101).map(f64::from).collect();
        // ceil(0.99 * 101) = ceil(99.99) = 100.
        assert_eq!(at(&v, 0.99), Some(100.0));
    }

    #[test]
    fn nothing_or_a_bad_p_has_no_percentile() {
        assert_eq!(at(&[], 0.5), None);
        assert_eq!(at(&[1.0], -0.1), None);
        assert_eq!(at(&[1.0], 1.5), None);
        assert_eq!(at(&[1.0], f64::NAN), None);
    }

    #[test]
    fn works_on_sorted_f32_too() {
        assert_eq!(of_sorted(&[0.1f32, 0.2, 0.3], 0.99), Some(0.3));
        assert_eq!(of_sorted::<f32>(&[], 0.99), None);
    }
}
