//! What a campaign expects its written suite to earn under the 2026 scoring: each test's expected points
//! ([`score`], with the figures report.json carries in [`figures`]), and the guard that sets aside tests whose
//! flown trajectories the judge would count as near-duplicates ([`trajectory_guard`]).

pub mod expected_points;
pub mod figures;
pub mod judged_mean;
pub mod score;
pub mod trajectory_guard;
