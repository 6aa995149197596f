//! Loading a prior (`learnt.json`) for a learning campaign.

use super::*;
use crate::campaign::learn::failure_counts::{BinCount, FailureCounts};
use crate::generator::adaptive::DIMS;

#[test]
fn a_prior_with_only_the_paper_draws_still_seeds_a_campaign() {
    let dir = tempfile::tempdir().unwrap();
    let mut distribution = DrawDistribution::uniform();
    distribution.weights[2] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0];
    let mut counts = FailureCounts::default();
    counts.observe(&[0.9; DIMS], true);
    let l = Learnt {
        calibration: Calibration::with_prior(0.7, 12.0),
        surrogate: None,
        distribution,
        rounds: Vec::new(),
        failure_counts: counts,
        drawn_near_failures: BinCount::default(),
        drawn_near_misses: BinCount::default(),
        drawn_elsewhere: BinCount::default(),
        drawn_close: BinCount::default(),
    };
    // A prior learnt before the generator had extra draws: one row per paper draw.
    let mut json = serde_json::to_value(&l).unwrap();
    for (field, rows) in [("distribution", "weights"), ("failure_counts", "draws")] {
        let rows = json[field][rows].as_array_mut().unwrap();
        rows.truncate(crate::generator::adaptive::PAPER_DIMS);
    }
    std::fs::write(dir.path().join("learnt.json"), json.to_string()).unwrap();
    let read = load_prior(dir.path()).unwrap();
    assert_eq!(read.distribution, l.distribution, "the extra draws start uniform");
    assert_eq!(read.failure_counts.draws[2], l.failure_counts.draws[2]);
    assert_eq!(
        read.failure_counts.draws[6],
        [BinCount::default(); 5],
        "no counts for the extra draws"
    );
    assert_eq!(read.calibration, l.calibration);
}

#[test]
fn a_bad_prior_file_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    assert!(load_prior(dir.path()).unwrap_err().to_string().contains("learnt.json"));
    let mut l = Learnt {
        calibration: Calibration::default(),
        surrogate: None,
        distribution: DrawDistribution::uniform(),
        rounds: Vec::new(),
        failure_counts: FailureCounts::default(),
        drawn_near_failures: BinCount::default(),
        drawn_near_misses: BinCount::default(),
        drawn_elsewhere: BinCount::default(),
        drawn_close: BinCount::default(),
    };
    l.calibration.prior_flights = -3.0;
    std::fs::write(dir.path().join("learnt.json"), serde_json::to_string(&l).unwrap()).unwrap();
    let e = load_prior(dir.path()).unwrap_err().to_string();
    assert!(e.contains("learnt.json") && e.contains("prior_flights"), "{e}");
}
