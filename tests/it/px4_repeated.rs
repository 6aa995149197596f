//! `tests/data/px4-repeated`: the written tests of six PX4 v1.14 campaigns, each flown 10 times. The data is
//! read by `examples/surrogate_rank.rs` and quoted in docs/evaluate.md; these checks keep it whole and keep
//! the quoted suite totals tied to it.

use std::collections::BTreeMap;

use prgenuav::judge::test_score;
use prgenuav::model::{Arena, Obstacle, TestCase};
use prgenuav::rules::check_obstacles;
use serde::Deserialize;

use super::repo;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Row {
    mission: u32,
    suite: String,
    test: String,
    obstacles: Vec<Obstacle>,
    px4_min_distance: Vec<f64>,
    px4_flight_time_s: Vec<f64>,
    evaluation: Vec<u8>,
}

fn rows() -> Vec<Row> {
    let path = repo().join("tests/data/px4-repeated/tests.jsonl");
    let text = std::fs::read_to_string(&path).expect("the data file");
    (text.lines().enumerate())
        .map(|(i, l)| serde_json::from_str(l).unwrap_or_else(|e| panic!("{}:{}: {e}", path.display(), i + 1)))
        .collect()
}

#[test]
fn every_test_is_valid_and_flown_ten_times_in_two_evaluations() {
    let rows = rows();
    assert_eq!(rows.len(), 59);
    for r in &rows {
        let id = format!("{} {}", r.suite, r.test);
        assert!(r.suite.starts_with(&format!("m{}-", r.mission)), "{id}");
        assert_eq!(r.px4_min_distance.len(), 10, "{id}");
        assert_eq!(r.px4_flight_time_s.len(), 10, "{id}");
        assert_eq!(r.evaluation, [1, 1, 1, 1, 1, 2, 2, 2, 2, 2], "{id}");
        assert!(r.px4_min_distance.iter().all(|d| (0.0..30.0).contains(d)), "{id}");
        assert!(r.px4_flight_time_s.iter().all(|t| (30.0..500.0).contains(t)), "{id}");
        let case = TestCase::load(&repo().join(format!("missions/mission{}.yaml", r.mission))).expect("mission");
        let broken = check_obstacles(&r.obstacles, &case.mission, &Arena::COMPETITION);
        assert!(broken.is_empty(), "{id}: {broken:?}");
    }
}

#[test]
fn the_suite_totals_quoted_in_the_docs_come_from_this_data() {
    let mut totals: BTreeMap<&str, f64> = BTreeMap::new();
    let rows = rows();
    for r in &rows {
        *totals.entry(&r.suite).or_default() +=
            test_score(&r.px4_min_distance, &r.px4_flight_time_s, r.obstacles.len());
    }
    // The pooled totals before sim_pen (docs/evaluate.md).
    let quoted = [
        ("m2-new", 7.237),
        ("m2-no-screen", 8.194),
        ("m2-old", 7.100),
        ("m5-new", 11.760),
        ("m5-no-screen", 8.707),
        ("m5-old", 12.940),
    ];
    for (suite, want) in quoted {
        let got = totals.get(suite).copied().unwrap_or(f64::NAN);
        assert!((got - want).abs() < 0.0015, "{suite}: {got} against {want}");
    }
}
