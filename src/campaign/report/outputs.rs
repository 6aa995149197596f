//! The campaign's outputs: the failing tests best first, with their flights, and report.json / report.md. With
//! `--confirm` K > 1 only the confirmed tests are written as `test_N`; the others that failed are listed in
//! `unconfirmed.json` and the report.

use std::fmt::Write as _;

use serde::Serialize;

use crate::campaign::config::CampaignInput;
use crate::campaign::fly::vehicle::FleetUse;
use crate::campaign::learn::calibration::Learnt;
use crate::campaign::learn::failure_counts::FAIL_BINS;
use crate::campaign::report::backends::{self, BackendSummary};
use crate::campaign::report::suite::summary;
pub use crate::campaign::report::suite::{DISTINCT_IOU, SuiteSummary};
use crate::campaign::report::user_report::{self, Invocation};
use crate::campaign::report::verdicts::{TestVerdict, verdicts};
use crate::campaign::store::journal::{FlightRecord, Journal};
use crate::campaign::store::journal_check::inside_bytes;
use crate::generator::adaptive::DRAW_NAMES;
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

fn opt(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.3}"))
}

/// The report as Markdown.
pub fn markdown(r: &Report) -> String {
    let s = &r.suite;
    let mut md = String::new();
    user_report::opening(&mut md, &r.view(), &r.folder);
    let _ = writeln!(
        md,
        "## Appendix: diagnostics\n\nFor judging the run itself: how well the low-fidelity simulator (LFS) predicted \
         the flights, what the campaign learnt, and where the time went.\n\n{} candidates screened; judge {}: {}\n\n{}",
        s.candidates_screened,
        r.judge,
        r.judge_definition,
        user_report::DEFINITIONS
    );
    summary_table(&mut md, r);
    if s.confirm > 1 {
        crate::campaign::report::verdicts::markdown(&mut md, &r.tests, s.confirm);
    }
    backends::markdown(&mut md, &r.backends);
    if let Some(l) = &r.learning {
        learning_section(&mut md, l);
    }
    flights_table(&mut md, r);
    md
}

/// The suite's numbers and the stages' wall times.
fn summary_table(md: &mut String, r: &Report) {
    let s = &r.suite;
    let _ = writeln!(md, "| metric | value |\n|---|---|");
    let failing = if s.confirm > 1 {
        "confirmed failing tests"
    } else {
        "failing tests (< 1.5 m)"
    };
    let _ = writeln!(md, "| {failing} / flown | {} / {} |", s.failing, s.flown);
    let _ = writeln!(
        md,
        "| distinct failing tests (none overlapping a better one by IoU > {DISTINCT_IOU}) | {} |",
        s.distinct_failing
    );
    let _ = writeln!(md, "| failing tests with three obstacles | {} |", s.failing_with_three);
    let _ = writeln!(md, "| failure score | {:.3} |", s.failure_score);
    let _ = writeln!(md, "| diversity | {} |", opt(s.diversity));
    if s.confirm > 1 {
        confirm_rows(md, s);
    }
    let _ = writeln!(
        md,
        "| LFS precision (predicted < 1.5 m that flew < 1.5 m) | {} |",
        opt(s.lfs_precision)
    );
    let _ = writeln!(md, "| LFS mean absolute error | {} m |", opt(s.lfs_mean_abs_error_m));
    let _ = writeln!(
        md,
        "| LFS ensemble p_fail Brier (flown tests) | {} |",
        opt(s.lfs_p_fail_brier)
    );
    let _ = writeln!(
        md,
        "| LFS ranking: Spearman of the ranked prediction against the flown distance (first flights) | {} |",
        opt(s.lfs_spearman)
    );
    let throughput = (s.screening_per_s > 0.0).then_some(s.screening_per_s);
    let _ = writeln!(md, "| screening throughput | {} candidates/s |", opt(throughput));
    let st = &r.stages;
    let _ = writeln!(
        md,
        "| wall time: sample / screen / ensemble / learn / fly / report | {:.2} / {:.2} / {:.2} / {:.2} / {:.2} / {:.2} s |",
        st.sample_s, st.screen_s, st.ensemble_s, st.learn_s, st.fly_s, st.report_s
    );
    if let Some(idle) = st.vehicles_idle() {
        let _ = writeln!(
            md,
            "| vehicles idle from the first take-off to the last landing | {:.1} % of {:.0} vehicle-seconds |",
            100.0 * idle,
            st.vehicle_span_s
        );
    }
    md.push('\n');
}

/// With `--confirm`: the numbers above are over the confirmed tests; these over every test that failed.
fn confirm_rows(md: &mut String, s: &SuiteSummary) {
    let _ = writeln!(
        md,
        "| tests that failed at least once (confirmed: more than half of up to {} flights failed) | {} |",
        s.confirm, s.failed_once
    );
    let _ = writeln!(
        md,
        "| failure score / diversity over every test that failed at least once | {:.3} / {} |",
        s.failure_score_failed_once,
        opt(s.diversity_failed_once)
    );
    let _ = writeln!(
        md,
        "| flights that flew a test again; confirmation rate (2nd flight failed too / flown again) | {}; {} / {} |",
        s.reflights, s.failed_again, s.flown_again
    );
}

/// What a learning campaign learnt: the calibration, the kernel, the rounds and where the flights failed.
fn learning_section(md: &mut String, l: &Learnt) {
    let _ = writeln!(
        md,
        "## Learning\n\nLFS bias learnt: {:+.3} m from {} flights (prior {:+.3} m weighing {} flights).\n",
        l.calibration.bias_m(),
        l.calibration.flights,
        l.calibration.prior_bias_m,
        l.calibration.prior_flights
    );
    if let Some(k) = &l.surrogate {
        let _ = writeln!(
            md,
            "Flights' kernel at the end: bandwidth {:.2} (unit draws), LFS weight {:.2}; leave-one-out error {:.3} m \
             against {:.3} m for the calibrated LFS alone, over {} flights.\n",
            k.bandwidth, k.lfs_weight, k.loo_error_m, k.lfs_error_m, k.flights
        );
    }
    let _ = writeln!(
        md,
        "| round | candidates (near flights) | flights (share offered near) | bias used m | kernel h / LOO error m | draw means ({}) |",
        DRAW_NAMES.join(", ")
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for round in &l.rounds {
        let means: Vec<String> = round.draw_means.iter().map(|m| format!("{m:.2}")).collect();
        let kernel = round.surrogate.map_or("LFS alone".to_string(), |k| {
            format!("{:.2} / {:.3}", k.bandwidth, k.loo_error_m)
        });
        let near = if round.near_miss_parents {
            format!("{} near misses", round.local_candidates)
        } else {
            round.local_candidates.to_string()
        };
        let _ = writeln!(
            md,
            "| {} | {} ({}) | {} ({:.2}) | {:+.3} | {} | {} |",
            round.round + 1,
            round.candidates,
            near,
            round.flights,
            round.local_flight_share,
            round.bias_m,
            kernel,
            means.join(", ")
        );
    }
    failure_bins(md, l);
}

/// Failures per bin of each draw, and per arm (near failures, near misses, elsewhere).
fn failure_bins(md: &mut String, l: &Learnt) {
    let fm = &l.failure_counts;
    let _ = writeln!(
        md,
        "\nWhere the flights failed (failures / flights per bin of each draw's unit range; {} of {} overall):\n",
        fm.total.failures, fm.total.flights
    );
    let edges: Vec<String> = (0..FAIL_BINS)
        .map(|k| {
            format!(
                "{:.1}-{:.1}",
                k as f64 / FAIL_BINS as f64,
                (k + 1) as f64 / FAIL_BINS as f64
            )
        })
        .collect();
    let _ = writeln!(md, "| draw | {} |", edges.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(FAIL_BINS));
    for (name, row) in DRAW_NAMES.iter().zip(&fm.draws) {
        let cells: Vec<String> = row.iter().map(|c| format!("{} / {}", c.failures, c.flights)).collect();
        let _ = writeln!(md, "| {name} | {} |", cells.join(" | "));
    }
    let (near, misses, other) = (l.drawn_near_failures, l.drawn_near_misses, l.drawn_elsewhere);
    if near.flights + misses.flights > 0 {
        let _ = writeln!(
            md,
            "\nCandidates drawn near failing flights failed {} of {} flights (those closer to a flown test than \
             --max-iou: {} of {}); near the closest flights before the first failure, {} of {}; the others {} of \
             {}.",
            near.failures,
            near.flights,
            l.drawn_close.failures,
            l.drawn_close.flights,
            misses.failures,
            misses.flights,
            other.failures,
            other.flights
        );
    }
    let _ = writeln!(md);
}

/// Every flight, in flight order.
fn flights_table(md: &mut String, r: &Report) {
    let _ = writeln!(
        md,
        "## Flights\n\n| candidate | predicted m | p_fail | flown m | raw m | status | time s | points | score | reported as |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|");
    for f in &r.flights {
        let _ = writeln!(
            md,
            "| {} | {:.3} | {} | {} | {} | {} | {:.1} | {} | {:.3} | {} |",
            match f.attempt {
                0 => f.candidate.to_string(),
                a => format!("{} (flight {})", f.candidate, a + 1),
            },
            f.predicted_min_distance,
            opt(f.predicted_p_fail),
            opt(f.min_distance),
            opt(f.min_distance_raw),
            f.reason.as_deref().map_or(f.status.clone(), |why| format!(
                "{} ({})",
                f.status,
                why.replace('|', "/")
            )),
            f.flight_time_s,
            f.points,
            f.test_score,
            f.reported_as.as_deref().unwrap_or("")
        );
    }
}
