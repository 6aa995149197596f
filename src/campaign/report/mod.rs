//! What a campaign hands its user: each test's verdict over its flights ([`verdicts`]), the suite's numbers
//! ([`suite`]), the per-backend figures ([`backends`]), the report as data ([`document`]), the written tests and report.json ([`outputs`]), report.md
//! ([`user_report`] opens it for people, [`markdown`] adds the appendix), and what the suite is expected to earn in 2026 ([`expected`]).

pub mod backends;
pub mod cp_tests;
pub mod document;
pub mod expected;
pub mod markdown;
pub mod outputs;
pub mod suite;
pub mod user_report;
pub mod verdicts;
