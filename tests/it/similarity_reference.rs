//! The 2026 evaluation's averages and DTW distances against the reference libraries (tslearn, ruptures,
//! similaritymeasures) on recorded flights: the competition cases flown both by the competition's stack
//! (`hfs-flights`, digitised) and by PX4 v1.14 (`px4-flights`), two flights per test.
//!
//! Interpreter: `$PYTHON` or `python3`. Without the libraries the test fails when `CI=true`, and prints
//! why it skips otherwise.

use std::path::PathBuf;
use std::process::Command;

use prgenuav::judge::similarity::{average, path_distance, prepare};
use prgenuav::lfs::eval::fidelity::spearman;
use prgenuav::model::{Sample, Trajectory, load_flight};
use serde_json::Value;

use super::repo;

/// Tests whose flights are at most this many samples: keeps the reference's pure-Python DTW quick.
const MAX_SAMPLES: usize = 330;

fn python() -> String {
    std::env::var("PYTHON").unwrap_or_else(|_| "python3".into())
}

fn libraries_available() -> bool {
    let ok = Command::new(python())
        .args(["-c", "import tslearn, ruptures, similaritymeasures"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        let ci = std::env::var("CI").map(|v| v == "true").unwrap_or(false);
        let install = "pip install tslearn==0.10.0 ruptures==1.1.10 similaritymeasures==1.5.0";
        assert!(!ci, "the reference libraries are missing for {}: {install}", python());
        eprintln!(
            "SKIP: tslearn, ruptures or similaritymeasures not importable by {} ({install})",
            python()
        );
    }
    ok
}

/// The recorded case's digitised competition flight, as a trajectory (`None` without one).
fn hfs_flight(json: &Value) -> Option<Trajectory> {
    let rows = json["trajectory"].as_array()?;
    let samples: Option<Vec<Sample>> = rows
        .iter()
        .map(|r| {
            let v = |i: usize| r.get(i).and_then(Value::as_f64);
            Some(Sample {
                t_s: v(0)?,
                x: v(1)?,
                y: v(2)?,
                z: v(3)?,
                r: Some(0.0),
            })
        })
        .collect();
    samples.filter(|s| !s.is_empty()).map(Trajectory::new)
}

/// The tests: (name, flight files), the digitised flight written as a CSV into `dir`.
fn recorded_tests(dir: &std::path::Path) -> Vec<(String, Vec<PathBuf>)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join("tests/data/hfs-flights"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    let mut out = Vec::new();
    for f in files {
        let json: Value = serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
        let id = json["id"].as_str().unwrap().to_string();
        let px4 = repo().join(format!("tests/data/px4-flights/traj/{id}.csv"));
        let Some(hfs) = hfs_flight(&json) else { continue };
        if !px4.is_file() || hfs.samples.len() > MAX_SAMPLES {
            continue;
        }
        if load_flight(&px4).unwrap().samples.len() > MAX_SAMPLES {
            continue;
        }
        let hfs_csv = dir.join(format!("{id}-hfs.csv"));
        std::fs::write(&hfs_csv, hfs.to_csv()).unwrap();
        out.push((id, vec![px4, hfs_csv]));
    }
    out
}

/// The reference's pairwise distances `(i, j, dtw)`.
fn reference(dir: &std::path::Path, tests: &[(String, Vec<PathBuf>)]) -> Vec<(usize, usize, f64)> {
    let manifest = serde_json::json!({
        "tests": tests.iter().map(|(name, flights)| serde_json::json!({"name": name, "flights": flights})).collect::<Vec<_>>()
    });
    let path = dir.join("manifest.json");
    std::fs::write(&path, manifest.to_string()).unwrap();
    let script = repo().join("tests/py/similarity_reference.py");
    let out = Command::new(python())
        .arg(&script)
        .arg(&path)
        .output()
        .expect("run python");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    v["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p[0].as_u64().unwrap() as usize,
                p[1].as_u64().unwrap() as usize,
                p[2].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn averages_and_dtw_agree_with_the_reference_libraries() {
    if !libraries_available() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let tests = recorded_tests(dir.path());
    assert!(tests.len() >= 12, "only {} recorded tests", tests.len());
    let averages: Vec<Trajectory> = tests
        .iter()
        .map(|(_, files)| {
            let flights: Vec<Trajectory> = files.iter().map(|f| prepare(&load_flight(f).unwrap())).collect();
            average(&flights).unwrap()
        })
        .collect();
    let theirs = reference(dir.path(), &tests);
    assert_eq!(theirs.len(), tests.len() * (tests.len() - 1) / 2);
    let ours: Vec<f64> = theirs
        .iter()
        .map(|&(i, j, _)| path_distance(&averages[i], &averages[j]).unwrap())
        .collect();
    let refs: Vec<f64> = theirs.iter().map(|p| p.2).collect();
    let rho = spearman(&ours, &refs).unwrap();
    let mut rel: Vec<f64> = ours.iter().zip(&refs).map(|(o, r)| (o - r).abs() / r).collect();
    rel.sort_by(f64::total_cmp);
    let median = rel[rel.len() / 2];
    eprintln!(
        "{} tests, {} pairs: Spearman {rho:.4}, median relative error {:.2} %, worst {:.2} %",
        tests.len(),
        refs.len(),
        100.0 * median,
        100.0 * rel[rel.len() - 1]
    );
    assert!(rho >= 0.98, "Spearman {rho}");
    assert!(median <= 0.05, "median relative error {median}");
    // At thresholds across the range, the similar pairs are the same, except pairs within 5 % of it.
    let mut sorted = refs.clone();
    sorted.sort_by(f64::total_cmp);
    for q in [0.05, 0.1, 0.25, 0.5] {
        let threshold = sorted[(q * sorted.len() as f64) as usize];
        for (o, r) in ours.iter().zip(&refs) {
            if (r - threshold).abs() > 0.05 * r {
                assert_eq!(o < &threshold, r < &threshold, "ours {o} vs {r} at {threshold}");
            }
        }
    }
}
