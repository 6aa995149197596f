//! Seeded horizontal gusts: the flight-to-flight scatter a real vehicle has and a deterministic point mass
//! lacks.
//!
//! Real PX4 SITL flies the same test differently each time (sensor noise through the estimator, the
//! companion's timing). The mock stands in for all of it with one disturbance: a horizontal acceleration that
//! follows a first-order Gauss-Markov (Ornstein-Uhlenbeck) process per axis, with a given RMS and correlation
//! time. It is a stand-in fitted on PX4's repeat flights, not a model of any one physical cause. Seeded
//! (ChaCha8) and stepped with the fixed physics step, so a flight is the same for the same seed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::dynamics::Ned;

/// The gust process of one flight. Frame: local NED; only x (North) and y (East) are disturbed.
#[derive(Debug, Clone)]
pub struct Gusts {
    /// RMS of each horizontal component, m/s²; 0: no gusts (and no random numbers drawn).
    rms_m_s2: f64,
    /// Correlation time, s (positive).
    tau_s: f64,
    rng: ChaCha8Rng,
    /// The current disturbance, local NED m/s² (z always 0).
    acc_ned: Ned,
}

impl Gusts {
    /// Gusts of `rms_m_s2` per horizontal axis with correlation time `tau_s`, from `seed`. The process
    /// starts in its stationary distribution, so the first second of a flight is as gusty as the rest.
    pub fn new(seed: u64, rms_m_s2: f64, tau_s: f64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let rms_m_s2 = if rms_m_s2.is_finite() { rms_m_s2.max(0.0) } else { 0.0 };
        let acc_ned = if rms_m_s2 > 0.0 {
            Ned::new(rms_m_s2 * normal(&mut rng), rms_m_s2 * normal(&mut rng), 0.0)
        } else {
            Ned::zeros()
        };
        Self {
            rms_m_s2,
            tau_s: if tau_s.is_finite() { tau_s.max(1e-3) } else { 1.0 },
            rng,
            acc_ned,
        }
    }

    /// No gusts.
    pub fn calm() -> Self {
        Self::new(0, 0.0, 1.0)
    }

    /// The disturbance now, local NED m/s².
    pub fn acc_ned(&self) -> Ned {
        self.acc_ned
    }

    /// Advances the process by `dt_s` (exact discretisation: the stationary RMS does not depend on the step).
    pub fn step(&mut self, dt_s: f64) -> Ned {
        if self.rms_m_s2 > 0.0 && dt_s > 0.0 {
            let keep = (-dt_s / self.tau_s).exp();
            let fresh = self.rms_m_s2 * (1.0 - keep * keep).sqrt();
            self.acc_ned.x = keep * self.acc_ned.x + fresh * normal(&mut self.rng);
            self.acc_ned.y = keep * self.acc_ned.y + fresh * normal(&mut self.rng);
        }
        self.acc_ned
    }
}

/// The seed of flight number `flight` (counted from 0 since boot) of a vehicle seeded with `seed`: each
/// arming draws a different gust sequence, and the same sequence for the same (seed, flight).
pub fn flight_seed(seed: u64, flight: u64) -> u64 {
    // SplitMix64 of the pair: neighbouring seeds and flights give unrelated streams.
    let mut z = seed ^ flight.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A standard normal draw (Box-Muller; one of the pair is enough here).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]: ln is finite
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(seed: u64, rms: f64, tau: f64, n: usize, dt: f64) -> Vec<Ned> {
        let mut g = Gusts::new(seed, rms, tau);
        (0..n).map(|_| g.step(dt)).collect()
    }

    #[test]
    fn same_seed_same_gusts_other_seed_other_gusts() {
        let a = series(7, 0.5, 1.0, 1000, 0.004);
        assert_eq!(a, series(7, 0.5, 1.0, 1000, 0.004));
        assert_ne!(a, series(8, 0.5, 1.0, 1000, 0.004));
        assert!(a.iter().all(|v| v.z == 0.0), "horizontal only");
    }

    #[test]
    fn calm_draws_nothing_and_stays_zero() {
        assert!(series(3, 0.0, 1.0, 100, 0.004).iter().all(|v| *v == Ned::zeros()));
        assert!(series(3, f64::NAN, 1.0, 100, 0.004).iter().all(|v| *v == Ned::zeros()));
        assert_eq!(Gusts::calm().acc_ned(), Ned::zeros());
    }

    #[test]
    fn rms_and_correlation_time_are_as_set() {
        // 400 correlation times at a 4 ms step: the sample RMS is within a few percent of the set value.
        let (rms, tau, dt) = (0.4, 0.5, 0.004);
        let s = series(11, rms, tau, (400.0 * tau / dt) as usize, dt);
        let ms = s.iter().map(|v| v.x * v.x + v.y * v.y).sum::<f64>() / (2 * s.len()) as f64;
        assert!((ms.sqrt() / rms - 1.0).abs() < 0.1, "rms {}", ms.sqrt());
        // Autocorrelation at one correlation time is about 1/e.
        let lag = (tau / dt) as usize;
        let c = s.iter().zip(&s[lag..]).map(|(a, b)| a.x * b.x).sum::<f64>() / (s.len() - lag) as f64;
        let r = c / ms;
        assert!((r - (-1.0f64).exp()).abs() < 0.12, "autocorrelation {r}");
        // The stationary RMS does not depend on the step.
        let coarse = series(11, rms, tau, (400.0 * tau / 0.02) as usize, 0.02);
        let ms2 = coarse.iter().map(|v| v.x * v.x).sum::<f64>() / coarse.len() as f64;
        assert!((ms2.sqrt() / rms - 1.0).abs() < 0.15, "coarse rms {}", ms2.sqrt());
    }

    #[test]
    fn flight_seeds_differ_by_flight_and_by_seed() {
        let seeds: Vec<u64> = (0..4).flat_map(|s| (0..4).map(move |f| flight_seed(s, f))).collect();
        let mut unique = seeds.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), seeds.len());
        assert_eq!(flight_seed(5, 2), flight_seed(5, 2));
    }
}
