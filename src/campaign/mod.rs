//! The competition-ready campaign: screening, flights within a budget, journal, reports and scores.

pub mod diversity_guard;
pub mod failure_counts;
pub mod journal;
pub mod learn;
pub mod neighbours;
pub mod parallel;
pub mod pool;
pub mod rank;
pub mod report;
pub mod rounds;
pub mod run;
pub mod score;
pub mod screen;
pub mod stages;
pub mod surrogate;
pub mod vehicles;
