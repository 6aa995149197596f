//! The 2026 evaluation of a suite: every test flown several times, scored by its mean points, and the
//! suite's total multiplied by the similarity penalty of the tests' average trajectories
//! (`docs/evaluate.md`). `suite` computes it from flights; `folder` reads flights already on disk
//! and `folder_score` gives them the competition's metrics.

pub mod flying;
pub mod folder;
pub mod folder_score;
pub mod kept;
pub mod listing;
pub mod missing;
pub mod report;
pub mod runs;
pub mod suite;

pub use folder::evaluate_folder;
pub use suite::{Evaluation, FlownTest, evaluate_suite};

/// The competition flies each test this many times.
pub const RUNS_2026: usize = 5;
