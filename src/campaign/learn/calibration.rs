//! Online calibration: the LFS learns the vehicle a campaign flies.
//!
//! The LFS is biased for any given stack: each flown test gives a residual `flown - predicted`, and the
//! campaign's bias is their mean shrunk towards a prior, `(k b0 + sum r) / (k + n)`, so a few flights cannot
//! run it away (docs/design-constants.md#lfs-bias-per-vehicle). Calibrated predictions and every ensemble
//! member move by the bias, so `p_fail` and the expected points follow without simulating again.
//!
//! The motion model itself is not refitted online: other gains did not rank the flights better, so they are
//! not worth re-screening for (docs/design-constants.md#no-online-refit-of-the-motion-model).

use serde::{Deserialize, Serialize};

use crate::campaign::learn::failure_counts::{BinCount, FailureCounts};
use crate::campaign::learn::surrogate::Surrogate;
use crate::generator::adaptive::{DIMS, DrawDistribution};

/// Residuals are clipped to this many metres: one flight stuck far from the boxes must not swing the bias.
pub const MAX_RESIDUAL_M: f64 = 3.0;

/// Prior weight in pseudo-flights, chosen by prequential cross-validation on the recorded flights and on PX4
/// (docs/design-constants.md#prior-weight).
pub const DEFAULT_PRIOR_FLIGHTS: f64 = 1.0;

/// Carried-over knowledge never counts for more than this many flights, so a new campaign can still move.
pub const MAX_CARRIED_FLIGHTS: f64 = 30.0;

/// The learnt distance bias of the LFS for one vehicle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Prior mean of `flown - predicted`, metres.
    pub prior_bias_m: f64,
    /// Prior weight, pseudo-flights.
    pub prior_flights: f64,
    /// Sum of the clipped residuals seen, metres.
    pub residual_sum_m: f64,
    /// Flights seen.
    pub flights: usize,
}

impl Default for Calibration {
    fn default() -> Self {
        Self::with_prior(0.0, DEFAULT_PRIOR_FLIGHTS)
    }
}

impl Calibration {
    /// No flights yet.
    pub fn with_prior(prior_bias_m: f64, prior_flights: f64) -> Self {
        Self {
            prior_bias_m,
            prior_flights,
            residual_sum_m: 0.0,
            flights: 0,
        }
    }

    /// The posterior mean of `flown - predicted`, metres.
    pub fn bias_m(&self) -> f64 {
        let w = self.prior_flights.max(0.0);
        let n = self.flights as f64;
        if w + n <= 0.0 {
            return 0.0;
        }
        (w * self.prior_bias_m + self.residual_sum_m) / (w + n)
    }

    /// Learns from one flight (ignored unless both distances are finite).
    pub fn observe(&mut self, predicted_m: f64, flown_m: f64) {
        if predicted_m.is_finite() && flown_m.is_finite() {
            self.residual_sum_m += (flown_m - predicted_m).clamp(-MAX_RESIDUAL_M, MAX_RESIDUAL_M);
            self.flights += 1;
        }
    }

    /// A calibrated prediction.
    pub fn predict(&self, predicted_m: f64) -> f64 {
        (predicted_m + self.bias_m()).max(0.0)
    }

    /// The prior of the next campaign on the same vehicle: this posterior, weighing at most
    /// [`MAX_CARRIED_FLIGHTS`] flights.
    pub fn carried(&self) -> Self {
        Self::with_prior(
            self.bias_m(),
            (self.prior_flights + self.flights as f64).min(MAX_CARRIED_FLIGHTS),
        )
    }

    /// Refuses a hand-edited prior that makes no sense, naming the field.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.prior_bias_m.is_finite() && self.prior_bias_m.abs() <= 10.0) {
            return Err(format!("prior_bias_m {} must be within +-10 m", self.prior_bias_m));
        }
        if !(self.prior_flights.is_finite() && (0.0..=1000.0).contains(&self.prior_flights)) {
            return Err(format!("prior_flights {} must be within 0..1000", self.prior_flights));
        }
        // Every residual is clipped, so a sum beyond the clip times the flights was written by hand; it would
        // shift every prediction far past the threshold, and the campaign would fly nothing.
        let most = MAX_RESIDUAL_M * self.flights as f64;
        if !(self.residual_sum_m.is_finite() && self.residual_sum_m.abs() <= most) {
            return Err(format!(
                "residual_sum_m {} must be within +-{most} m ({} flights of residuals clipped to +-{MAX_RESIDUAL_M} \
                 m): beyond it the prior would move every prediction by metres and the campaign would fly nothing",
                self.residual_sum_m, self.flights
            ));
        }
        Ok(())
    }
}

/// What a campaign learnt; written as `learnt.json`, read back by `--prior FOLDER`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Learnt {
    /// The calibration after the last flight.
    pub calibration: Calibration,
    /// The flights' kernel the last round ranked with (`None`: the calibrated LFS alone).
    #[serde(default)]
    pub surrogate: Option<Surrogate>,
    /// The draw distribution the next round would have used (uniform without `adapt`).
    pub distribution: DrawDistribution,
    /// One entry per round.
    pub rounds: Vec<RoundLog>,
    /// Where the flights failed, per draw bin (a diagnostic for the report; not carried by `--prior`).
    #[serde(default)]
    pub failure_counts: FailureCounts,
    /// Flights and failures of the candidates drawn near failing flights ([`crate::campaign::plan::neighbours`]) ...
    #[serde(default)]
    pub drawn_near_failures: BinCount,
    /// ... near the closest flights, before the first failure ...
    #[serde(default)]
    pub drawn_near_misses: BinCount,
    /// ... and of all the others (a diagnostic: did the boxes pay on this vehicle?).
    #[serde(default)]
    pub drawn_elsewhere: BinCount,
    /// Of the candidates drawn near failing flights, those closer to a flown test than `--max-iou`
    /// ([`crate::campaign::plan::diversity_guard`]).
    #[serde(default)]
    pub drawn_close: BinCount,
}

/// One round.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoundLog {
    /// 0-based.
    pub round: usize,
    /// Index of its first candidate.
    pub first_candidate: u64,
    /// Candidates drawn in it.
    pub candidates: usize,
    /// Of them, drawn around the failing flights so far ([`crate::campaign::plan::neighbours`]).
    #[serde(default)]
    pub local_candidates: usize,
    /// Share of its flights offered to neighbour candidates ([`crate::campaign::plan::neighbours::local_flight_share`]; 0
    /// without `adapt`).
    #[serde(default)]
    pub local_flight_share: f64,
    /// Its neighbour candidates were drawn around near misses: no flight had failed yet.
    #[serde(default)]
    pub near_miss_parents: bool,
    /// Flights made in it (by this run; a resumed run counts only its own).
    pub flights: usize,
    /// The learnt bias used to rank its flights, metres.
    pub bias_m: f64,
    /// The flights' kernel used to rank its flights (`None`: the calibrated LFS alone).
    #[serde(default)]
    pub surrogate: Option<Surrogate>,
    /// Mean of each unit draw of its distribution (0.5 = uniform; files with only the paper's five are padded).
    #[serde(deserialize_with = "uniform_means")]
    pub draw_means: [f64; DIMS],
}

fn uniform_means<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; DIMS], D::Error> {
    crate::generator::adaptive::padded(d, 0.5)
}

/// Mean absolute error of a prequential run: each truth predicted with the bias learnt from those before it
/// (the cross-validation of the prior weight, and the campaign's "first vs last quarter" figure).
pub fn prequential_errors(pairs: &[(f64, f64)], prior: &Calibration) -> Vec<f64> {
    let mut c = prior.clone();
    pairs
        .iter()
        .map(|&(predicted, truth)| {
            let e = (c.predict(predicted) - truth).abs();
            c.observe(predicted, truth);
            e
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn the_bias_is_the_shrunk_mean_residual() {
        let mut c = Calibration::with_prior(0.0, 4.0);
        assert_eq!(c.bias_m(), 0.0);
        for _ in 0..4 {
            c.observe(1.0, 2.0);
        }
        // (4 x 0 + 4 x 1) / (4 + 4)
        assert!((c.bias_m() - 0.5).abs() < 1e-12);
        assert!((c.predict(1.0) - 1.5).abs() < 1e-12);
        assert_eq!(c.predict(-3.0), 0.0, "never below 0 m");
        // A wild flight counts for at most MAX_RESIDUAL_M.
        c.observe(0.0, 100.0);
        assert!((c.residual_sum_m - (4.0 + MAX_RESIDUAL_M)).abs() < 1e-12);
        c.observe(f64::NAN, 1.0);
        assert_eq!(c.flights, 5);
    }

    #[test]
    fn a_carried_prior_keeps_the_bias_and_caps_its_weight() {
        let mut c = Calibration::default();
        for _ in 0..100 {
            c.observe(1.0, 2.0);
        }
        let next = c.carried();
        assert!((next.bias_m() - c.bias_m()).abs() < 1e-12);
        assert_eq!(next.prior_flights, MAX_CARRIED_FLIGHTS);
        assert_eq!(next.flights, 0);
        assert!(Calibration::with_prior(f64::NAN, 1.0).validate().is_err());
        assert!(
            Calibration::with_prior(0.0, -1.0)
                .validate()
                .unwrap_err()
                .contains("prior_flights")
        );
    }

    #[test]
    fn prequential_errors_learn_a_constant_offset() {
        let pairs: Vec<(f64, f64)> = (0..40).map(|i| (i as f64 * 0.1, i as f64 * 0.1 + 1.0)).collect();
        let e = prequential_errors(&pairs, &Calibration::default());
        assert!((e[0] - 1.0).abs() < 1e-12, "the first flight knows nothing");
        assert!(e[39] < 0.1, "{}", e[39]);
    }

    proptest! {
        #[test]
        fn the_bias_lies_between_the_prior_and_the_mean_residual(
            prior in -2.0f64..2.0,
            w in 0.1f64..20.0,
            r in proptest::collection::vec(-3.0f64..3.0, 1..30),
        ) {
            let mut c = Calibration::with_prior(prior, w);
            for x in &r {
                c.observe(0.0, *x);
            }
            let mean = r.iter().sum::<f64>() / r.len() as f64;
            let (lo, hi) = if prior < mean { (prior, mean) } else { (mean, prior) };
            prop_assert!(c.bias_m() >= lo - 1e-9 && c.bias_m() <= hi + 1e-9);
        }
    }
}
