//! What the 2026 judge will see of a test: the mean points of its [`JUDGED_FLIGHTS`] flights, as a
//! distribution. The expected points ([`crate::campaign::report::expected::expected_points`]) say what one flight earns
//! on average and how sure that average is; the judge's mean of 5 flights scatters around it as well (a test
//! failing half its flights earns 0 to 5 points on 5 flights). Under the estimate's pseudo-counts the band
//! counts of 5 fresh flights follow a Dirichlet-multinomial, so the distribution is exact: its 56 outcomes
//! are enumerated, no normal approximation.

/// Flights (or pseudo-flights) per points band.
pub type Bands = [f64; 4];

/// The points of each band, best first (the 2026 judge's 5 / 2 / 1 / 0).
pub const BAND_POINTS: [f64; 4] = [5.0, 2.0, 1.0, 0.0];

/// Flights the 2026 judge flies each test and averages.
pub const JUDGED_FLIGHTS: usize = 5;

/// The judge's mean points of a test: 10 % and 90 % quantiles and standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JudgedMean {
    /// 10 % quantile, points.
    pub low: f64,
    /// 90 % quantile, points.
    pub high: f64,
    /// Standard deviation, points.
    pub sd: f64,
}

/// The judged mean under pseudo-counts `alpha` (a band with no count never happens). Without any count:
/// anything from 0 to 5 points, with the spread of two equally likely extremes.
pub fn judged_mean(alpha: &Bands) -> JudgedMean {
    let total: f64 = alpha.iter().sum();
    if total <= 0.0 {
        let top = BAND_POINTS[0];
        return JudgedMean {
            low: 0.0,
            high: top,
            sd: top / 2.0,
        };
    }
    let mut outcomes = outcomes(alpha, total);
    outcomes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mass: f64 = outcomes.iter().map(|o| o.1).sum();
    let mean: f64 = outcomes.iter().map(|(v, p)| v * p).sum::<f64>() / mass;
    let var: f64 = outcomes.iter().map(|(v, p)| p * (v - mean) * (v - mean)).sum::<f64>() / mass;
    JudgedMean {
        low: quantile(&outcomes, 0.1 * mass),
        high: quantile(&outcomes, 0.9 * mass),
        sd: var.max(0.0).sqrt(),
    }
}

/// Every split of the judged flights over the bands: (mean points, probability).
fn outcomes(alpha: &Bands, total: f64) -> Vec<(f64, f64)> {
    let n = JUDGED_FLIGHTS;
    let denominator = rising(total, n);
    let mut out = Vec::new();
    for a in 0..=n {
        for b in 0..=n - a {
            for c in 0..=n - a - b {
                let x = [a, b, c, n - a - b - c];
                let mut p = multinomial(&x) / denominator;
                for i in 0..4 {
                    p *= rising(alpha[i], x[i]);
                }
                let points: f64 = (0..4).map(|i| x[i] as f64 * BAND_POINTS[i]).sum();
                out.push((points / n as f64, p));
            }
        }
    }
    out
}

/// The smallest value whose cumulative probability reaches `level` (outcomes sorted by value).
fn quantile(sorted: &[(f64, f64)], level: f64) -> f64 {
    let mut cumulative = 0.0;
    for &(v, p) in sorted {
        cumulative += p;
        // Rounding must not push the top quantile past the last outcome.
        if cumulative >= level * (1.0 - 1e-12) {
            return v;
        }
    }
    sorted.last().map_or(0.0, |o| o.0)
}

/// x (x + 1) ... (x + k - 1): Γ(x + k) / Γ(x) without the gamma function.
fn rising(x: f64, k: usize) -> f64 {
    (0..k).map(|i| x + i as f64).product()
}

/// n! / (x1! x2! x3! x4!) for the split `x` of n.
fn multinomial(x: &[usize; 4]) -> f64 {
    let factorial = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
    factorial(x.iter().sum()) / x.iter().map(|&k| factorial(k)).product::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    #[test]
    fn probabilities_sum_to_one_over_56_outcomes() {
        let alpha = [0.3, 1.7, 2.0, 4.0];
        let o = outcomes(&alpha, alpha.iter().sum());
        assert_eq!(o.len(), 56);
        assert!(close(o.iter().map(|x| x.1).sum(), 1.0));
    }

    #[test]
    fn a_certain_band_gives_a_point() {
        let j = judged_mean(&[0.0, 0.0, 3.0, 0.0]);
        assert_eq!((j.low, j.high), (1.0, 1.0));
        assert!(close(j.sd, 0.0));
    }

    #[test]
    fn variance_matches_the_dirichlet_multinomial_formula() {
        // Var(mean of n) = s² (T + n) / (n (T + 1)), s² the per-flight variance at the mean shares.
        let alpha = [1.0, 0.5, 2.0, 4.5];
        let t: f64 = alpha.iter().sum();
        let share = alpha.map(|a| a / t);
        let m: f64 = (0..4).map(|i| share[i] * BAND_POINTS[i]).sum();
        let s2: f64 = (0..4).map(|i| share[i] * BAND_POINTS[i] * BAND_POINTS[i]).sum::<f64>() - m * m;
        let n = JUDGED_FLIGHTS as f64;
        let j = judged_mean(&alpha);
        assert!(close(j.sd * j.sd, s2 * (t + n) / (n * (t + 1.0))), "{j:?}");
    }

    #[test]
    fn half_failing_tests_scatter_over_the_bands() {
        // One flight at 1 point and one at 0, nothing else known: the judge's mean lies anywhere in 0-1.
        let j = judged_mean(&[0.0, 0.0, 1.0, 1.0]);
        assert_eq!((j.low, j.high), (0.0, 1.0));
        // Many flights, same shares: the judge's 5 flights still scatter (binomial), but less.
        let many = judged_mean(&[0.0, 0.0, 50.0, 50.0]);
        assert!(many.sd < j.sd && many.sd > 0.2, "{many:?}");
        assert_eq!((many.low, many.high), (0.2, 0.8));
    }

    #[test]
    fn no_evidence_spans_every_score() {
        let j = judged_mean(&[0.0; 4]);
        assert_eq!((j.low, j.high, j.sd), (0.0, 5.0, 2.5));
    }

    #[test]
    fn quantiles_bracket_the_mean_and_stay_in_range() {
        for alpha in [[4.0, 0.0, 0.0, 1.0], [0.1, 0.1, 0.1, 9.0], [2.0, 2.0, 2.0, 2.0]] {
            let j = judged_mean(&alpha);
            let t: f64 = alpha.iter().sum();
            let m: f64 = (0..4).map(|i| alpha[i] / t * BAND_POINTS[i]).sum();
            assert!(
                0.0 <= j.low && j.low <= m && m <= j.high && j.high <= 5.0,
                "{alpha:?} {j:?}"
            );
        }
    }
}
