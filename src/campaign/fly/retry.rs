//! One rule for every vehicle whose backend can fail apart from the test (a PX4 that never boots, a job
//! engine that loses a job, a vehicle that refuses to arm): a flight gets [`ATTEMPTS`] tries, a flight
//! whose tries all failed is `backend_failed` (not charged), and a vehicle that fails [`IN_A_ROW_TO_DROP`]
//! flights in a row is dropped, since its backend, not the tests, is broken.

use std::sync::atomic::{AtomicBool, Ordering};

use std::path::Path;

use super::vehicle::{Flown, Vehicle, VehicleError};
use crate::campaign::ground::flight_status::FlightStatus;
use crate::campaign::store::journal::FlightRecord;
use crate::model::TestCase;

/// Tries of one flight: the first and one retry.
pub const ATTEMPTS: usize = 2;
/// Failed flights (or setup rejections) in a row that drop a vehicle.
pub const IN_A_ROW_TO_DROP: usize = 2;

/// How one try of a flight ended.
pub enum Attempt {
    /// The flight ran (whatever its verdict).
    Flew(Flown),
    /// The campaign's stop came before the flight ran.
    Stopped,
    /// The backend failed; why.
    Failed(String),
}

/// How a flight's tries ended.
pub enum Tried {
    /// One try flew.
    Flew(Flown),
    /// The campaign's stop came first.
    Stopped,
    /// Every try failed; why, in order.
    Failed(Vec<String>),
}

/// A vehicle's failed flights in a row.
#[derive(Debug, Default)]
pub struct Retry {
    failed_in_a_row: usize,
}

impl Retry {
    /// Runs `attempt(n)` for n = 1..=[`ATTEMPTS`] until one flies; no retry once `stop` is set.
    pub fn tries(&mut self, stop: &AtomicBool, mut attempt: impl FnMut(usize) -> Attempt) -> Tried {
        let mut failures = Vec::new();
        for n in 1..=ATTEMPTS {
            match attempt(n) {
                Attempt::Flew(f) => {
                    self.failed_in_a_row = 0;
                    return Tried::Flew(f);
                }
                Attempt::Stopped => return Tried::Stopped,
                Attempt::Failed(why) => failures.push(why),
            }
            if stop.load(Ordering::Relaxed) {
                return Tried::Stopped;
            }
        }
        self.failed_in_a_row += 1;
        Tried::Failed(failures)
    }

    /// A flight whose tries all failed for `reason`: `backend_failed`, or `vehicle` dropped when it is the
    /// [`IN_A_ROW_TO_DROP`]th in a row.
    pub fn failed(&self, vehicle: String, reason: String) -> Result<Flown, VehicleError> {
        if self.failed_in_a_row >= IN_A_ROW_TO_DROP {
            return Err(VehicleError::Unreachable {
                vehicle,
                reason: format!(
                    "{} flights in a row failed on the backend (last: {reason})",
                    self.failed_in_a_row
                ),
            });
        }
        Ok(Flown::unflown(FlightStatus::BackendFailed, reason))
    }
}

/// A vehicle that rejects [`IN_A_ROW_TO_DROP`] flights in a row at setup (status `rejected`: never armed) is
/// dropped, and the last of them is given to another vehicle instead of being journaled: a PX4 whose simulated
/// sensors timed out rejects every flight, each spending a flight of the budget.
pub const REJECTED_IN_A_ROW_TO_DROP: usize = IN_A_ROW_TO_DROP;

/// The setup rejections `vehicle` ended its journaled flights with.
pub(in crate::campaign) fn rejected_in_a_row(history: &[FlightRecord], vehicle: &str) -> usize {
    history
        .iter()
        .rev()
        .filter(|r| r.vehicle == vehicle)
        .take_while(|r| r.flown.status == FlightStatus::REJECTED)
        .count()
}

/// Flies `test` on `vehicle`; the [`REJECTED_IN_A_ROW_TO_DROP`]th setup rejection in a row makes the vehicle
/// unreachable.
pub(in crate::campaign) fn fly_counting_rejections(
    vehicle: &mut dyn Vehicle,
    test: &TestCase,
    csv: &Path,
    cancel: &AtomicBool,
    rejected_in_a_row: &mut usize,
) -> Result<Flown, VehicleError> {
    match vehicle.fly(test, csv, cancel) {
        Ok(flown) if flown.status == FlightStatus::REJECTED => {
            *rejected_in_a_row += 1;
            if *rejected_in_a_row >= REJECTED_IN_A_ROW_TO_DROP {
                Err(VehicleError::Unreachable {
                    vehicle: vehicle.name(),
                    reason: format!(
                        "rejected {rejected_in_a_row} flights in a row at setup (last: {})",
                        flown.reason.as_deref().unwrap_or("no reason given")
                    ),
                })
            } else {
                Ok(flown)
            }
        }
        other => {
            *rejected_in_a_row = 0;
            other
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flown() -> Flown {
        Flown {
            status: FlightStatus::LANDED,
            min_distance: Some(2.0),
            min_distance_raw: Some(2.0),
            flight_time_s: 60.0,
            warnings: Vec::new(),
            reason: None,
            closest_centre_m: None,
            inside_cp_dist: None,
        }
    }

    #[test]
    fn a_failed_try_is_retried_once_then_the_flight_is_backend_failed() {
        let (stop, mut retry, mut n) = (AtomicBool::new(false), Retry::default(), 0);
        let Tried::Failed(why) = retry.tries(&stop, |k| {
            n = k;
            Attempt::Failed(format!("boot {k}"))
        }) else {
            panic!("both tries failed")
        };
        assert_eq!((n, why), (ATTEMPTS, vec!["boot 1".to_string(), "boot 2".into()]));
        let f = retry.failed("px4#0".into(), "boot".into()).unwrap();
        assert_eq!(f.status, FlightStatus::BackendFailed);
    }

    #[test]
    fn the_second_failed_flight_in_a_row_drops_the_vehicle_and_a_flight_resets_the_count() {
        let (stop, mut retry) = (AtomicBool::new(false), Retry::default());
        let _ = retry.tries(&stop, |_| Attempt::Failed("x".into()));
        assert!(matches!(retry.tries(&stop, |_| Attempt::Flew(flown())), Tried::Flew(_)));
        let _ = retry.tries(&stop, |_| Attempt::Failed("x".into()));
        assert!(
            retry.failed("v".into(), "x".into()).is_ok(),
            "one in a row after a flight"
        );
        let _ = retry.tries(&stop, |_| Attempt::Failed("x".into()));
        let e = retry.failed("v".into(), "x".into()).unwrap_err().to_string();
        assert!(e.contains("2 flights in a row"), "{e}");
    }

    #[test]
    fn no_retry_after_the_stop() {
        let (stop, mut retry, mut tries) = (AtomicBool::new(true), Retry::default(), 0);
        let outcome = retry.tries(&stop, |_| {
            tries += 1;
            Attempt::Failed("x".into())
        });
        assert!(matches!(outcome, Tried::Stopped));
        assert_eq!(tries, 1);
    }
}
