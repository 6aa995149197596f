//! A campaign folder as a hostile or hurried user treats it: counts out of range, two writers, Ctrl-C in the
//! middle of flights, outputs that cannot be written. Each case runs the binary as a user would.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{prgenuav, repo};

fn binary() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_prgenuav"));
    c.current_dir(repo());
    c
}

/// A mock campaign of `budget` flights on two vehicles, slowed so that flights are in the air for seconds.
fn campaign_args<'a>(budget: &'a str, seed: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "generate",
        "missions/mission2.yaml",
        budget,
        "--seed",
        seed,
        "--candidates",
        "8",
        "--no-learn",
        "--mode",
        "mission",
        "--mock-speed",
        "4",
        "--mock-vehicles",
        "2",
        "--out",
        out,
    ]
}

fn records(folder: &Path) -> Vec<Value> {
    std::fs::read_to_string(folder.join("journal.jsonl"))
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn folder_of(stdout: &str) -> PathBuf {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("output folder:"))
        .unwrap_or_default();
    PathBuf::from(line.trim_start_matches("output folder:").trim())
}

/// Waits (bounded) until `child` has exited; returns its code and how long that took.
fn wait_bounded(child: &mut Child, limit: Duration) -> (Option<i32>, Duration) {
    let t0 = Instant::now();
    while t0.elapsed() < limit {
        if let Some(status) = child.try_wait().unwrap() {
            return (status.code(), t0.elapsed());
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    panic!("still running {limit:?} after the signal");
}

fn interrupt(child: &Child) {
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
}

/// Starts a campaign and returns it once its flights have started (its stderr says so), with its folder.
fn start_flying(out: &Path, budget: &str) -> (Child, PathBuf) {
    let mut child = binary()
        .args(campaign_args(budget, "0", out.to_str().unwrap()))
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let mut lines = BufReader::new(stderr).lines();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(120) {
        match lines.next() {
            Some(Ok(line)) if line.starts_with("[fly]") => break,
            Some(_) => {}
            None => panic!("generate ended before flying"),
        }
    }
    // Drain the rest so the child never blocks on a full pipe.
    std::thread::spawn(move || lines.for_each(drop));
    let folder = std::fs::read_dir(out).unwrap().next().unwrap().unwrap().path();
    (child, folder)
}

#[test]
fn counts_out_of_range_are_refused_before_anything_is_drawn() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    for (args, needle) in [
        (
            vec!["generate", "missions/mission2.yaml", "1000000000", "--out", o],
            "1 to 10000 flights",
        ),
        (
            vec!["generate", "missions/mission2.yaml", "0", "--out", o],
            "1 to 10000 flights",
        ),
        (
            vec![
                "generate",
                "missions/mission2.yaml",
                "5",
                "--candidates",
                "1000000",
                "--out",
                o,
            ],
            "1 to 100000",
        ),
        (
            vec!["sample", "missions/mission2.yaml", "--count", "1000000000", "--out", o],
            "1 to 5000 tests",
        ),
    ] {
        let t0 = Instant::now();
        let (code, _, err) = prgenuav(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "{args:?} took {:?}",
            t0.elapsed()
        );
    }
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0, "nothing written");
}

#[test]
fn outputs_and_vehicle_addresses_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    // No vehicle listens: without the early check `fly` would wait for one before failing on the plot.
    for (args, needle) in [
        (vec!["fly", "missions/mission2.yaml", "--plot", d], "--plot"),
        (vec!["simulate", "missions/mission2.yaml", "--plot", d], "--plot"),
        (
            vec!["render", "missions/mission2.yaml", "--pose", "0,0,5,0", "--out-file", d],
            "--out-file",
        ),
        (
            vec![
                "generate",
                "missions/mission2.yaml",
                "3",
                "--connect",
                "udpin:0.0.0.0:99999",
                "--out",
                d,
            ],
            "--connect",
        ),
    ] {
        let t0 = Instant::now();
        let (code, _, err) = prgenuav(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "{args:?} took {:?}",
            t0.elapsed()
        );
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no output and no campaign folder"
    );
}

#[test]
fn ctrl_c_charges_nothing_for_flights_in_the_air_and_resume_flies_them_first() {
    let out = tempfile::tempdir().unwrap();
    let (mut child, folder) = start_flying(out.path(), "4");
    std::thread::sleep(Duration::from_millis(500));
    interrupt(&child);
    let (code, took) = wait_bounded(&mut child, Duration::from_secs(25));
    assert_eq!(code, Some(1), "an interrupted campaign exits 1 (took {took:?})");
    let first = records(&folder);
    let interrupted: Vec<u64> = (first.iter())
        .filter(|r| r["status"] == "interrupted")
        .map(|r| r["candidate"].as_u64().unwrap())
        .collect();
    assert!(!interrupted.is_empty(), "two vehicles were in the air: {first:?}");
    for r in first.iter().filter(|r| r["status"] == "interrupted") {
        let kept = folder.join(r["trajectory"].as_str().unwrap());
        assert!(
            kept.to_string_lossy().ends_with(".interrupted.csv") && kept.exists(),
            "{kept:?}"
        );
    }

    let (code, stdout, stderr) = prgenuav(&["generate", "--resume", folder.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("interrupted last time (candidates"), "{stderr}");
    let all = records(&folder);
    let charged: Vec<&Value> = all.iter().filter(|r| r["status"] != "interrupted").collect();
    assert_eq!(
        charged.len(),
        4,
        "the budget is spent on finished flights only: {all:?}"
    );
    let after: Vec<u64> = all[first.len()..first.len() + interrupted.len()]
        .iter()
        .map(|r| r["candidate"].as_u64().unwrap())
        .collect();
    let (mut a, mut b) = (after.clone(), interrupted.clone());
    a.sort();
    b.sort();
    assert_eq!(a, b, "the interrupted flights are the first flown on resume");
    assert!(stdout.contains("of 4 flights"), "{stdout}");
}

#[test]
fn a_second_writer_is_refused_naming_the_holder_and_same_second_campaigns_get_their_own_folders() {
    let out = tempfile::tempdir().unwrap();
    let (mut child, folder) = start_flying(out.path(), "6");
    let (code, _, stderr) = prgenuav(&["generate", "--resume", folder.to_str().unwrap()]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains(&format!("pid {}", child.id())) && stderr.contains("one writer"),
        "{stderr}"
    );
    interrupt(&child);
    wait_bounded(&mut child, Duration::from_secs(25));

    // Two campaigns started together into one --out: one folder each, each journal of its own seed.
    let shared = tempfile::tempdir().unwrap();
    let o = shared.path().to_str().unwrap();
    let spawn = |seed: &str| {
        binary()
            .args(campaign_args("2", seed, o))
            .arg("--quiet")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("1"), spawn("2"));
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert!(a.status.success() && b.status.success());
    let (fa, fb) = (
        folder_of(&String::from_utf8_lossy(&a.stdout)),
        folder_of(&String::from_utf8_lossy(&b.stdout)),
    );
    assert_ne!(fa, fb);
    assert_eq!(records(&fa).len(), 2);
    assert_eq!(records(&fb).len(), 2);
}
