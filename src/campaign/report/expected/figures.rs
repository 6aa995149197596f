//! The expected 2026 figures of a campaign's tests and of its written suite, as report.json carries them
//! (computed by [`crate::campaign::report::expected::score`]).

use serde::Serialize;

use crate::campaign::report::expected::expected_points::PointsEstimate;

/// A test's expected 2026 figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TestExpectation {
    /// Expected points of a flight, with the 10-90 % intervals of that expectation and of the judge's mean.
    pub points: PointsEstimate,
    /// Expected flight time, minutes: its flown flights' mean (the prediction when none has a distance).
    pub minutes: f64,
    /// Expected 2026 test score: expected points x 10 / (obstacles² x minutes).
    pub score: f64,
    /// The score at the 10 % quantile of the judge's mean points.
    pub score_low: f64,
    /// The score at their 90 % quantile.
    pub score_high: f64,
    /// Standard deviation of the score the judge will give.
    pub score_sd: f64,
}

/// The written suite's expected 2026 score.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuiteExpectation {
    /// Tests written.
    pub tests: usize,
    /// Tests that earned a place but were set aside as near-duplicate trajectories.
    pub near_duplicates: usize,
    /// The DTW distance below which two average trajectories are too similar (`evaluate`'s default), m.
    pub similar_below_m: f64,
    /// The guard's threshold: a test whose flown average lies closer than this to a better written test's is
    /// more likely than not too similar for the judge, and set aside, m. Further ones are written when they
    /// raise the expected score.
    pub guard_below_m: f64,
    /// Sum of the written tests' expected scores.
    pub total_score: f64,
    /// 10 % quantile of the sum the judge will give: the tests scatter independently, so the sum's standard
    /// deviation is the root of their variances' sum (normal approximation, at least 0).
    pub total_low: f64,
    /// Its 90 % quantile.
    pub total_high: f64,
    /// The expected similarity penalty of the written tests: 1 - the sum of their chances of being found too
    /// similar to a better one / tests.
    pub sim_pen: f64,
    /// total_score x sim_pen: the expected 2026 score.
    pub final_score: f64,
    /// total_low x sim_pen.
    pub final_low: f64,
    /// total_high x sim_pen.
    pub final_high: f64,
}
