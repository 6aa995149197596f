//! A `--px4 BUILD --sim iris` flight: a fresh PX4 SITL in its release's external-simulator mode with
//! prgenuav's iris simulator beside it in this process, at the test's home, the simulator seeded by the
//! campaign's seed and the flight's trajectory file (which test, which flight of it), so a flight flown again
//! repeats; both stopped when the flight ends. Over TCP the two run in lockstep and the avoidance companion
//! holds simulated time, so its answers cannot fall behind; a simulator that loses PX4 is a backend failure,
//! retried like a PX4 that dies.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use super::mock_mavlink::{flight_seed, fly_blocking};
use super::px4::{Px4Vehicle, boot_failed, outcome};
use super::retry::Attempt;
use crate::bridge::hil::run::SimSummary;
use crate::bridge::hil::sitl::{IrisError, IrisSitl, IrisSpec};
use crate::bridge::{FlyMode, SimLink};
use crate::model::TestCase;

/// Holds released late beyond this share of all holds: the companion fell behind simulated time (the
/// machine stalled it for seconds), so the flight is the backend's failure, as a starved SIH flight is.
pub const LATE_SHARE: f64 = 0.01;

impl Px4Vehicle {
    /// One fresh PX4 and simulator at the test's home, flown and stopped; PX4's console and the simulator's
    /// account appended to `log`.
    pub(super) fn attempt_iris(&self, test: &TestCase, csv: &Path, stop: &AtomicBool, log: &mut String) -> Attempt {
        let s = self.settings();
        let test = &s.bench.flown(test);
        let tcp = s.sim_link == SimLink::Tcp;
        let spec = IrisSpec {
            build: s.build.clone(),
            instance: self.instance(),
            home: test.home,
            heading_deg: s.bench.heading_deg(),
            seed: flight_seed(s.seed, csv),
            speed_factor: s.speed_factor,
            link: s.sim_link,
            paced: tcp && s.mode == FlyMode::Avoidance,
            boot_timeout: s.boot_timeout,
        };
        let mut iris = match IrisSitl::start(self.handle(), &spec, stop) {
            Ok(iris) => iris,
            Err(IrisError::Sitl(e)) => return boot_failed(e, log),
            Err(e) => return Attempt::Failed(e.to_string()),
        };
        let mut opts = s.fly_options(iris.px4.url(), self.instance(), csv);
        opts.sim_gate = iris.gate();
        if tcp {
            // PX4 waits for the simulator, and the simulator for the companion.
            opts.lockstep = Some(Duration::ZERO);
        } else {
            opts.time_scale = 1.0;
        }
        let result = fly_blocking(self.handle(), test, &opts, stop);
        let lost = iris.sim_failure();
        let summary = iris.finish();
        let died = iris.px4.exited();
        self.keep_console(&iris.px4, csv, log);
        if let Some(summary) = &summary {
            log.push_str(&format!("{summary}\n"));
        }
        drop(iris);
        match outcome(result, died, self.instance(), lost) {
            Attempt::Flew(_) if let Some(why) = summary.as_ref().and_then(|s| late(s, self.instance())) => {
                Attempt::Failed(why)
            }
            Attempt::Flew(mut flown) => {
                flown.warnings.extend(s.bench.caveats(test));
                Attempt::Flew(flown)
            }
            other => other,
        }
    }
}

/// A flight whose companion held simulated time too long too often ([`LATE_SHARE`]): PX4 then flew on
/// without its answer, so the flight did not test the avoidance.
fn late(s: &SimSummary, instance: u8) -> Option<String> {
    let holds = s.holds + s.late_releases;
    (s.late_releases > 1 && s.late_releases as f64 > LATE_SHARE * holds as f64).then(|| {
        format!(
            "PX4 instance {instance}: {} of {holds} holds of simulated time were released late: the machine stalled \
             the companion for seconds",
            s.late_releases
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_companion_late_in_more_than_one_percent_of_its_holds_fails_the_flight() {
        let s = |holds, late_releases| SimSummary {
            holds,
            late_releases,
            ..SimSummary::default()
        };
        assert_eq!(late(&s(1000, 1), 3), None, "one stall");
        assert_eq!(late(&s(990, 10), 3), None, "exactly 1 %");
        let why = late(&s(980, 20), 3).expect("2 %");
        assert!(why.contains("instance 3") && why.contains("20 of 1000"), "{why}");
    }
}
