//! report.md: the user's opening (the verdict, the tests and pictures), then the appendix of the learning and
//! screening diagnostics with each metric defined, the rounds, where the flights failed and every flight.

use std::fmt::Write as _;

use crate::campaign::learn::calibration::Learnt;
use crate::campaign::learn::failure_counts::FAIL_BINS;
use crate::campaign::report::backends;
use crate::campaign::report::document::Report;
use crate::campaign::report::suite::{DISTINCT_IOU, SuiteSummary};
use crate::campaign::report::user_report;
use crate::generator::adaptive::DRAW_NAMES;

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
    crate::campaign::report::verdicts::markdown(&mut md, &r.tests, s.confirm);
    crate::campaign::report::cp_tests::markdown(&mut md, &r.collision_prevention);
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
    let failing = "written tests (expected to earn 2026 points)";
    let _ = writeln!(md, "| {failing} / flown | {} / {} |", s.failing, s.flown);
    let _ = writeln!(
        md,
        "| distinct failing tests (none overlapping a better one by IoU > {DISTINCT_IOU}) | {} |",
        s.distinct_failing
    );
    let _ = writeln!(md, "| failing tests with three obstacles | {} |", s.failing_with_three);
    let _ = writeln!(md, "| failure score | {:.3} |", s.failure_score);
    let _ = writeln!(md, "| diversity | {} |", opt(s.diversity));
    crate::campaign::report::expected::score::markdown_rows(md, s.expected_2026.as_ref());
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
        "| tests that failed at least once (each flown up to {} times) | {} |",
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
            "| {} | {} | {} | {} | {} | {} | {:.1} | {} | {:.3} | {} |",
            match f.attempt {
                0 => f.candidate.to_string(),
                a => format!("{} (flight {})", f.candidate, a + 1),
            },
            opt(f.predicted_min_distance),
            opt(f.predicted_p_fail),
            opt(f.min_distance),
            opt(f.min_distance_raw),
            f.reason.as_deref().map_or(f.status.to_string(), |why| format!(
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
