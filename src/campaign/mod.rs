//! The competition-ready campaign: screening, flights within a budget, journal, reports and scores.

pub mod score;
