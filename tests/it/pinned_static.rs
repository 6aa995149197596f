//! The campaigns that do not learn are pinned too: a `--no-learn` and a `--no-screen` campaign fly the
//! candidates recorded in `tests/data/pinned/`, in the recorded order (one vehicle, so the journal's order is
//! the order they took off in), with the recorded predictions. And a folder the one-pass campaign left when it
//! was killed mid-way (`tests/data/static-killed/`) resumes to the flights the uninterrupted campaign makes.
//!
//! The flights are in `--mode mission`, whose mock runs free (no avoidance answer to hold its clock for), so
//! a flight's times move a little from run to run; what is pinned is what the campaign decides.

use std::path::Path;

use serde_json::Value;

use super::{prgenuav, repo};

const NO_LEARN: &str = "tests/data/pinned/static-no-learn-seed3-budget4.jsonl";
const NO_SCREEN: &str = "tests/data/pinned/static-no-screen-seed3-budget4.jsonl";
const KILLED: &str = "tests/data/static-killed";

/// What a campaign decides about each flight: which test, which of its flights, what it predicted, how the
/// flight ended (a collision here, whatever the free-running clock does).
const DECIDED: [&str; 8] = [
    "candidate",
    "attempt",
    "obstacles",
    "predicted_min_distance",
    "predicted_flight_time_s",
    "predicted_p_fail",
    "predicted_raw_min_distance",
    "status",
];

/// The decided fields of a journal's records, in its order.
fn decided(text: &str) -> Vec<Value> {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str::<Value>(l).expect("journal record"))
        .map(|r| {
            let kept = DECIDED.iter().filter_map(|k| Some((k.to_string(), r.get(*k)?.clone())));
            Value::Object(kept.collect())
        })
        .collect()
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The one folder `generate` made under `out`.
fn campaign_folder(out: &Path) -> std::path::PathBuf {
    std::fs::read_dir(out)
        .expect("output")
        .flatten()
        .map(|e| e.path())
        .find(|p| p.is_dir())
        .expect("the campaign folder")
}

fn flies_the_pinned_journal(switch: &str, pinned: &str) {
    let out = tempfile::tempdir().expect("temp dir");
    let out_dir = out.path().to_string_lossy().into_owned();
    let args = [
        "generate",
        "missions/mission2.yaml",
        "4",
        "--seed",
        "3",
        "--candidates",
        "8",
        switch,
        "--mode",
        "mission",
        "--mock-vehicles",
        "1",
        "--out",
        &out_dir,
        "--quiet",
    ];
    let (code, stdout, stderr) = prgenuav(&args);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let flown = decided(&read(&campaign_folder(out.path()).join("journal.jsonl")));
    let pinned_flights = decided(&read(&repo().join(pinned)));
    assert_eq!(
        flown,
        pinned_flights,
        "the journal moved from {pinned}; if that is meant, record it again with `prgenuav generate {}` and say why",
        args[1..args.len() - 3].join(" ")
    );
}

#[test]
fn a_campaign_without_learning_flies_the_pinned_candidates_in_order() {
    flies_the_pinned_journal("--no-learn", NO_LEARN);
}

#[test]
fn a_campaign_without_screening_flies_the_pinned_candidates_in_draw_order() {
    flies_the_pinned_journal("--no-screen", NO_SCREEN);
}

/// Copies the fixture's files (one level of folders) into `to`, with the case at this checkout's path.
fn copy_killed_folder(to: &Path) {
    let from = repo().join(KILLED);
    let case = repo().join("missions/mission2.yaml");
    for entry in walk(&from) {
        let rel = entry.strip_prefix(&from).expect("inside the fixture");
        let dest = to.join(rel);
        std::fs::create_dir_all(dest.parent().expect("a parent")).expect("create");
        let name = rel.to_string_lossy();
        if name == "campaign.json" || name == "campaign.first.json" {
            let mut cfg: Value = serde_json::from_str(&read(&entry)).expect("settings");
            cfg["case"] = Value::String(case.to_string_lossy().into_owned());
            std::fs::write(&dest, serde_json::to_string_pretty(&cfg).expect("json")).expect("write");
        } else {
            std::fs::copy(&entry, &dest).expect("copy");
        }
    }
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for e in std::fs::read_dir(dir).expect("fixture").flatten() {
        let p = e.path();
        if p.is_dir() {
            files.extend(walk(&p));
        } else {
            files.push(p);
        }
    }
    files
}

#[test]
fn a_folder_the_one_pass_campaign_left_when_killed_resumes_to_the_uninterrupted_flights() {
    let dir = tempfile::tempdir().expect("temp dir");
    copy_killed_folder(dir.path());
    let before = read(&dir.path().join("journal.jsonl"));
    let (code, stdout, stderr) = prgenuav(&["generate", "--resume", dir.path().to_str().expect("utf-8"), "--quiet"]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let after = read(&dir.path().join("journal.jsonl"));
    assert!(
        after.starts_with(&before),
        "the journaled flights are kept as they were"
    );
    let mut resumed = decided(&after);
    let mut uninterrupted = decided(&read(&repo().join(NO_LEARN)));
    // Two vehicles land in either order; what is flown is what the uninterrupted campaign flies.
    let key = |r: &Value| (r["candidate"].as_u64(), r["attempt"].as_u64().unwrap_or(0));
    resumed.sort_by_key(key);
    uninterrupted.sort_by_key(key);
    assert_eq!(resumed, uninterrupted);
    assert!(stdout.contains("of 4 flights"), "{stdout}");
}

/// A killed learning campaign whose `campaign.json` the previous, flat format holds (written by prgenuav
/// before the settings were sectioned, with three of its six flights journaled) resumes to what the
/// uninterrupted campaign made: the embedded mock flies in lockstep, so the result repeats to the line.
#[test]
fn a_learning_campaign_of_the_previous_format_resumes_to_its_uninterrupted_result() {
    let dir = tempfile::tempdir().expect("temp dir");
    let folder = dir.path().join("killed");
    copy_tree(&repo().join("tests/data/learning-killed"), &folder);
    let f = folder.to_string_lossy().into_owned();
    let (code, stdout, stderr) = prgenuav(&["generate", "--resume", &f, "--quiet"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(
        stdout.lines().next(),
        Some(
            "2 failing tests (2 distinct at IoU 0.5) of 6 flights (20 candidates screened), failure score 2.18, \
             diversity 0.956"
        ),
        "{stdout}"
    );
    let (code, _, stderr) = prgenuav(&["generate", "--resume", &f, "--seed", "2"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--seed 2 conflicts with seed 1 stored in"), "{stderr}");
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create");
    for e in std::fs::read_dir(from).expect("read").flatten() {
        let target = to.join(e.file_name());
        if e.path().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).expect("copy");
        }
    }
}
