//! The part of the campaign's report written for its user: the verdict in plain words and what to do next,
//! how to reproduce the run, the written tests with their files, and two pictures of the whole suite. The
//! learning and screening diagnostics follow it as an appendix (see `report.rs`).

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use super::suite::SuiteSummary;
use super::verdicts::TestVerdict;
use crate::campaign::ground::input::CampaignInput;
use crate::io::write_atomic;
use crate::judge::{Judge, above_top_count};
use crate::model::{ModelError, Spelling};
use crate::plot::suite::{Layout, Point, layouts_svg, scatter_svg};

/// The sub-folder of the tests that failed but were not confirmed.
pub const UNCONFIRMED_DIR: &str = "unconfirmed";
/// The picture of the failing layouts over the mission.
pub const SUITE_SVG: &str = "suite.svg";
/// The picture of the predicted against the flown distance of every flight.
pub const SCATTER_SVG: &str = "predicted_vs_flown.svg";
/// Below this flown distance a flight fails (the competition's threshold), metres.
const FAIL_M: f64 = 1.5;

/// How the run was started: the command line as typed (arguments quoted where a shell needs it) and the
/// prgenuav version.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Invocation {
    /// The command line.
    pub command: String,
    /// prgenuav's version.
    pub version: String,
}

impl Invocation {
    /// This process's command line, with the program named `prgenuav`.
    pub fn current() -> Self {
        let mut args: Vec<String> = std::env::args().skip(1).map(|a| quote(&a)).collect();
        args.insert(0, "prgenuav".into());
        Self {
            command: args.join(" "),
            version: env!("CARGO_PKG_VERSION").into(),
        }
    }
}

fn quote(arg: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=:,@+%".contains(c);
    if !arg.is_empty() && arg.chars().all(plain) {
        arg.to_string()
    } else {
        format!("'{}'", arg.replace('\'', r"'\''"))
    }
}

/// What this part of the report reads of the whole report.
pub struct View<'a> {
    /// The case study as given.
    pub case: &'a str,
    /// The campaign's seed.
    pub seed: u64,
    /// The flight budget.
    pub budget: usize,
    /// The judge edition.
    pub judge: Judge,
    /// The suite's numbers.
    pub suite: &'a SuiteSummary,
    /// Every test that failed at least once, best first.
    pub tests: &'a [TestVerdict],
    /// Every flight with a flown distance: predicted and flown distance, and whether its test was written.
    pub flights: Vec<Point>,
    /// How the run was started.
    pub invocation: &'a Invocation,
}

/// Writes each unconfirmed test as `unconfirmed/test_K.yaml`, best first, so it can be flown again, and
/// names it in its verdict.
pub fn write_unconfirmed(
    input: &CampaignInput,
    tests: &mut [TestVerdict],
    spelling: Spelling,
) -> Result<(), ModelError> {
    let case = input.case.with_absolute_references()?;
    for (k, t) in tests.iter_mut().filter(|t| !t.confirmed).enumerate() {
        let name = format!("{UNCONFIRMED_DIR}/test_{k}.yaml");
        case.with_obstacles(t.obstacles.clone())
            .save(&input.folder.join(&name), spelling)?;
        t.reported_as = Some(name);
    }
    Ok(())
}

/// Writes [`SUITE_SVG`] and [`SCATTER_SVG`] into the campaign folder.
pub fn write_pictures(input: &CampaignInput, r: &View) -> Result<(), ModelError> {
    let layouts: Vec<Layout> = (r.tests.iter())
        .filter(|t| t.confirmed)
        .map(|t| Layout {
            label: format!(
                "{}: flew {:.2} m",
                t.reported_as.as_deref().unwrap_or("?").trim_end_matches(".yaml"),
                t.best_min_distance
            ),
            obstacles: t.obstacles.clone(),
        })
        .collect();
    let title = format!("{} failing tests of {} over the mission", layouts.len(), r.case);
    write_atomic(
        &input.folder.join(SUITE_SVG),
        layouts_svg(input.case, &layouts, &title).as_bytes(),
    )?;
    let title = format!(
        "{} flights: the low-fidelity prediction against the flight",
        r.flights.len()
    );
    write_atomic(
        &input.folder.join(SCATTER_SVG),
        scatter_svg(&r.flights, FAIL_M, &title).as_bytes(),
    )
}

/// The verdict in two or three plain sentences: what was found, how sure, and what to do next (with the
/// command). `folder` is the campaign folder as the user named it.
pub fn verdict(r: &View, folder: &Path) -> Vec<String> {
    let unconfirmed: Vec<&TestVerdict> = r.tests.iter().filter(|t| !t.confirmed).collect();
    let mut lines = Vec::new();
    if r.suite.failing > 0 {
        found(r, folder, &unconfirmed, &mut lines);
    } else if !unconfirmed.is_empty() {
        only_unconfirmed(r, folder, &unconfirmed, &mut lines);
    } else {
        none_failed(r, &mut lines);
    }
    lines
}

/// The verdict when confirmed failing tests were found.
fn found(r: &View, folder: &Path, unconfirmed: &[&TestVerdict], lines: &mut Vec<String>) {
    let s = &r.suite;
    let best = r
        .tests
        .iter()
        .find(|t| t.confirmed)
        .map_or(f64::NAN, |t| t.best_min_distance);
    lines.push(format!(
        "Found {} ({} distinct) in {}: the drone flew closer than {FAIL_M} m to an obstacle; test_0, the \
         best expected 2026 score, came to {best:.2} m.",
        plural(s.failing, "failing test"),
        s.distinct_failing,
        plural(s.flown, "flight")
    ));
    if let Some(crossed) = above_top(r) {
        lines.push(crossed);
    }
    let (unsure, copies) = set_aside(unconfirmed.iter().copied());
    lines.push(how_sure(s.expected_2026.as_ref(), unsure, copies));
    lines.push(format!(
        "Next: open test_0.svg, or fly it again: prgenuav fly {}",
        folder.join("test_0.yaml").display()
    ));
}

/// How many written tests came closest to a box while above its top, where the judge's distance is not
/// the vehicle's (`None` when none did).
pub fn above_top(r: &View) -> Option<String> {
    let (tests, lowest) = above_top_count(r.tests.iter().filter(|t| t.confirmed).map(|t| t.above_top))?;
    Some(format!(
        "Of them, {} came closest to a box above its top (the lowest {lowest:.2} m above): {}. Boxes higher \
         than the vehicle climbs (`--height`, default 20 m) rule this out.",
        plural(tests, "test"),
        r.judge.above_top_rule()
    ))
}

/// The verdict when tests failed but none was confirmed.
fn only_unconfirmed(r: &View, folder: &Path, unconfirmed: &[&TestVerdict], lines: &mut Vec<String>) {
    let s = &r.suite;
    let unsettled = unconfirmed.iter().filter(|t| !t.settled).count();
    lines.push(format!(
        "No test expected to earn 2026 points surely enough in {}, but {} failed at least once (the closest \
         at {:.2} m).",
        plural(s.flown, "flight"),
        plural(unconfirmed.len(), "test"),
        unconfirmed
            .iter()
            .map(|t| t.best_min_distance)
            .fold(f64::INFINITY, f64::min)
    ));
    lines.push(if unsettled > 0 {
        format!(
            "How sure: not yet; the budget ran out before {unsettled} of them could be flown again (a test \
             is written when the 10 % bound of its expected points is above zero)."
        )
    } else {
        "How sure: they failed, but too rarely over their flights to expect points surely.".into()
    });
    lines.push(format!(
        "Next: fly one again (prgenuav fly {}), or run a larger budget: prgenuav generate {} {} --seed {}",
        folder.join(UNCONFIRMED_DIR).join("test_0.yaml").display(),
        r.case,
        2 * r.budget,
        r.seed
    ));
}

/// The verdict when no flight failed, or none was flown at all.
fn none_failed(r: &View, lines: &mut Vec<String>) {
    let s = &r.suite;
    if s.flown == 0 {
        lines.push("Nothing was flown to its end: no flight was charged to the budget (the warnings say why).".into());
        lines.push("Next: fix what the warnings name, then run it again.".into());
        return;
    }
    let closest = (r.flights.iter()).map(|f| f.flown_m).fold(f64::INFINITY, f64::min);
    let closest = if closest.is_finite() {
        format!(" (the closest came to {closest:.2} m)")
    } else {
        String::new()
    };
    let which = match s.flown {
        1 => "the one flight".to_string(),
        n => format!("all {n} flights"),
    };
    lines.push(format!(
        "No failure: {which} stayed {FAIL_M} m or farther from every obstacle{closest}."
    ));
    lines.push(format!(
        "Next: a larger budget or another seed: prgenuav generate {} {} --seed {}",
        r.case,
        2 * r.budget,
        r.seed + 1
    ));
}

/// The summary on stdout: the suite's figures, what it means and the next step, and the output folder.
pub fn stdout_lines(r: &View, folder: &Path) -> Vec<String> {
    let s = &r.suite;
    let three = if s.failing_with_three > 0 {
        format!(", {} with three obstacles", s.failing_with_three)
    } else {
        String::new()
    };
    let figures = format!(
        "{} ({} distinct at IoU {}{three}) of {} ({}), failure score {:.2}, diversity {}",
        plural(s.failing, "failing test"),
        s.distinct_failing,
        super::suite::DISTINCT_IOU,
        plural(s.flown, "flight"),
        match s.candidates_screened {
            0 => "none screened".to_string(),
            n => format!("{} screened", plural(n, "candidate")),
        },
        s.failure_score,
        s.diversity.map_or("n/a".into(), |d| format!("{d:.3}"))
    );
    let v = verdict(r, folder);
    let next = v.last().cloned().unwrap_or_default();
    let (unsure, copies) = set_aside(r.tests.iter().filter(|t| !t.confirmed));
    let meaning = if s.failing == 0 {
        format!("{} {next}", v[0])
    } else {
        let sure = how_sure(s.expected_2026.as_ref(), unsure, copies);
        let crossed = above_top(r).map_or(String::new(), |c| format!(" {c}"));
        format!("{sure}{crossed} {next}").trim_start().to_string()
    };
    vec![figures, meaning, format!("output folder: {}", folder.display())]
}

/// How many of the failing tests not written lacked evidence, and how many fly like a better written test.
fn set_aside<'a>(unwritten: impl Iterator<Item = &'a TestVerdict>) -> (usize, usize) {
    unwritten.fold((0, 0), |(unsure, copies), t| match t.near_duplicate_of {
        Some(_) => (unsure, copies + 1),
        None => (unsure + 1, copies),
    })
}

/// How sure the written tests are, in one sentence; `unsure`: the tests that failed but were not written
/// for want of evidence, `copies`: those set aside because they fly like a better written test.
fn how_sure(e: Option<&super::expected::figures::SuiteExpectation>, unsure: usize, copies: usize) -> String {
    let Some(e) = e else {
        return "Each written test failed at least once.".into();
    };
    let unsure_part = (unsure > 0).then(|| format!("{} failed but not surely enough", plural(unsure, "more test")));
    let copies_part = (copies > 0).then(|| {
        let verb = if copies == 1 { "flies" } else { "fly" };
        format!("{} {verb} like a better written test", plural(copies, "failing test"))
    });
    let others: Vec<String> = [unsure_part, copies_part].into_iter().flatten().collect();
    let others = match others.is_empty() {
        true => String::new(),
        false => format!("; {} ({UNCONFIRMED_DIR}/)", others.join(", ")),
    };
    format!(
        "Written by expected 2026 points: each is expected to earn points (the 10 % bound above zero); \
         expected 2026 score {:.2} (the judge's 5 flights per test, 10-90 %: {:.2}-{:.2}){others}.",
        e.final_score, e.final_low, e.final_high
    )
}

/// `1 test`, `2 tests`: a count and its noun, plural when the count is not one.
pub fn plural(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// The report's opening: title, verdict, how to reproduce it, the written tests and the suite's pictures.
pub fn opening(md: &mut String, r: &View, folder: &Path) {
    let _ = writeln!(md, "# prgenuav campaign: {}\n", r.case);
    for line in verdict(r, folder) {
        let _ = writeln!(md, "{line}\n");
    }
    let _ = writeln!(
        md,
        "Reproduce: `{}` (prgenuav {}; seed {}, budget {}, judge {}).\n",
        r.invocation.command,
        r.invocation.version,
        r.seed,
        plural(r.budget, "flight"),
        r.judge
    );
    tests_section(md, r);
    let _ = writeln!(
        md,
        "## The suite\n\nThe failing layouts over the mission path (each test's two or three boxes in one colour):\n\n\
         ![failing layouts]({SUITE_SVG})\n\nThe low-fidelity simulator's predicted minimum distance against the \
         flown one, one dot per flight (below the dashed lines: under {FAIL_M} m):\n\n\
         ![predicted against flown]({SCATTER_SVG})\n"
    );
}

/// The written tests with links to their files: the failing ones, then the unconfirmed.
fn tests_section(md: &mut String, r: &View) {
    let _ = writeln!(md, "## Failing tests\n");
    let confirmed: Vec<&TestVerdict> = r.tests.iter().filter(|t| t.confirmed).collect();
    if confirmed.is_empty() {
        let _ = writeln!(md, "None was confirmed.\n");
    } else {
        let _ = writeln!(
            md,
            "Best first. Each is an Aerialist test file; its picture shows the mission, the boxes, the predicted \
             and the flown path and the closest approach.\n\n| test | closest flown | failed / flights | picture |\n|---|---|---|---|"
        );
        for t in confirmed {
            let yaml = t.reported_as.as_deref().unwrap_or("?");
            let svg = yaml.replace(".yaml", ".svg");
            let over = t.above_top.map_or(String::new(), |o| {
                format!(", {:.2} m above obstacle {}", o.height_m, o.obstacle)
            });
            let _ = writeln!(
                md,
                "| [{yaml}]({yaml}) | {:.2} m{over} | {} / {} | [{svg}]({svg}) |",
                t.best_min_distance, t.failures, t.flights
            );
        }
        md.push('\n');
    }
    let unconfirmed: Vec<&TestVerdict> = r.tests.iter().filter(|t| !t.confirmed).collect();
    if !unconfirmed.is_empty() {
        let _ = writeln!(
            md,
            "Failed at least once but not confirmed ({}), written to fly again:\n",
            plural(unconfirmed.len(), "test")
        );
        for t in unconfirmed {
            let yaml = t.reported_as.as_deref().unwrap_or("?");
            let why = match (&t.near_duplicate_of, t.settled) {
                (Some(better), _) => format!(
                    "flies like the better {better}: their flown averages lie {:.0} m apart (DTW)",
                    t.near_duplicate_dtw_m.unwrap_or(f64::NAN)
                ),
                (None, true) => "did not hold".to_string(),
                (None, false) => "budget spent before its confirmation".to_string(),
            };
            let _ = writeln!(
                md,
                "- [{yaml}]({yaml}): {:.2} m, failed {} of {} ({why})",
                t.best_min_distance,
                t.failures,
                plural(t.flights, "flight")
            );
        }
        md.push('\n');
    }
}

/// What the appendix's metrics mean, each in one line.
pub const DEFINITIONS: &str = "\
- **failure score**: the sum of the failing tests' competition scores (points 5 / 2 / 1 below 0.25 / 1 / 1.5 m, \
times 10, over obstacles squared times the flight time in minutes).
- **diversity**: 1 - the mean IoU (overlap) of every pair of failing tests' obstacle footprints; n/a below two tests.
- **LFS**: the low-fidelity simulator that predicts each flight before it is flown. **Precision**: of the flights \
it predicted below 1.5 m, the share that flew below 1.5 m. **Mean absolute error**: of its predicted distance.
- **p_fail** and **Brier**: the LFS ensemble's probability that a flight fails, and the mean squared difference \
between it and what happened (0 is perfect, 0.25 is a coin toss).
- **Spearman**: the rank correlation of the ranking's predicted distance with the flown one (1: the same order, \
0: unrelated, negative: reversed).
- **vehicles idle**: the share of vehicle time from the first take-off to the last landing that vehicles waited.
- **bias**: the learnt offset added to the LFS prediction. **Kernel h / LOO error**: the bandwidth of the \
flights' kernel, in units of each draw's range scaled to 0-1 (*unit draws*), and its leave-one-out error.
- **share offered near**: the share of a round's flights drawn near earlier failures.
";

#[cfg(test)]
#[path = "user_report_tests.rs"]
mod tests;
