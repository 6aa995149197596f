//! A Collision Prevention campaign on the embedded mocks at their default settings: every flight takes off and
//! flies (the mocks hold their clocks for the pilot's sticks, so no stick gap trips the manual-control-loss
//! failsafe) and the journal and report carry each flight's Collision Prevention verdict.

use std::time::Duration;

use super::campaign::{output_folder, spawn, wait_bounded};

#[test]
fn a_mock_cp_campaign_at_default_settings_flies_and_journals_its_verdicts() {
    let out = tempfile::tempdir().unwrap();
    let child = spawn(&[
        "generate",
        "missions/mission2.yaml",
        "3",
        "--mode",
        "collision-prevention",
        "--seed",
        "0",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let (code, stdout, stderr) = wait_bounded(child, Duration::from_secs(300));
    assert_eq!(code, 0, "{stderr}");
    let folder = output_folder(&stdout);
    let journal = std::fs::read_to_string(folder.join("journal.jsonl")).unwrap();
    let records: Vec<serde_json::Value> = journal.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert!(!records.is_empty(), "nothing flown: {stderr}");
    for r in &records {
        // Collision Prevention may let the mock's vehicle into a box (`collision`), or hold it (`timeout`).
        let flew = ["landed", "collision", "timeout"].contains(&r["status"].as_str().unwrap_or(""));
        assert!(flew && r["flight_time_s"].as_f64() > Some(20.0), "{r}");
        assert!(
            !r.to_string().contains("manual control lost") && !r.to_string().contains("no sticks"),
            "{r}"
        );
        let centre = r["closest_centre_m"].as_f64().expect("closest centre journaled");
        assert_eq!(r["inside_cp_dist"].as_bool(), Some(centre < 2.0), "{r}");
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("report.json")).unwrap()).unwrap();
    let tests = report["collision_prevention"]
        .as_array()
        .expect("a CP verdict per test");
    let flights: u64 = tests.iter().map(|t| t["flights"].as_u64().unwrap()).sum();
    assert_eq!(flights as usize, records.len());
    let md = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(md.contains("## Collision Prevention"), "{md}");
}
