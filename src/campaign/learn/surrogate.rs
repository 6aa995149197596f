//! The flights as a surrogate: a candidate's prediction moves from the calibrated LFS towards the flown
//! distances of the tests near it in draw space (Nadaraya-Watson kernel regression shrunk towards the LFS).
//!
//! Why: the LFS ranks a vehicle's flights only loosely, while a test's nearest flown neighbour in draw space
//! predicts it well; far from every flight the LFS still speaks (docs/design-constants.md#the-flights-kernel).
//!
//! `prediction = (k lfs + sum w_i flown_i) / (k + sum w_i)` with `w_i = exp(-|x - x_i|^2 / (2 h^2))` over the
//! unit draws `x`. The bandwidth `h` and the LFS's weight `k` are chosen before each round by leave-one-out
//! cross-validation on the campaign's own flights; when no pair beats the calibrated LFS alone, the LFS is
//! used unchanged, so the surrogate cannot make a campaign's ranking worse than calibration on the flights
//! it has seen.

use serde::{Deserialize, Serialize};

use crate::generator::adaptive::DIMS;

/// Candidate bandwidths, in unit draws.
pub const BANDWIDTHS: [f64; 5] = [0.05, 0.08, 0.12, 0.18, 0.25];
/// Candidate weights of the LFS, in flights at distance 0.
pub const LFS_WEIGHTS: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];
/// Fewer flights than this teach nothing a cross-validation can check.
pub const MIN_FLIGHTS: usize = 8;

/// One flown test as the kernel sees it: where it was drawn, what the LFS predicted, what it flew.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KernelPoint {
    /// Its unit draws.
    pub unit: [f64; DIMS],
    /// The calibrated LFS prediction for it, metres.
    pub lfs_m: f64,
    /// The flown minimum distance, metres.
    pub flown_m: f64,
}

/// The chosen kernel and what the cross-validation measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Surrogate {
    /// Kernel bandwidth `h`, unit draws.
    pub bandwidth: f64,
    /// Weight `k` of the LFS.
    pub lfs_weight: f64,
    /// Leave-one-out mean absolute error of this kernel on the flights, metres.
    pub loo_error_m: f64,
    /// Mean absolute error of the calibrated LFS alone on the same flights, metres.
    pub lfs_error_m: f64,
    /// Flights it was fitted on.
    pub flights: usize,
}

impl Surrogate {
    /// The kernel with the lowest leave-one-out error on `flights`; `None` with fewer than [`MIN_FLIGHTS`]
    /// or when none beats the calibrated LFS alone.
    pub fn fit(flights: &[KernelPoint]) -> Option<Self> {
        if flights.len() < MIN_FLIGHTS {
            return None;
        }
        let n = flights.len() as f64;
        let lfs_error_m = flights.iter().map(|f| (f.lfs_m - f.flown_m).abs()).sum::<f64>() / n;
        let mut best: Option<Self> = None;
        for &bandwidth in &BANDWIDTHS {
            for &lfs_weight in &LFS_WEIGHTS {
                let kernel = Self {
                    bandwidth,
                    lfs_weight,
                    loo_error_m: 0.0,
                    lfs_error_m,
                    flights: flights.len(),
                };
                let loo = flights
                    .iter()
                    .enumerate()
                    .map(|(j, f)| (kernel.predict_without(&f.unit, f.lfs_m, flights, Some(j)) - f.flown_m).abs())
                    .sum::<f64>()
                    / n;
                if loo < best.map_or(lfs_error_m, |b| b.loo_error_m) {
                    best = Some(Self {
                        loo_error_m: loo,
                        ..kernel
                    });
                }
            }
        }
        best
    }

    /// The prediction for a test at `unit` whose calibrated LFS prediction is `lfs_m`.
    pub fn predict(&self, unit: &[f64; DIMS], lfs_m: f64, flights: &[KernelPoint]) -> f64 {
        self.predict_without(unit, lfs_m, flights, None)
    }

    fn predict_without(&self, unit: &[f64; DIMS], lfs_m: f64, flights: &[KernelPoint], skip: Option<usize>) -> f64 {
        let two_h2 = 2.0 * self.bandwidth * self.bandwidth;
        let (mut num, mut den) = (self.lfs_weight * lfs_m, self.lfs_weight);
        for (i, f) in flights.iter().enumerate() {
            if Some(i) == skip {
                continue;
            }
            let d2: f64 = unit.iter().zip(&f.unit).map(|(a, b)| (a - b) * (a - b)).sum();
            let w = (-d2 / two_h2).exp();
            num += w * f.flown_m;
            den += w;
        }
        num / den
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn flown(x: f64, lfs_m: f64, flown_m: f64) -> KernelPoint {
        KernelPoint {
            unit: [x, 0.5, 0.5, 0.5, 0.5, 0.5, 0.0, 0.0],
            lfs_m,
            flown_m,
        }
    }

    #[test]
    fn a_smooth_truth_the_lfs_misses_is_learnt_from_the_neighbours() {
        // The truth rises with draw 0; the LFS says 2 m everywhere.
        let flights: Vec<KernelPoint> = (0..40)
            .map(|i| {
                let x = i as f64 / 40.0;
                flown(x, 2.0, 1.0 + 2.0 * x)
            })
            .collect();
        let s = Surrogate::fit(&flights).expect("the kernel beats a constant LFS");
        assert!(s.loo_error_m < 0.5 * s.lfs_error_m, "{s:?}");
        assert!((s.lfs_error_m - 0.5).abs() < 1e-9);
        let low = s.predict(&[0.05, 0.5, 0.5, 0.5, 0.5, 0.5, 0.0, 0.0], 2.0, &flights);
        let high = s.predict(&[0.95, 0.5, 0.5, 0.5, 0.5, 0.5, 0.0, 0.0], 2.0, &flights);
        assert!(low < 1.4 && high > 2.6, "{low} {high}");
        // Far from every flight (other draws), the LFS speaks.
        let far = s.predict(&[0.05, 0.0, 0.0, 1.0, 1.0, 0.5, 0.0, 0.0], 2.0, &flights);
        assert!((far - 2.0).abs() < 0.05, "{far}");
    }

    #[test]
    fn no_kernel_when_the_lfs_is_right_or_the_flights_are_few() {
        let exact: Vec<KernelPoint> = (0..20)
            .map(|i| flown(i as f64 / 20.0, 1.0 + i as f64 * 0.1, 1.0 + i as f64 * 0.1))
            .collect();
        assert_eq!(Surrogate::fit(&exact), None);
        let few: Vec<KernelPoint> = (0..MIN_FLIGHTS - 1).map(|i| flown(i as f64 / 8.0, 2.0, 1.0)).collect();
        assert_eq!(Surrogate::fit(&few), None);
    }

    proptest! {
        #[test]
        fn a_prediction_lies_between_the_lfs_and_the_flown_extremes(
            raw in proptest::collection::vec((proptest::array::uniform8(0.0f64..1.0), 0.0f64..5.0, 0.0f64..5.0), 1..30),
            x in proptest::array::uniform8(0.0f64..1.0),
            lfs in 0.0f64..5.0,
            h in 0usize..BANDWIDTHS.len(),
            k in 0usize..LFS_WEIGHTS.len(),
        ) {
            let flights: Vec<KernelPoint> = raw.iter().map(|(u, l, f)| KernelPoint { unit: *u, lfs_m: *l, flown_m: *f }).collect();
            let s = Surrogate { bandwidth: BANDWIDTHS[h], lfs_weight: LFS_WEIGHTS[k], loo_error_m: 0.0, lfs_error_m: 0.0, flights: 0 };
            let p = s.predict(&x, lfs, &flights);
            let lo = flights.iter().map(|f| f.flown_m).fold(lfs, f64::min);
            let hi = flights.iter().map(|f| f.flown_m).fold(lfs, f64::max);
            prop_assert!(p >= lo - 1e-9 && p <= hi + 1e-9, "{p} not in [{lo}, {hi}]");
        }
    }
}
