//! The competition-ready campaign: screening, flights within a budget, journal, reports and scores.

pub mod candidate;
pub mod config;
pub mod diversity_guard;
pub mod draw;
pub mod failure_counts;
pub mod flights;
pub mod journal;
pub mod learn;
pub mod learning;
pub mod neighbours;
pub mod parallel;
pub mod pool;
pub mod px4_vehicle;
pub mod rank;
pub mod report;
pub mod rounds;
pub mod run;
pub mod score;
pub mod screen;
pub mod screener;
pub mod screening;
pub mod static_campaign;
pub mod surrogate;
pub mod vehicles;
