//! The expected 2026 points of a flown test: how many points one of its flights earns on average (the 2026
//! judge flies it 5 times and scores the mean), with the uncertainty said.
//!
//! Each flight lands in one points band (5, 2, 1 or 0 points). The band probabilities get a Dirichlet-like
//! pseudo-count blend: the calibrated LFS prediction is a prior of [`PRIOR_FLIGHTS`] pseudo-flights (its band
//! shares from the campaign's other flights, tilted by the prediction only as far as it ranks them:
//! [`skilled_prior`]), each of the test's own flights counts one, and each flight of
//! a neighbour (a test overlapping it) counts [`NEIGHBOUR_WEIGHT`], all neighbours together at most
//! [`MAX_NEIGHBOUR_FLIGHTS`]. Expected points = sum of band share x band points; the interval is the 10-90 %
//! of that sum under the pseudo-counts (normal approximation, clipped to 0-5 points): how sure the campaign is
//! of the average, which decides whether a test is written. What the judge's 5 flights will average scatters
//! more ([`crate::campaign::report::expected::judged_mean`]); that is the interval reported. How the constants were
//! chosen: docs/design-constants.md#expected-points-weights.

use serde::Serialize;

use crate::campaign::learn::calibration::MAX_RESIDUAL_M;
use crate::campaign::report::expected::judged_mean::judged_mean;
use crate::judge::points;

pub use crate::campaign::report::expected::judged_mean::{BAND_POINTS, Bands};

/// Weight of the calibrated LFS prediction, pseudo-flights. This and the two neighbour weights were chosen
/// together by cross-validation with folds by obstacle set (docs/design-constants.md#expected-points-weights).
pub const PRIOR_FLIGHTS: f64 = 4.0;

/// Weight of one neighbour flight, in own flights.
pub const NEIGHBOUR_WEIGHT: f64 = 1.0;

/// All neighbour flights together count for at most this many own flights: a place flown often must not
/// drown the test's own flights.
pub const MAX_NEIGHBOUR_FLIGHTS: f64 = 4.0;

/// Fewer residuals than this give no spread: the prediction is then left out (no calibration).
pub const MIN_RESIDUALS: usize = 3;

/// The standard normal's 90 % quantile: the interval is 10-90 %.
pub const Z80: f64 = 1.281_551_565_545;

/// The standard normal distribution function (Abramowitz and Stegun 7.1.26, error below 1.5e-7).
pub fn normal_cdf(z: f64) -> f64 {
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly =
        t * (0.254_829_592 + t * (-0.284_496_736 + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erf = 1.0 - poly * (-x * x).exp();
    0.5 * (1.0 + erf.copysign(z))
}

/// The band of a flight's points.
pub fn band(flight_points: u32) -> usize {
    match flight_points {
        5.. => 0,
        2..=4 => 1,
        1 => 2,
        0 => 3,
    }
}

/// Flights per band of flown distances (metres).
pub fn counts(distances: impl IntoIterator<Item = f64>) -> Bands {
    let mut c = [0.0; 4];
    for d in distances {
        c[band(points(d))] += 1.0;
    }
    c
}

/// The calibrated prediction's band shares: the share of the campaign's residuals (flown - calibrated
/// prediction, metres) that would put a flight predicted at `predicted_m` into each band. `None` with fewer
/// than [`MIN_RESIDUALS`] residuals or a prediction that is not finite.
pub fn prior_bands(predicted_m: f64, residuals: &[f64]) -> Option<Bands> {
    if residuals.len() < MIN_RESIDUALS || !predicted_m.is_finite() {
        return None;
    }
    let c = counts(residuals.iter().map(|r| (predicted_m + r).max(0.0)));
    Some(c.map(|n| n / residuals.len() as f64))
}

/// The calibrated prediction's band shares as far as the prediction carries over to this vehicle: `others`
/// are the other flights' (calibrated prediction, flown distance) pairs, metres, each flown distance clipped to
/// within [`MAX_RESIDUAL_M`] of its prediction as the calibration clips it. The prediction is first pulled
/// toward the flights' mean by the least-squares slope of flown on predicted, held to 0-1 ([`skill_slope`]):
/// at slope 1 this is [`prior_bands`] on the plain residuals, at slope 0 the campaign's base rate, the same
/// for every test. On a vehicle the LFS does not rank (PX4 SIH: a slope at or below zero in every budget-100
/// campaign, docs/design-constants.md#expected-points-prior) the prior then shrinks toward what flights here
/// do, not toward what the LFS likes. `None` as [`prior_bands`].
pub fn skilled_prior(predicted_m: f64, others: &[(f64, f64)]) -> Option<Bands> {
    let pairs: Vec<(f64, f64)> = (others.iter())
        .filter(|(p, f)| p.is_finite() && f.is_finite())
        .map(|&(p, f)| (p, p + (f - p).clamp(-MAX_RESIDUAL_M, MAX_RESIDUAL_M)))
        .collect();
    if pairs.len() < MIN_RESIDUALS || !predicted_m.is_finite() {
        return None;
    }
    let line = SkillLine::fit(&pairs);
    let residuals: Vec<f64> = pairs.iter().map(|&(p, f)| f - line.at(p)).collect();
    prior_bands(line.at(predicted_m), &residuals)
}

/// The least-squares slope of flown on predicted over `pairs`, held to 0-1: 0 when the predictions do not
/// vary.
pub fn skill_slope(pairs: &[(f64, f64)]) -> f64 {
    SkillLine::fit(pairs).slope
}

/// Flown against predicted, fitted once: the line through the pairs' means at the held slope.
struct SkillLine {
    mean_predicted: f64,
    mean_flown: f64,
    slope: f64,
}

impl SkillLine {
    fn fit(pairs: &[(f64, f64)]) -> Self {
        let n = pairs.len().max(1) as f64;
        let mean_predicted = pairs.iter().map(|x| x.0).sum::<f64>() / n;
        let mean_flown = pairs.iter().map(|x| x.1).sum::<f64>() / n;
        let var: f64 = pairs.iter().map(|x| (x.0 - mean_predicted).powi(2)).sum();
        let cov: f64 = (pairs.iter())
            .map(|x| (x.0 - mean_predicted) * (x.1 - mean_flown))
            .sum();
        let slope = if pairs.len() < 2 || var <= 1e-12 {
            0.0
        } else {
            (cov / var).clamp(0.0, 1.0)
        };
        Self {
            mean_predicted,
            mean_flown,
            slope,
        }
    }

    fn at(&self, predicted_m: f64) -> f64 {
        self.mean_flown + self.slope * (predicted_m - self.mean_predicted)
    }
}

/// What a test's estimate is made of.
#[derive(Debug, Clone, PartialEq)]
pub struct Evidence {
    /// Its own flights per band.
    pub own: Bands,
    /// Its neighbours' flights per band.
    pub neighbours: Bands,
    /// The calibrated prediction's band shares (`None`: no calibration).
    pub prior: Option<Bands>,
}

/// The expected points of one flight of a test, with the 10-90 % interval of that expectation and of the
/// judge's mean of 5 flights.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PointsEstimate {
    /// Expected points of a flight (= expected mean points over 5 flights).
    pub mean: f64,
    /// 10 % bound of the expected points.
    pub low: f64,
    /// 90 % bound of the expected points.
    pub high: f64,
    /// 10 % quantile of the mean points the judge's 5 flights will give.
    pub judged_low: f64,
    /// 90 % quantile of the judge's mean points.
    pub judged_high: f64,
    /// Standard deviation of the judge's mean points.
    pub judged_sd: f64,
    /// What the estimate weighs, in flights (prior, own and neighbours').
    pub weight: f64,
}

impl PointsEstimate {
    /// Whether the test is expected to earn points with enough confidence: the 10 % bound is above zero.
    pub fn earns(&self) -> bool {
        self.low > 0.0
    }
}

/// The three weights of the blend, in flights; [`Weights::CHOSEN`] is what the campaign uses, other values
/// are for fitting them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weights {
    /// The calibrated prediction's weight, pseudo-flights.
    pub prior_flights: f64,
    /// One neighbour flight's weight.
    pub neighbour_weight: f64,
    /// The neighbours' flights together weigh at most this.
    pub max_neighbour_flights: f64,
}

impl Weights {
    /// [`PRIOR_FLIGHTS`], [`NEIGHBOUR_WEIGHT`], [`MAX_NEIGHBOUR_FLIGHTS`].
    pub const CHOSEN: Weights = Weights {
        prior_flights: PRIOR_FLIGHTS,
        neighbour_weight: NEIGHBOUR_WEIGHT,
        max_neighbour_flights: MAX_NEIGHBOUR_FLIGHTS,
    };
}

/// The pseudo-counts of `e`: prior, own flights and down-weighted neighbours.
pub fn pseudo_counts(e: &Evidence) -> Bands {
    pseudo_counts_with(e, &Weights::CHOSEN)
}

/// [`pseudo_counts`] under weights `w`.
pub fn pseudo_counts_with(e: &Evidence, w: &Weights) -> Bands {
    let neighbour_flights: f64 = e.neighbours.iter().sum();
    let nw = if neighbour_flights > 0.0 {
        w.neighbour_weight.min(w.max_neighbour_flights / neighbour_flights)
    } else {
        0.0
    };
    std::array::from_fn(|i| e.own[i] + nw * e.neighbours[i] + e.prior.map_or(0.0, |p| w.prior_flights * p[i]))
}

/// The estimate from `e`. Without any evidence: 0 points expected, anything from 0 to 5 possible.
pub fn estimate(e: &Evidence) -> PointsEstimate {
    estimate_with(e, &Weights::CHOSEN)
}

/// [`estimate`] under weights `w`.
pub fn estimate_with(e: &Evidence, w: &Weights) -> PointsEstimate {
    let alpha = pseudo_counts_with(e, w);
    let total: f64 = alpha.iter().sum();
    let judged = judged_mean(&alpha);
    if total <= 0.0 {
        return PointsEstimate {
            mean: 0.0,
            low: 0.0,
            high: BAND_POINTS[0],
            judged_low: judged.low,
            judged_high: judged.high,
            judged_sd: judged.sd,
            weight: 0.0,
        };
    }
    let share = alpha.map(|a| a / total);
    let mean: f64 = (0..4).map(|i| share[i] * BAND_POINTS[i]).sum();
    let square: f64 = (0..4).map(|i| share[i] * BAND_POINTS[i] * BAND_POINTS[i]).sum();
    // Variance of sum p_i v_i when p ~ Dirichlet(alpha).
    let sd = ((square - mean * mean).max(0.0) / (total + 1.0)).sqrt();
    PointsEstimate {
        mean,
        low: (mean - Z80 * sd).clamp(0.0, BAND_POINTS[0]),
        high: (mean + Z80 * sd).clamp(0.0, BAND_POINTS[0]),
        judged_low: judged.low,
        judged_high: judged.high,
        judged_sd: judged.sd,
        weight: total,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn evidence(own: &[f64], neighbours: &[f64], prior: Option<Bands>) -> Evidence {
        Evidence {
            own: counts(own.iter().copied()),
            neighbours: counts(neighbours.iter().copied()),
            prior,
        }
    }

    #[test]
    fn no_flights_and_no_calibration_expect_nothing_and_know_nothing() {
        let e = estimate(&evidence(&[], &[], None));
        assert_eq!((e.mean, e.low, e.high, e.weight), (0.0, 0.0, 5.0, 0.0));
        assert!(!e.earns());
    }

    #[test]
    fn no_flights_follow_the_calibrated_prediction() {
        let prior = prior_bands(0.6, &[-0.5, 0.0, 0.1, 2.0]).expect("enough residuals");
        // 0.1 m -> 5 points, 0.6 and 0.7 m -> 2, 2.6 m -> 0.
        assert_eq!(prior, [0.25, 0.5, 0.0, 0.25]);
        let e = estimate(&evidence(&[], &[], Some(prior)));
        assert!((e.mean - 2.25).abs() < 1e-12, "{e:?}");
        assert!(e.low < e.mean && e.mean < e.high);
        assert_eq!(e.weight, PRIOR_FLIGHTS);
    }

    #[test]
    fn all_5_point_flights_expect_nearly_5_and_earn() {
        let own = [0.1, 0.2, 0.0, 0.05, 0.1];
        let alone = estimate(&evidence(&own, &[], None));
        assert_eq!((alone.mean, alone.low, alone.high), (5.0, 5.0, 5.0));
        let prior = Some([0.0, 0.0, 0.0, 1.0]);
        let e = estimate(&evidence(&own, &[], prior));
        assert!((e.mean - 5.0 * 5.0 / (5.0 + PRIOR_FLIGHTS)).abs() < 1e-12, "{e:?}");
        assert!(e.earns() && e.high <= 5.0 && e.low < e.mean);
    }

    #[test]
    fn more_flights_narrow_the_interval() {
        let prior = Some([0.1, 0.2, 0.2, 0.5]);
        let one = estimate(&evidence(&[0.5], &[], prior));
        let three = estimate(&evidence(&[0.5, 0.6, 0.7], &[], prior));
        assert!(three.high - three.low < one.high - one.low, "{one:?} {three:?}");
        // One 1-point flight among passes: enough of three flights, not of five.
        let one_of_three = estimate(&evidence(&[1.4, 2.0, 2.5], &[], None));
        assert!(one_of_three.earns(), "{one_of_three:?}");
        let one_of_five = estimate(&evidence(&[1.4, 2.0, 2.5, 3.0, 2.2], &[], None));
        assert!(!one_of_five.earns(), "{one_of_five:?}");
    }

    #[test]
    fn neighbours_weigh_as_chosen_and_a_crowd_of_them_is_capped() {
        let own = estimate(&evidence(&[3.0], &[], None));
        assert_eq!(own.mean, 0.0);
        let near = estimate(&evidence(&[3.0], &[0.1], None));
        let w = NEIGHBOUR_WEIGHT;
        assert!((near.mean - 5.0 * w / (1.0 + w)).abs() < 1e-12, "{near:?}");
        let crowd = estimate(&evidence(&[3.0], &[0.1; 40], None));
        let cap = MAX_NEIGHBOUR_FLIGHTS;
        assert!(
            (crowd.mean - 5.0 * cap / (1.0 + cap)).abs() < 1e-12,
            "40 neighbours weigh {cap} flights: {crowd:?}"
        );
        let weights = Weights {
            neighbour_weight: 0.25,
            max_neighbour_flights: 1.0,
            ..Weights::CHOSEN
        };
        let capped = estimate_with(&evidence(&[3.0], &[0.1; 40], None), &weights);
        assert!((capped.mean - 2.5).abs() < 1e-12, "{capped:?}");
    }

    #[test]
    fn the_normal_distribution_function_matches_its_table() {
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-9);
        assert!((normal_cdf(Z80) - 0.9).abs() < 1e-6 && (normal_cdf(-Z80) - 0.1).abs() < 1e-6);
        assert!((normal_cdf(1.96) - 0.975).abs() < 1e-4);
    }

    #[test]
    fn a_prediction_that_ranks_the_flights_keeps_its_tilt_and_one_that_does_not_gives_the_base_rate() {
        // Flown = predicted + 0.3 m: slope 1, and the prior equals the plain residuals' prior.
        let ranked: Vec<(f64, f64)> = [0.2, 0.8, 1.2, 1.6, 2.4].iter().map(|&p| (p, p + 0.3)).collect();
        assert!((skill_slope(&ranked) - 1.0).abs() < 1e-12);
        let residuals: Vec<f64> = ranked.iter().map(|(p, f)| f - p).collect();
        assert_eq!(skilled_prior(0.5, &ranked), prior_bands(0.5, &residuals));
        assert_ne!(skilled_prior(0.5, &ranked), skilled_prior(2.0, &ranked));
        // Flown against predicted reversed: slope held at 0, every test gets the flights' own band shares.
        let reversed: Vec<(f64, f64)> = [(0.5, 2.0), (1.0, 1.2), (1.5, 0.8), (2.0, 0.1)].to_vec();
        assert_eq!(skill_slope(&reversed), 0.0);
        let base = Some([0.25, 0.25, 0.25, 0.25]);
        assert_eq!(skilled_prior(0.1, &reversed), base);
        assert_eq!(skilled_prior(9.0, &reversed), base);
        // A flight far off its prediction weighs as the calibration clips it; no spread in the predictions
        // (the plain draws of --no-screen, all 0) gives slope 0.
        let clipped = skilled_prior(1.0, &[(1.0, 1.2), (1.0, 40.0), (1.0, 0.9)]).expect("three flights");
        assert_eq!(
            clipped,
            skilled_prior(1.0, &[(1.0, 1.2), (1.0, 4.0), (1.0, 0.9)]).expect("three")
        );
        assert_eq!(skill_slope(&[(0.0, 1.0), (0.0, 2.0)]), 0.0);
        assert_eq!(skilled_prior(1.0, &[(1.0, 1.2), (f64::NAN, 1.0)]), None);
    }

    #[test]
    fn too_few_residuals_or_no_prediction_give_no_prior() {
        assert_eq!(prior_bands(0.5, &[0.0, 0.1]), None);
        assert_eq!(prior_bands(f64::INFINITY, &[0.0, 0.1, 0.2]), None);
        assert_eq!(band(5), 0);
        assert_eq!(band(0), 3);
    }
}
