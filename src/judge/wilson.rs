//! How sure a failure rate is: the organisers fly a submitted test again, so a test that failed once may pass
//! the next time. The Wilson score interval bounds a test's failure rate from its flights; unlike the plain
//! k/n +- z sqrt(p(1-p)/n) it stays within [0, 1] and is not zero-width at 0 of n or n of n.

/// z of a two-sided 90 % interval (the 95th percentile of the standard normal).
pub const Z90: f64 = 1.6449;

/// The Wilson score interval (lower, upper) of a rate of `k` successes in `n` trials at `z`; (0, 1) with no
/// trial. `k` above `n` is taken as `n`.
pub fn wilson_interval(k: usize, n: usize, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (n, p) = (n as f64, k.min(n) as f64 / n as f64);
    let z2 = z * z;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = z / (1.0 + z2 / n) * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    // Rounding can put a bound a hair outside [0, p] or [p, 1] at k = 0 or k = n.
    ((centre - half).clamp(0.0, p), (centre + half).clamp(p, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn known_values() {
        // 1 of 1 at 90 %: lower = 1 / (1 + z^2).
        let (lo, hi) = wilson_interval(1, 1, Z90);
        assert!((lo - 1.0 / (1.0 + Z90 * Z90)).abs() < 1e-12 && hi == 1.0, "{lo} {hi}");
        // 5 of 10 is symmetric about 0.5: 0.5 +- z sqrt(0.25/10 + z^2/400) / (1 + z^2/10).
        let (lo, hi) = wilson_interval(5, 10, Z90);
        let half = Z90 * (0.025 + Z90 * Z90 / 400.0).sqrt() / (1.0 + Z90 * Z90 / 10.0);
        assert!((lo - (0.5 - half)).abs() < 1e-12 && (hi - (0.5 + half)).abs() < 1e-12);
        assert!((lo - 0.2693).abs() < 1e-3 && (hi - 0.7307).abs() < 1e-3, "{lo} {hi}");
        assert_eq!(wilson_interval(0, 0, Z90), (0.0, 1.0));
        assert_eq!(wilson_interval(0, 3, Z90).0, 0.0);
        assert_eq!(wilson_interval(3, 3, Z90).1, 1.0);
        // More flights, narrower: 2 of 2 is less sure than 20 of 20.
        assert!(wilson_interval(2, 2, Z90).0 < wilson_interval(20, 20, Z90).0);
    }

    proptest! {
        #[test]
        fn the_interval_holds_the_rate_within_0_and_1(n in 0usize..500, k in 0usize..500, z in 0.0f64..4.0) {
            let k = k.min(n);
            let (lo, hi) = wilson_interval(k, n, z);
            prop_assert!((0.0..=1.0).contains(&lo) && (0.0..=1.0).contains(&hi), "{lo} {hi}");
            prop_assert!(lo <= hi);
            if n > 0 {
                let p = k as f64 / n as f64;
                prop_assert!(lo <= p && p <= hi, "{lo} {p} {hi}");
            }
        }
    }
}
