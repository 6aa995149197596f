//! The campaign aims at the 2026 score on the embedded mock: report.json carries the written suite's expected
//! 2026 score, the written tests follow its ranking, and a test set aside as a near-duplicate trajectory names
//! the better written test it copies and stays on disk.

use std::time::Duration;

use serde_json::Value;

use super::campaign::{output_folder, spawn, verify_folder, wait_bounded};

fn expected_score(t: &Value) -> f64 {
    t["expected"]["score"]
        .as_f64()
        .expect("every failing test has an expected score")
}

#[test]
fn the_report_carries_the_expected_2026_score_and_the_written_order_follows_it() {
    let out = tempfile::tempdir().expect("temp dir");
    let child = spawn(&[
        "generate",
        "missions/mission2.yaml",
        "10",
        "--out",
        out.path().to_str().expect("utf-8 temp dir"),
    ]);
    let (code, stdout, stderr) = wait_bounded(child, Duration::from_secs(300));
    assert_eq!(code, 0, "{stderr}");
    let folder = output_folder(&stdout);
    let report = verify_folder(&folder);
    let tests = report["tests"].as_array().expect("tests");
    assert!(!tests.is_empty(), "the seed's 10 flights fail at least once: {stdout}");
    // Every failing test ranks by its expected score, the written ones and the others alike.
    let scores: Vec<f64> = tests.iter().map(expected_score).collect();
    assert!(scores.windows(2).all(|w| w[0] >= w[1]), "{scores:?}");
    let written: Vec<&Value> = tests.iter().filter(|t| t["confirmed"] == true).collect();
    for (i, t) in written.iter().enumerate() {
        assert_eq!(t["reported_as"], format!("test_{i}.yaml").as_str());
        assert!(
            t["expected"]["points"]["low"].as_f64().expect("low") > 0.0,
            "written without points"
        );
    }
    let e = &report["suite"]["expected_2026"];
    let total: f64 = written.iter().map(|t| expected_score(t)).sum();
    let num = |k: &str| e[k].as_f64().unwrap_or_else(|| panic!("{k} in {e}"));
    assert_eq!(e["tests"].as_u64(), Some(written.len() as u64));
    assert!((num("total_score") - total).abs() < 1e-9, "{e}");
    assert!((num("final_score") - total * num("sim_pen")).abs() < 1e-9, "{e}");
    assert!(num("final_low") <= num("final_score") && num("final_score") <= num("final_high"));
    // The expected penalty: each written test's chance of being found similar to a better one, at most 0.5.
    let chances: Vec<f64> = (written.iter())
        .map(|t| t["similar_chance"].as_f64().expect("similar_chance of a written test"))
        .collect();
    assert!(chances.iter().all(|q| (0.0..=0.5).contains(q)), "{chances:?}");
    let expected_pen = 1.0 - chances.iter().sum::<f64>() / chances.len().max(1) as f64;
    assert!((num("sim_pen") - expected_pen).abs() < 1e-9, "{e}");
    for t in tests.iter().filter(|t| !t["near_duplicate_of"].is_null()) {
        assert!(t["near_duplicate_dtw_m"].as_f64().is_some_and(|d| d >= 0.0), "{t}");
        let better = t["near_duplicate_of"].as_str().expect("a file name");
        assert!(folder.join(better).is_file(), "{better} is written");
        let kept = t["reported_as"].as_str().expect("kept on disk");
        assert!(
            kept.starts_with("unconfirmed/") && folder.join(kept).is_file(),
            "{kept}"
        );
    }
    let md = std::fs::read_to_string(folder.join("report.md")).expect("report.md");
    assert!(md.contains("expected 2026 score of the written tests"), "{md}");
}
