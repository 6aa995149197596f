//! The competition-ready campaign, one pipeline in stages: [`plan`] draws and ranks candidates, [`screen`]
//! predicts them with the LFS, [`fly`] flies the best on the vehicles within the budget, [`learn`] calibrates
//! the LFS on the flights, [`store`] keeps the folder, journal and resume, and [`report`] writes the tests.
//! [`conductor`] conducts the rounds and [`run`] runs a campaign; [`ground`] holds what every stage shares.

pub mod conductor;
pub mod evaluation;
pub mod fly;
pub mod ground;
pub mod learn;
pub mod plan;
pub mod report;
pub mod run;
pub mod screen;
pub mod settings;
pub mod store;
