//! Time handling that stays linear in the samples, whatever the timestamps say.

use std::path::Path;
use std::time::{Duration, Instant};

use proptest::prelude::*;

use super::*;
use crate::judge::{Judge, judge_flight};
use crate::model::Obstacle;

fn at(t_s: f64) -> Sample {
    Sample {
        t_s,
        x: t_s.min(1e3),
        y: 0.0,
        z: 1.0,
        r: None,
    }
}

/// The binning as Aerialist writes it, one bin after another: the reference for real flights.
fn stepwise(t: &Trajectory, period_s: f64) -> Trajectory {
    let s = &t.samples;
    let mut out = Vec::new();
    let mut start = s[0].t_s;
    let mut i = 0;
    while i < s.len() {
        let from = i;
        while i < s.len() && s[i].t_s <= start + period_s {
            i += 1;
        }
        if i > from {
            out.push(mean(&s[from..i]));
        }
        start += period_s;
    }
    Trajectory::new(out)
}

#[test]
fn a_row_at_1e18_us_bins_at_once() {
    let t = Trajectory::new(vec![at(0.0), at(1e12), at(1e12 + 0.6), at(1e12 + 0.8)]);
    let clock = Instant::now();
    let b = t.binned(0.5);
    assert!(clock.elapsed() < Duration::from_millis(100), "{:?}", clock.elapsed());
    assert_eq!(b.samples.len(), 3, "{b:?}");
    assert_eq!(b.samples[0].t_s, 0.0);
    // Bins stay whole periods from the first sample: 1e12 s ends one, the next two share the following.
    assert_eq!(b.samples[1].t_s, 1e12);
    assert_eq!(b.samples[2].t_s, 1e12 + 0.7);
}

#[test]
fn degenerate_times_end() {
    for t in [
        vec![at(0.0), at(1e300)],
        vec![at(1e300), at(1e300), at(f64::MAX)],
        vec![at(0.0), at(f64::INFINITY)],
        vec![at(0.0), at(f64::NAN), at(1.0)],
    ] {
        let b = Trajectory::new(t.clone()).binned(0.5);
        assert!(!b.samples.is_empty() && b.samples.len() <= t.len(), "{t:?}");
    }
    let b = Trajectory::new(vec![at(0.0), at(1.0), at(2.0)]).binned(0.0);
    assert_eq!(b.samples.len(), 1, "a zero period ends, in one bin");
}

#[test]
fn recorded_flights_bin_bit_for_bit_as_aerialist() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/px4-flights/traj");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let t = Trajectory::load_csv(&path).unwrap_or_else(|e| panic!("{e}"));
        let aligned = t.origin_aligned();
        assert_eq!(aligned.binned(0.5), stepwise(&aligned, 0.5), "{}", path.display());
        assert_eq!(t.binned(0.5), stepwise(&t, 0.5), "{}", path.display());
        seen += 1;
    }
    assert!(seen > 100, "{seen} flights");
}

#[test]
fn gaps_just_under_the_jump_bin_as_aerialist() {
    // Pauses around JUMP_BINS periods: stepping and jumping must agree on which samples share a bin.
    let mut samples = vec![at(0.0)];
    for pause in [0.3, 511.9, 512.0, 512.1, 513.0, 2000.25, 3599.0] {
        let last = samples.last().unwrap().t_s;
        samples.extend([at(last + pause), at(last + pause + 0.1), at(last + pause + 0.7)]);
    }
    let t = Trajectory::new(samples);
    let (fast, slow) = (t.binned(0.5), stepwise(&t, 0.5));
    assert_eq!(fast.samples.len(), slow.samples.len());
    for (a, b) in fast.samples.iter().zip(&slow.samples) {
        assert_eq!(a.x, b.x, "same bin members");
    }
}

#[test]
fn a_pause_over_an_hour_or_time_going_back_is_refused_naming_the_row() {
    let e = Trajectory::parse_csv(
        "timestamp,x,y,z,r\n0,0,0,0,\n1000000000000000000,0,0,10,\n",
        Path::new("f.csv"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("f.csv:3") && e.contains("at most 3600 s"), "{e}");
    let e = Trajectory::parse_csv("timestamp,x,y,z\n5,0,0,0\n\n4,0,0,0\n", Path::new("g.csv"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("g.csv:4") && e.contains("goes back in time"), "{e}");
    let hour = "timestamp,x,y,z\n0,0,0,0\n3600000000,0,0,0\n";
    assert!(
        Trajectory::parse_csv(hour, Path::new("h.csv")).is_ok(),
        "exactly an hour is a pause"
    );
}

/// What `distance` and `score` do with a flight file: parse, then judge.
fn parse_and_judge(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    if let Ok(t) = Trajectory::parse_csv(text, Path::new("f.csv")) {
        let obstacles = [Obstacle::new(10.0, 2.0, 20.0, -5.0, 20.0, 30.0)];
        for judge in [Judge::E2025, Judge::E2026] {
            let _ = judge_flight(&t, &obstacles, judge);
        }
    }
}

/// CSV-ish text: a header, then rows of numbers that are sometimes huge, negative or not numbers.
fn csv_like() -> impl Strategy<Value = Vec<u8>> {
    let cell = prop_oneof![
        any::<i64>().prop_map(|v| v.to_string()),
        any::<f64>().prop_map(|v| v.to_string()),
        (0u64..100_000_000).prop_map(|v| v.to_string()),
        Just("1e18".to_string()),
        Just(String::new()),
        "[-0-9.eE]{0,6}",
    ];
    let row = proptest::collection::vec(cell, 3..6).prop_map(|c| c.join(","));
    proptest::collection::vec(row, 0..40)
        .prop_map(|rows| format!("timestamp,x,y,z,r\n{}", rows.join("\n")).into_bytes())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn any_bytes_parse_and_judge_quickly(bytes in prop_oneof![proptest::collection::vec(any::<u8>(), 0..400), csv_like()]) {
        let clock = Instant::now();
        parse_and_judge(&bytes);
        prop_assert!(clock.elapsed() < Duration::from_secs(1), "{:?} on {:?}", clock.elapsed(), String::from_utf8_lossy(&bytes));
    }
}
