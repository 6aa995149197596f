//! The campaign's outputs: the failing tests best first, with their flights, and report.json / report.md. With
//! `--confirm` K > 1 only the confirmed tests are written as `test_N`; the others that failed are listed in
//! `unconfirmed.json` and the report.

use serde::Serialize;

use crate::campaign::config::CampaignInput;
use crate::campaign::fly::vehicle::FleetUse;
use crate::campaign::learn::calibration::Learnt;
use crate::campaign::report::backends::{self, BackendSummary};
use crate::campaign::report::markdown::markdown;
use crate::campaign::report::suite::summary;
pub use crate::campaign::report::suite::{DISTINCT_IOU, SuiteSummary};
use crate::campaign::report::user_report::{self, Invocation};
use crate::campaign::report::verdicts::{TestVerdict, verdicts};
use crate::campaign::store::journal::{FlightRecord, Journal};
use crate::campaign::store::journal_check::inside_bytes;
use crate::io::{write_atomic, write_json};
use crate::judge::{Judge, judge_in_frame, points, test_score};
use crate::model::{ModelError, Spelling, TestCase, Trajectory};
use crate::plot::{FlightPlot, PathStyle};

/// Wall time of each stage, seconds.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Drawing the candidates.
    pub sample_s: f64,
    /// Low-fidelity screening.
    pub screen_s: f64,
    /// The LFS ensemble on the shortlisted candidates.
    pub ensemble_s: f64,
    /// Online learning: calibrating the LFS on the flights, re-ranking, adapting the generator.
    pub learn_s: f64,
    /// High-fidelity flights.
    pub fly_s: f64,
    /// Writing the outputs.
    pub report_s: f64,
    /// Vehicle-seconds the vehicles spent flying, summed over the flight stages.
    pub vehicle_busy_s: f64,
    /// Vehicle-seconds available from each stage's first take-off to its last landing (vehicles x span).
    pub vehicle_span_s: f64,
}

impl StageTimes {
    /// Counts a fleet's use of its vehicles.
    pub fn add_fleet(&mut self, fleet: FleetUse) {
        self.vehicle_busy_s += fleet.busy_s;
        self.vehicle_span_s += fleet.vehicles as f64 * fleet.span_s;
    }

    /// Share of the vehicle time from take-off to last landing the vehicles waited (on screening, learning, or
    /// the last flights of a round); `None` before any flight.
    pub fn vehicles_idle(&self) -> Option<f64> {
        (self.vehicle_span_s > 0.0).then(|| (1.0 - self.vehicle_busy_s / self.vehicle_span_s).clamp(0.0, 1.0))
    }
}

/// One flight in the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlownTest {
    /// The candidate index.
    pub candidate: u64,
    /// Which flight of the candidate, from 0 (left out when 0).
    #[serde(skip_serializing_if = "crate::campaign::store::journal::is_first")]
    pub attempt: u32,
    /// LFS prediction, metres.
    pub predicted_min_distance: f64,
    /// The LFS ensemble's probability of a flight below 1.5 m.
    pub predicted_p_fail: Option<f64>,
    /// Flown minimum distance (competition definition), metres.
    pub min_distance: Option<f64>,
    /// Flown un-binned minimum distance, metres.
    pub min_distance_raw: Option<f64>,
    /// How the flight ended.
    pub status: String,
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
    pub flights: Vec<FlownTest>,
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
                        predicted_m: f.predicted_min_distance,
                        flown_m: f.min_distance?,
                        highlighted: f.reported_as.is_some(),
                    })
                })
                .collect(),
            invocation: &self.invocation,
        }
    }
}

/// Writes `test_N.yaml` (+ `test_N.csv`, `test_N.svg`) for each confirmed failing test, best first, then
/// report.json and report.md (and with `--confirm` above 1, `unconfirmed.json`), for the campaign `input` that
/// drew `candidates_screened` candidates and flew `records`. Returns the report.
pub fn write_outputs(
    input: &CampaignInput,
    candidates_screened: usize,
    records: &[FlightRecord],
    mut stages: StageTimes,
    learning: Option<&Learnt>,
) -> Result<Report, ModelError> {
    let t0 = std::time::Instant::now();
    let cfg = input.cfg;
    let mut tests = verdicts(records, cfg.confirm);
    let reported = write_failing_tests(input, &mut tests)?;
    let flights: Vec<FlownTest> = records.iter().map(|r| flown_test(r, &reported)).collect();
    let mut tests: Vec<TestVerdict> = tests.into_iter().map(|(t, _)| t).collect();
    user_report::write_unconfirmed(input, &mut tests, spelling(input))?;
    let mut suite = summary(records, &tests, cfg.screen);
    suite.confirm = cfg.confirm;
    suite.candidates_screened = candidates_screened;
    suite.screening_per_s = if cfg.screen && stages.screen_s > 0.0 {
        candidates_screened as f64 / stages.screen_s
    } else {
        0.0
    };
    stages.report_s = t0.elapsed().as_secs_f64();
    let report = Report {
        case: input.case.path.display().to_string(),
        judge: cfg.judge,
        judge_definition: cfg.judge.description(),
        seed: cfg.seed,
        budget: cfg.budget,
        flights,
        tests,
        suite,
        stages,
        learning: learning.cloned(),
        // The whole journal: the flights backends failed around are not in `records`.
        backends: backends::summarise(
            &Journal::read_all(&input.folder.join("journal.jsonl")).unwrap_or_else(|_| records.to_vec()),
        ),
        invocation: Invocation::current(),
        folder: input.folder.to_path_buf(),
    };
    user_report::write_pictures(input, &report.view())?;
    if cfg.confirm > 1 {
        let unconfirmed: Vec<&TestVerdict> = report.tests.iter().filter(|t| !t.confirmed).collect();
        write_json(&input.folder.join("unconfirmed.json"), &unconfirmed, true)?;
    }
    write_json(&input.folder.join("report.json"), &report, true)?;
    write_atomic(&input.folder.join("report.md"), markdown(&report).as_bytes())?;
    Ok(report)
}

/// Writes each confirmed failing test as `test_N` (YAML, its best failing flight's trajectory CSV and a plot;
/// its other flights as `test_N-<flight>.csv`, the runs `score` reads); returns (candidate, file name).
fn write_failing_tests(
    input: &CampaignInput,
    tests: &mut [(TestVerdict, Vec<&FlightRecord>)],
) -> Result<Vec<(u64, String)>, ModelError> {
    let folder = input.folder;
    let spelling = spelling(input);
    let case = input.case.with_absolute_references()?;
    let mut reported: Vec<(u64, String)> = Vec::new();
    for (i, (verdict, flights)) in tests.iter_mut().filter(|(t, _)| t.confirmed).enumerate() {
        let name = format!("test_{i}");
        let r = flights[0];
        let test = case.with_obstacles(r.obstacles.clone());
        test.save(&folder.join(format!("{name}.yaml")), spelling)?;
        let flown = inside_bytes(folder, &r.trajectory)
            .and_then(|b| String::from_utf8(b).ok())
            .and_then(|text| Trajectory::parse_csv(&text, &r.trajectory).ok());
        for (k, f) in flights.iter().enumerate() {
            // The best failing flight is the test's own CSV; the others are its runs, by flight number.
            let run = if k == 0 {
                name.clone()
            } else {
                format!("{name}-{}", f.attempt + 1)
            };
            if let Some(bytes) = inside_bytes(folder, &f.trajectory) {
                write_atomic(&folder.join(format!("{run}.csv")), &bytes)?;
            }
        }
        let title = format!(
            "{name}: flew {}",
            r.min_distance.map_or("-".into(), |d| format!("{d:.2} m"))
        );
        let lfs = input.screener.path(&test);
        let svg = plot(&test, lfs.as_ref(), flown.as_ref(), &title, input.cfg.judge);
        write_atomic(&folder.join(format!("{name}.svg")), svg.as_bytes())?;
        verdict.reported_as = Some(format!("{name}.yaml"));
        reported.push((r.candidate, format!("{name}.yaml")));
    }
    Ok(reported)
}

/// The key spelling the tests are written in.
fn spelling(input: &CampaignInput) -> Spelling {
    if input.cfg.old_spelling {
        Spelling::Old
    } else {
        Spelling::New
    }
}

/// One flight in the report; `reported` names the failing tests written.
fn flown_test(r: &FlightRecord, reported: &[(u64, String)]) -> FlownTest {
    let d = r.min_distance.unwrap_or(f64::INFINITY);
    FlownTest {
        candidate: r.candidate,
        attempt: r.attempt,
        predicted_min_distance: r.predicted_min_distance,
        predicted_p_fail: r.predicted_p_fail,
        min_distance: r.min_distance,
        min_distance_raw: r.min_distance_raw,
        status: r.status.clone(),
        reason: r.reason.clone(),
        flight_time_s: r.flight_time_s,
        points: points(d),
        test_score: if r.min_distance.is_some() {
            test_score(&[d], &[r.flight_time_s], r.obstacles.len())
        } else {
            0.0
        },
        reported_as: reported.iter().find(|(c, _)| *c == r.candidate).map(|(_, n)| n.clone()),
        vehicle: r.vehicle.clone(),
    }
}

/// Top-down plot: arena, obstacles, mission, the LFS's path and the flown path with its closest approach.
fn plot(test: &TestCase, lfs: Option<&Trajectory>, flown: Option<&Trajectory>, title: &str, judge: Judge) -> String {
    let mut p = FlightPlot::new(test);
    p.set_title(title);
    if let Some(t) = lfs {
        p.add_path(t, PathStyle::Simulated, "LFS prediction");
    }
    if let Some(t) = flown {
        p.add_path(t, PathStyle::Flown, "flown");
        // Flown trajectories are recorded in the test's frame.
        if let Some(v) = judge_in_frame(t, &test.obstacles, judge) {
            p.mark_closest(&v.closest);
        }
    }
    p.to_svg()
}
