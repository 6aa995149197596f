//! The campaign's report as data: what report.json holds and report.md renders (the suite, each test's
//! verdict, every flight, the stage times, what was learnt).

use serde::Serialize;

use crate::campaign::ground::stage_times::StageTimes;
use crate::campaign::learn::calibration::Learnt;
use crate::campaign::report::backends::BackendSummary;
use crate::campaign::report::suite::SuiteSummary;
use crate::campaign::report::user_report::{self, Invocation};
use crate::campaign::report::verdicts::TestVerdict;
use crate::judge::Judge;

/// One flight in the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportedFlight {
    /// The candidate flown.
    pub candidate: crate::campaign::ground::candidate::CandidateId,
    /// Which flight of the candidate, from 0 (left out when 0).
    #[serde(skip_serializing_if = "crate::campaign::store::journal::is_first")]
    pub attempt: u32,
    /// LFS prediction, metres.
    pub predicted_min_distance: Option<f64>,
    /// The LFS ensemble's probability of a flight below 1.5 m.
    pub predicted_p_fail: Option<f64>,
    /// Flown minimum distance (competition definition), metres.
    pub min_distance: Option<f64>,
    /// Flown un-binned minimum distance, metres.
    pub min_distance_raw: Option<f64>,
    /// How the flight ended.
    pub status: crate::campaign::ground::flight_status::FlightStatus,
    /// Why, in words, when it did not land.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Flight time, seconds.
    pub flight_time_s: f64,
    /// The competition's points for this run.
    pub points: u32,
    /// The competition's test score of this flight alone.
    pub test_score: f64,
    /// `test_N.yaml` its test was reported as, if confirmed as failing.
    pub reported_as: Option<String>,
    /// The vehicle that flew it.
    pub vehicle: String,
    /// Collision Prevention: the closest the vehicle's centre came to a box, metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub closest_centre_m: Option<f64>,
    /// Collision Prevention: whether the vehicle came inside `CP_DIST`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inside_cp_dist: Option<bool>,
}

/// The whole report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The case study.
    pub case: String,
    /// The judge edition of every flown distance and point here.
    pub judge: Judge,
    /// Its definition in one line.
    pub judge_definition: &'static str,
    /// The campaign's seed.
    pub seed: u64,
    /// The flight budget.
    pub budget: usize,
    /// Every flight, in flight order.
    pub flights: Vec<ReportedFlight>,
    /// Every test that failed at least once, best first: the confirmed ones (reported as `test_N.yaml`) and
    /// the others.
    pub tests: Vec<TestVerdict>,
    /// Suite numbers.
    pub suite: SuiteSummary,
    /// Wall time per stage.
    pub stages: StageTimes,
    /// What a learning campaign learnt (`None` with `--no-learn`).
    pub learning: Option<Learnt>,
    /// Per backend (mock, px4, runner, MAVLink URL): flights, failed jobs, wall time per flight.
    pub backends: Vec<BackendSummary>,
    /// Collision Prevention per test (left out in the other modes).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub collision_prevention: Vec<crate::campaign::report::cp_tests::CpTest>,
    /// The command line and version that made it.
    pub invocation: Invocation,
    /// The campaign folder (the next commands report.md suggests name it).
    #[serde(skip)]
    pub folder: std::path::PathBuf,
}

impl Report {
    /// What the user's part of report.md reads.
    pub fn view(&self) -> user_report::View<'_> {
        user_report::View {
            case: &self.case,
            seed: self.seed,
            budget: self.budget,
            judge: self.judge,
            suite: &self.suite,
            tests: &self.tests,
            flights: (self.flights.iter())
                .filter_map(|f| {
                    Some(crate::plot::suite::Point {
                        predicted_m: f.predicted_min_distance?,
                        flown_m: f.min_distance?,
                        highlighted: f.reported_as.is_some(),
                    })
                })
                .collect(),
            invocation: &self.invocation,
        }
    }
}
