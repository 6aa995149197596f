//! A journal damaged by a crash: what resume drops, what it refuses, and that no byte string panics.

use crate::campaign::ground::flight_status::FlightStatus;
use proptest::prelude::*;

use super::tests::{line, record};
use super::*;

fn journal(bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("journal.jsonl");
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

#[test]
fn a_torn_last_line_is_dropped_and_the_next_record_starts_clean() {
    let whole = [line(1), line(2)].concat();
    let torn = &line(3)[..40];
    let (_d, path) = journal(format!("{whole}{torn}").as_bytes());
    let said = Journal::heal(&path).unwrap().unwrap();
    assert!(
        said.contains("journal.jsonl:3") && said.contains("40 bytes") && said.contains("flown again"),
        "{said}"
    );
    assert_eq!(std::fs::read_to_string(&path).unwrap(), whole);
    let mut j = Journal::open(&path).unwrap();
    j.append(&record(3)).unwrap();
    assert_eq!(Journal::read(&path).unwrap(), vec![record(1), record(2), record(3)]);
    assert_eq!(Journal::heal(&path).unwrap(), None, "a sound journal is left alone");
}

#[test]
fn a_complete_last_record_without_its_newline_is_kept_and_ended() {
    let text = [line(1), line(2)].concat();
    let (_d, path) = journal(text.trim_end().as_bytes());
    assert_eq!(Journal::heal(&path).unwrap(), None, "nothing dropped");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
}

#[test]
fn a_damaged_middle_line_or_a_terminated_bad_last_line_stops_naming_the_line_and_the_fix() {
    for (text, at) in [
        (format!("{}garbage\n{}", line(1), line(2)), "journal.jsonl:2"),
        (format!("{}{}\n", line(1), &line(2)[..30]), "journal.jsonl:2"),
        (format!("\n{}\u{0}\u{ff}\n{}", line(1), line(2)), "journal.jsonl:3"),
    ] {
        let (_d, path) = journal(text.as_bytes());
        for e in [Journal::read(&path).unwrap_err(), Journal::heal(&path).unwrap_err()] {
            let e = e.to_string();
            assert!(e.contains(at) && e.contains("delete this line"), "{e}");
        }
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            text,
            "an error changes nothing"
        );
    }
}

#[test]
fn a_candidate_journaled_twice_is_refused_naming_both_lines() {
    let (_d, path) = journal([line(4), line(5), line(4)].concat().as_bytes());
    let e = Journal::read(&path).unwrap_err().to_string();
    assert!(
        e.contains("journal.jsonl:3") && e.contains("lines 1 and 3") && e.contains("candidate 4"),
        "{e}"
    );
}

#[test]
fn re_flights_of_a_candidate_are_distinct_and_the_same_flight_twice_is_refused() {
    let again = |attempt| FlightRecord {
        attempt,
        trajectory: format!("flights/candidate_4_{}.csv", attempt + 1).into(),
        ..record(4)
    };
    let text = |r: &FlightRecord| serde_json::to_string(r).unwrap() + "\n";
    assert!(!line(4).contains("attempt"), "a first flight is written as before");
    assert!(text(&again(1)).contains("\"attempt\":1"));
    let (_d, path) = journal([line(4), text(&again(1)), line(5), text(&again(2))].concat().as_bytes());
    let back = Journal::read(&path).unwrap();
    assert_eq!(
        back.iter().map(|r| (r.candidate.0, r.attempt)).collect::<Vec<_>>(),
        [(4, 0), (4, 1), (5, 0), (4, 2)]
    );
    let (_d, path) = journal([line(4), text(&again(1)), text(&again(1))].concat().as_bytes());
    let e = Journal::read(&path).unwrap_err().to_string();
    assert!(
        e.contains("candidate 4 (flight 2) is journaled twice (lines 2 and 3)"),
        "{e}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn any_bytes_read_or_fail_clearly(
        bytes in prop_oneof![
            proptest::collection::vec(any::<u8>(), 0..300),
            (0usize..3, 0usize..400, any::<u8>()).prop_map(|(n, cut, b)| {
                let mut v = (0..n as u64).map(line).collect::<String>().into_bytes();
                v.push(b);
                v.extend_from_slice(&line(9).into_bytes()[..cut.min(200)]);
                v
            }),
        ]
    ) {
        let (_d, path) = journal(&bytes);
        match Journal::read(&path) {
            Ok(records) => prop_assert!(records.len() <= bytes.iter().filter(|b| **b == b'\n').count() + 1),
            Err(e) => prop_assert!(e.to_string().contains("journal.jsonl:"), "{}", e),
        }
        match Journal::heal(&path) {
            Ok(_) => prop_assert!(Journal::read(&path).is_ok() && std::fs::read(&path).unwrap().last().is_none_or(|b| *b == b'\n')),
            Err(e) => prop_assert!(e.to_string().contains("journal.jsonl:"), "{}", e),
        }
    }
}

fn interrupted_line(candidate: u64) -> String {
    let mut r = record(candidate);
    r.flown.status = FlightStatus::Interrupted;
    serde_json::to_string(&r).unwrap() + "\n"
}

#[test]
fn interrupted_flights_are_not_charged_and_are_pending_until_flown() {
    let (_d, path) = journal(
        [line(1), interrupted_line(2), interrupted_line(3), interrupted_line(2)]
            .concat()
            .as_bytes(),
    );
    let charged: Vec<u64> = Journal::read(&path).unwrap().iter().map(|r| r.candidate.0).collect();
    assert_eq!(charged, vec![1], "only the finished flight counts against the budget");
    assert_eq!(Journal::read_all(&path).unwrap().len(), 4);
    let pending: Vec<u64> = Journal::interrupted(&path)
        .unwrap()
        .iter()
        .map(|r| r.candidate.0)
        .collect();
    assert_eq!(pending, vec![3, 2], "one per candidate, the last interruption's place");
    // Flying candidate 2 again settles it, and is not a duplicate.
    let mut j = Journal::open(&path).unwrap();
    j.append(&record(2)).unwrap();
    let pending: Vec<u64> = Journal::interrupted(&path)
        .unwrap()
        .iter()
        .map(|r| r.candidate.0)
        .collect();
    assert_eq!(pending, vec![3]);
    assert_eq!(Journal::read(&path).unwrap().len(), 2);
}

#[test]
fn collision_prevention_verdicts_are_kept_and_old_lines_without_them_still_load() {
    // A line as journals were written before the Collision Prevention verdict was kept.
    let old = r#"{"candidate":2,"obstacles":[],"predicted_min_distance":1.8,"predicted_flight_time_s":50.0,"min_distance":1.2,"min_distance_raw":1.2,"status":"landed","flight_time_s":40.0,"vehicle":"mock#0","trajectory":"flights/candidate_2.csv","wall_s":1.1}"#;
    let mut cp = record(3);
    (cp.flown.closest_centre_m, cp.flown.inside_cp_dist) = (Some(1.35), Some(true));
    let line = serde_json::to_string(&cp).unwrap();
    assert!(
        line.contains(r#""closest_centre_m":1.35,"inside_cp_dist":true"#),
        "{line}"
    );
    assert!(
        !serde_json::to_string(&record(4)).unwrap().contains("inside_cp_dist"),
        "left out when absent"
    );
    let (_d, path) = journal(format!("{old}\n{line}\n").as_bytes());
    let read = Journal::read(&path).unwrap();
    let cp_of = |r: &FlightRecord| (r.flown.closest_centre_m, r.flown.inside_cp_dist);
    assert_eq!(cp_of(&read[0]), (None, None));
    assert_eq!(cp_of(&read[1]), (Some(1.35), Some(true)));
    let mut bad = cp;
    bad.flown.closest_centre_m = Some(-0.5);
    let e = crate::campaign::store::trust::check_record(&bad, 100.0).unwrap_err();
    assert!(e.contains("closest_centre_m") && e.contains("outside"), "{e}");
}

#[test]
fn a_record_with_every_field_is_written_as_the_journal_line_always_was() {
    let mut r = record(4);
    r.attempt = 2;
    r.obstacles.clear();
    r.prediction = Some(LfsPrediction {
        p_fail: Some(0.25),
        raw_min_distance: Some(0.75),
        // Not journaled: the line has no place for them.
        expected_points: Some(3.0),
        ..LfsPrediction::point(CandidateId(4), 0.5, 40.0, "landed".into())
    });
    r.flown.status = FlightStatus::COLLISION;
    (r.flown.warnings, r.flown.reason) = (vec!["w".into()], Some("r".into()));
    (r.flown.closest_centre_m, r.flown.inside_cp_dist) = (Some(1.5), Some(true));
    let line = r#"{"candidate":4,"attempt":2,"obstacles":[],"predicted_min_distance":0.5,"predicted_flight_time_s":40.0,"predicted_p_fail":0.25,"predicted_raw_min_distance":0.75,"min_distance":1.0,"min_distance_raw":0.9,"status":"collision","flight_time_s":41.0,"warnings":["w"],"reason":"r","vehicle":"mock","trajectory":"flights/candidate_1.csv","wall_s":0.3,"closest_centre_m":1.5,"inside_cp_dist":true}"#;
    assert_eq!(serde_json::to_string(&r).unwrap(), line);
    let back: FlightRecord = serde_json::from_str(line).unwrap();
    assert_eq!(serde_json::to_string(&back).unwrap(), line);
    let p = back.prediction.clone().expect("predicted");
    assert_eq!((p.status.as_str(), p.expected_points), ("", None));
    assert_eq!(back, Journal::read_back(&r));
}

#[test]
fn journals_written_before_read_and_write_back_byte_for_byte() {
    let recorded = [
        "tests/data/pinned/mission2-seed2-budget6.jsonl",
        "tests/data/pinned/static-no-learn-seed3-budget4.jsonl",
        "tests/data/pinned/static-no-screen-seed3-budget4.jsonl",
        "tests/data/static-killed/journal.jsonl",
    ];
    for path in recorded {
        let text = std::fs::read_to_string(path).unwrap();
        for line in text.lines().filter(|l| !l.trim().is_empty()) {
            let r: FlightRecord = serde_json::from_str(line).unwrap();
            assert_eq!(serde_json::to_string(&r).unwrap(), line, "{path}");
        }
    }
}
