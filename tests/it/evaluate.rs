//! The 2026 evaluation: `score` from flights on disk, `evaluate` flying a suite on the mock (resumable, one
//! writer), and their bad input.

use std::path::Path;

use prgenuav::model::{Obstacle, Spelling};
use serde_json::Value;

use super::anywhere::{assert_absolute_files, copy_missions, prgenuav_in};
use super::{case, prgenuav, valid_pair};

/// A flight from home north along `x = east_m`, 10 m up, `secs` long, as an Aerialist CSV.
fn csv_flight(east_m: f64, secs: f64) -> String {
    let mut s = String::from("timestamp,x,y,z,r\n0,0,0,0,\n");
    for i in 1..=100 {
        let t = secs * f64::from(i) / 100.0;
        s += &format!("{},{east_m},{},10,\n", (t * 1e6) as i64, 50.0 * f64::from(i) / 100.0);
    }
    s
}

fn write_test(dir: &Path, i: usize, mission: u32, obstacles: Vec<Obstacle>) {
    case(mission)
        .with_obstacles(obstacles)
        .save(&dir.join(format!("test_{i}.yaml")), Spelling::Old)
        .unwrap();
}

fn json(out: &str) -> Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

#[test]
fn score_gives_the_2026_evaluation_beside_the_2025_figures() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let near = Obstacle::new(2.0, 2.0, 20.0, 4.0, 25.0, 0.0);
    // Test 0 and its copy 1 fly the same path 0.5 m from the box; test 2 flies far from another box.
    for (i, east) in [(0, 2.5), (1, 2.5)] {
        write_test(d, i, 2, vec![near]);
        for k in 0..2 {
            std::fs::write(d.join(format!("test_{i}-{k}.csv")), csv_flight(east, 60.0)).unwrap();
        }
    }
    write_test(d, 2, 2, vec![Obstacle::new(2.0, 2.0, 20.0, -20.0, 25.0, 0.0)]);
    std::fs::write(d.join("test_2.csv"), csv_flight(-40.0, 30.0)).unwrap();
    let avg = d.join("averages");
    let (code, out, err) = prgenuav(&[
        "score",
        d.to_str().unwrap(),
        "--json",
        "--averages",
        avg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let j = json(&out);
    let e = &j["evaluation_2026"];
    assert_eq!(
        j["failing"], 1,
        "the 2025 figures stay at the top level (test 1 duplicates test 0)"
    );
    assert_eq!(e["tests"][0]["runs"].as_array().unwrap().len(), 2);
    // 0.5 m - 0.125 m (2026 buffer) = 0.375 m: 2 points each run.
    assert_eq!(e["tests"][0]["runs"][0]["points"], 2);
    assert_eq!(e["tests"][0]["mean_points"], 2.0);
    assert!(avg.join("test_0.csv").is_file());
    assert_eq!(
        e["tests"][0]["average_trajectory"],
        avg.join("test_0.csv").to_str().unwrap()
    );
    assert_eq!(e["pairs"].as_array().unwrap().len(), 3);
    assert_eq!(e["pairs"][0]["dtw"], 0.0);
    assert_eq!(e["tests"][1]["similar_to"], 0);
    assert_eq!(e["similar_tests"], 1);
    let sim_pen = e["sim_pen"].as_f64().unwrap();
    assert!((sim_pen - 2.0 / 3.0).abs() < 1e-12);
    let total = e["total_score"].as_f64().unwrap();
    assert!((e["final_score"].as_f64().unwrap() - total * sim_pen).abs() < 1e-9);
    // The text report names the 2026 figures; a threshold of 0 finds no similar pair.
    let (code, out, _) = prgenuav(&["score", d.to_str().unwrap(), "--similar-below", "0"]);
    assert_eq!(code, 0);
    assert!(out.contains("sim_pen 1.000") && out.contains("final score"), "{out}");
}

#[test]
fn score_and_evaluate_refuse_bad_input_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let empty = tempfile::tempdir().unwrap();
    let (code, _, err) = prgenuav(&["evaluate", empty.path().to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("no test"), "{err}");
    write_test(d, 0, 2, valid_pair());
    for runs in ["0", "21"] {
        let (code, _, err) = prgenuav(&["evaluate", d.to_str().unwrap(), "--runs", runs]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("--runs") && err.contains("<= 20"), "{err}");
    }
    let (code, _, err) = prgenuav(&["score", d.to_str().unwrap(), "--similar-below=-1"]);
    assert_eq!(code, 2);
    assert!(err.contains("--similar-below"), "{err}");
    // A test of another mission in the same folder.
    write_test(d, 1, 3, vec![Obstacle::new(2.0, 2.0, 20.0, -20.0, 25.0, 0.0)]);
    let (code, _, err) = prgenuav(&["evaluate", d.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("test_1.yaml") && err.contains("another mission"), "{err}");
    assert!(!d.join("evaluation").exists(), "nothing written for a refused folder");
}

/// A complete evaluation of `tests` tests with `runs` flights each, every file it names on disk.
fn assert_complete(j: &Value, tests: usize, runs: usize) {
    assert_eq!(j["missing_flights"], 0);
    let all = j["tests"].as_array().unwrap();
    assert_eq!(all.len(), tests);
    for t in all {
        let flown = t["runs"].as_array().unwrap();
        assert_eq!(flown.len(), runs);
        for r in flown {
            assert!(Path::new(r["trajectory"].as_str().unwrap()).is_file());
            assert!(r["min_distance"].as_f64().is_some() && r["points"].as_u64().is_some());
        }
        assert!(Path::new(t["average_trajectory"].as_str().unwrap()).is_file());
        assert!(t["mean_points"].as_f64().is_some() && t["score"].as_f64().is_some());
    }
    assert_eq!(j["pairs"].as_array().unwrap().len(), tests * (tests - 1) / 2);
    assert!(j["pairs"][0]["dtw"].as_f64().unwrap() > 0.0);
    assert!(j["sim_pen"].as_f64().is_some() && j["final_score"].as_f64().is_some());
}

#[test]
fn evaluate_flies_each_test_n_times_on_the_mock_and_resumes_without_flying_again() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_test(d, 0, 2, valid_pair());
    write_test(d, 1, 2, vec![Obstacle::new(10.0, 2.0, 20.0, -20.0, 20.0, 0.0)]);
    write_test(d, 2, 2, vec![Obstacle::new(4.0, 4.0, 20.0, 20.0, 30.0, 0.0)]);
    let args = [
        "evaluate",
        d.to_str().unwrap(),
        "--runs",
        "2",
        "--top",
        "2",
        "--json",
        "--jobs",
        "2",
    ];
    let (code, out, err) = prgenuav(&args);
    assert_eq!(code, 0, "{err}");
    let j = json(&out);
    assert_complete(&j, 2, 2);
    let folder = d.join("evaluation");
    for f in ["report.json", "report.md", "journal.jsonl"] {
        assert!(folder.join(f).is_file(), "{f}");
    }
    let journal = std::fs::read_to_string(folder.join("journal.jsonl")).unwrap();
    assert_eq!(journal.lines().count(), 4);
    // Again: every flight is journaled, nothing flies, the same figures come out.
    let (code, again, err) = prgenuav(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read_to_string(folder.join("journal.jsonl")).unwrap(), journal);
    assert_eq!(json(&again)["final_score"], j["final_score"]);
    // More runs fly only the missing ones.
    let more = [
        "evaluate",
        d.to_str().unwrap(),
        "--runs",
        "3",
        "--top",
        "2",
        "--json",
        "--jobs",
        "1",
    ];
    let (code, out, err) = prgenuav(&more);
    assert_eq!(code, 0, "{err}");
    assert_eq!(json(&out)["tests"][0]["runs"].as_array().unwrap().len(), 3);
    let journal = std::fs::read_to_string(folder.join("journal.jsonl")).unwrap();
    let vehicles: Vec<Value> = journal.lines().map(|l| json(l)["vehicle"].clone()).collect();
    assert_eq!(vehicles.len(), 6);
    // --jobs sets the embedded mocks as in `generate`: one vehicle flew both new runs.
    assert!(vehicles[4..].iter().all(|v| v == "mock#0"), "{vehicles:?}");
}

/// A suite named by a relative path: report.json names every file by an absolute path, so it can be read
/// from any directory.
#[test]
fn evaluate_names_its_files_by_absolute_paths() {
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("suite");
    std::fs::create_dir(&suite).unwrap();
    // The tests name their mission files relatively: from the working folder, where they are copied.
    copy_missions(dir.path());
    write_test(&suite, 0, 2, valid_pair());
    write_test(&suite, 1, 2, vec![Obstacle::new(10.0, 2.0, 20.0, -20.0, 20.0, 0.0)]);
    let args = ["evaluate", "suite", "--runs", "1", "--quiet", "--jobs", "2"];
    let (code, _, err) = prgenuav_in(dir.path(), &args);
    assert_eq!(code, 0, "{err}");
    let report = std::fs::read_to_string(suite.join("evaluation/report.json")).unwrap();
    let j = json(&report);
    let t = &j["tests"][0];
    assert_absolute_files(&[
        &t["test"],
        &t["runs"][0]["trajectory"],
        &t["average_trajectory"],
        &j["pairs"][0]["a"],
        &j["pairs"][0]["b"],
    ]);
}
