//! The campaign's outputs: the failing tests best first, with their flights, and report.json / report.md. Only
//! the tests expected to earn 2026 points, less near-duplicate trajectories, are written as `test_N`, by their
//! expected score ([`expected_score`]); the others that failed are listed in `unconfirmed.json` and the report.

use crate::campaign::ground::candidate::CandidateId;
use crate::campaign::ground::input::CampaignInput;
use crate::campaign::learn::calibration::Learnt;
use crate::campaign::report::markdown::markdown;
use crate::campaign::report::suite::summary;
pub use crate::campaign::report::suite::{DISTINCT_IOU, SuiteSummary};
use crate::campaign::report::user_report::{self, Invocation};
use crate::campaign::report::verdicts::{TestVerdict, verdicts};
use crate::campaign::report::{backends, expected::score as expected_score};
use crate::campaign::store::journal::{FlightRecord, Journal};
use crate::campaign::store::trust::inside_bytes;
use crate::io::{write_atomic, write_json};
use crate::judge::{ClosestApproach, judge_in_frame, points, test_score};
use crate::model::{ModelError, Spelling, TestCase, Trajectory};
use crate::plot::{FlightPlot, PathStyle};

use crate::campaign::ground::stage_times::StageTimes;
pub use crate::campaign::report::document::{Report, ReportedFlight};

/// Writes `test_N.yaml` (+ `test_N.csv`, `test_N.svg`) for each test to write, best first, then
/// report.json and report.md (and `unconfirmed.json` with `--confirm` above 1 or tests not written), for the campaign `input` that
/// drew `candidates_screened` candidates and flew the charged flights of `journal`. Returns the report.
pub fn write_outputs(
    input: &CampaignInput,
    candidates_screened: usize,
    journal: &Journal,
    mut stages: StageTimes,
    learning: Option<&Learnt>,
) -> Result<Report, ModelError> {
    let t0 = std::time::Instant::now();
    let cfg = input.cfg;
    let charged = journal.charged();
    let records = charged.as_slice();
    let mut tests = verdicts(records, cfg.flight.confirm);
    let expected_2026 = expected_score::aim(input.folder, records, &mut tests);
    let reported = write_failing_tests(input, &mut tests)?;
    let flights: Vec<ReportedFlight> = records.iter().map(|r| reported_flight(r, &reported)).collect();
    let mut tests: Vec<TestVerdict> = tests.into_iter().map(|(t, _)| t).collect();
    user_report::write_unconfirmed(input, &mut tests, spelling(input))?;
    let mut suite = summary(records, &tests, cfg.screening.screen);
    suite.confirm = cfg.flight.confirm;
    suite.expected_2026 = Some(expected_2026);
    suite.candidates_screened = candidates_screened;
    suite.screening_per_s = if cfg.screening.screen && stages.screen_s > 0.0 {
        candidates_screened as f64 / stages.screen_s
    } else {
        0.0
    };
    stages.report_s = t0.elapsed().as_secs_f64();
    let report = Report {
        case: input.case.path.display().to_string(),
        judge: cfg.campaign.judge,
        judge_definition: cfg.campaign.judge.description(),
        seed: cfg.campaign.seed,
        budget: cfg.campaign.budget,
        flights,
        tests,
        suite,
        stages,
        learning: learning.cloned(),
        // The whole journal: the flights backends failed around are not in `records`.
        backends: backends::summarise(journal.records()),
        collision_prevention: crate::campaign::report::cp_tests::cp_tests(records),
        invocation: Invocation::current(),
        folder: input.folder.to_path_buf(),
    };
    user_report::write_pictures(input, &report.view())?;
    let unconfirmed: Vec<&TestVerdict> = report.tests.iter().filter(|t| !t.confirmed).collect();
    if cfg.flight.confirm > 1 || !unconfirmed.is_empty() {
        write_json(&input.folder.join("unconfirmed.json"), &unconfirmed, true)?;
    }
    write_json(&input.folder.join("report.json"), &report, true)?;
    write_atomic(&input.folder.join("report.md"), markdown(&report).as_bytes())?;
    Ok(report)
}

/// Writes each test to write as `test_N` (YAML, its best failing flight's trajectory CSV and a plot;
/// its other flights as `test_N-<flight>.csv`, the runs `score` reads); returns (candidate, file name).
fn write_failing_tests(
    input: &CampaignInput,
    tests: &mut [(TestVerdict, Vec<&FlightRecord>)],
) -> Result<Vec<(CandidateId, String)>, ModelError> {
    let folder = input.folder;
    let spelling = spelling(input);
    let case = input.case.with_absolute_references()?;
    let mut reported: Vec<(CandidateId, String)> = Vec::new();
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
            r.flown.min_distance.map_or("-".into(), |d| format!("{d:.2} m"))
        );
        let lfs = input.screener.path(&test);
        // Flown trajectories are recorded in the test's frame.
        let judged = (flown.as_ref()).and_then(|t| judge_in_frame(t, &test.obstacles, input.cfg.campaign.judge));
        verdict.above_top = judged.as_ref().and_then(|j| j.above_top);
        let closest = judged.map(|j| j.closest);
        let svg = plot(&test, lfs.as_ref(), flown.as_ref(), closest.as_ref(), &title);
        write_atomic(&folder.join(format!("{name}.svg")), svg.as_bytes())?;
        verdict.reported_as = Some(format!("{name}.yaml"));
        reported.push((r.candidate, format!("{name}.yaml")));
    }
    Ok(reported)
}

/// The key spelling the tests are written in.
fn spelling(input: &CampaignInput) -> Spelling {
    input.cfg.output.spelling
}

/// One flight in the report; `reported` names the failing tests written.
fn reported_flight(r: &FlightRecord, reported: &[(CandidateId, String)]) -> ReportedFlight {
    let d = r.flown.min_distance.unwrap_or(f64::INFINITY);
    ReportedFlight {
        candidate: r.candidate,
        attempt: r.attempt,
        predicted_min_distance: r.predicted_m(),
        predicted_p_fail: r.prediction.as_ref().and_then(|p| p.p_fail),
        min_distance: r.flown.min_distance,
        min_distance_raw: r.flown.min_distance_raw,
        status: r.flown.status,
        reason: r.flown.reason.clone(),
        flight_time_s: r.flown.flight_time_s,
        points: points(d),
        test_score: if r.flown.min_distance.is_some() {
            test_score(&[d], &[r.flown.flight_time_s], r.obstacles.len())
        } else {
            0.0
        },
        reported_as: reported.iter().find(|(c, _)| *c == r.candidate).map(|(_, n)| n.clone()),
        vehicle: r.vehicle.clone(),
        closest_centre_m: r.flown.closest_centre_m,
        inside_cp_dist: r.flown.inside_cp_dist,
    }
}

/// Top-down plot: arena, obstacles, mission, the LFS's path and the flown path with its closest approach.
fn plot(
    test: &TestCase,
    lfs: Option<&Trajectory>,
    flown: Option<&Trajectory>,
    closest: Option<&ClosestApproach>,
    title: &str,
) -> String {
    let mut p = FlightPlot::new(test);
    p.set_title(title);
    if let Some(t) = lfs {
        p.add_path(t, PathStyle::Simulated, "LFS prediction");
    }
    if let Some(t) = flown {
        p.add_path(t, PathStyle::Flown, "flown");
    }
    if let Some(c) = closest {
        p.mark_closest(c);
    }
    p.to_svg()
}
