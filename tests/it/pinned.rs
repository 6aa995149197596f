//! The main job's behaviour is pinned: the seed's journal, flight for flight and bit for bit, as recorded
//! in `tests/data/pinned/`. A change that moves any draw, prediction, ranking or flight fails here; when the
//! change is meant, record the journal again (the command is in the failure message) and say why.

use serde_json::Value;

const PINNED: &str = "tests/data/pinned/mission2-seed2-budget6.jsonl";

/// A journal's records without what depends on the machine (vehicle name, wall time), by candidate.
fn normalised(text: &str) -> Vec<Value> {
    let mut records: Vec<Value> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str::<Value>(l).expect("journal record"))
        .map(|mut r| {
            if let Some(m) = r.as_object_mut() {
                m.remove("vehicle");
                m.remove("wall_s");
            }
            r
        })
        .collect();
    // Re-flights of a test (confirmation) follow its first flight: by candidate, then attempt.
    records.sort_by_key(|r| (r["candidate"].as_u64(), r["attempt"].as_u64().unwrap_or(0)));
    records
}

#[test]
fn the_main_job_flies_the_pinned_journal() {
    let out = tempfile::tempdir().expect("temp dir");
    let out_dir = out.path().to_string_lossy().into_owned();
    let (code, stdout, stderr) = super::prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "6",
        "--seed",
        "2",
        "--out",
        &out_dir,
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(
        stdout.starts_with(
            "2 failing tests (2 distinct at IoU 0.5) of 6 flights (35 candidates screened), failure score 1.82"
        ),
        "{stdout}"
    );
    let folder = std::fs::read_dir(out.path())
        .expect("output")
        .flatten()
        .map(|e| e.path())
        .find(|p| p.is_dir())
        .expect("the campaign folder");
    let flown = normalised(&std::fs::read_to_string(folder.join("journal.jsonl")).expect("journal"));
    let pinned = normalised(&std::fs::read_to_string(super::repo().join(PINNED)).expect("pinned journal"));
    assert_eq!(flown.len(), pinned.len());
    for (f, p) in flown.iter().zip(&pinned) {
        assert_eq!(
            f, p,
            "the journal moved from {PINNED}; if that is meant, record it again with \
             `prgenuav generate missions/mission2.yaml 6 --seed 2` and normalise the journal as this test does"
        );
    }
}
