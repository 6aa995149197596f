//! `generate` end to end against the embedded mock autopilot: outputs valid and best first, report numbers
//! recomputable from the files, kill and resume, bad input. Every wait is bounded.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use prgenuav::judge::{Judge, judge_in_frame, test_score};
use prgenuav::model::{Arena, TestCase, Trajectory};
use prgenuav::rules::check;

use super::{prgenuav, repo};

/// Runs `prgenuav` with a wall-clock limit; kills it on overrun.
fn run_bounded(args: &[&str], limit: Duration) -> (i32, String, String) {
    let child = spawn(args);
    wait_bounded(child, limit)
}

pub fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args(args)
        .current_dir(repo())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start prgenuav")
}

pub fn wait_bounded(mut child: Child, limit: Duration) -> (i32, String, String) {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            let out = child.wait_with_output().expect("output");
            return (
                status.code().unwrap_or(-1),
                String::from_utf8_lossy(&out.stdout).into_owned(),
                String::from_utf8_lossy(&out.stderr).into_owned(),
            );
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().expect("output");
            panic!(
                "prgenuav {:?} ran over {limit:?}; stderr: {}",
                "generate",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

pub fn output_folder(stdout: &str) -> PathBuf {
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("output folder: "))
        .expect("output folder line");
    repo().join(line.trim())
}

/// Recomputes every reported number from the folder's files and compares with report.json.
pub fn verify_folder(folder: &Path) -> serde_json::Value {
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("report.json")).unwrap()).unwrap();
    let flights = report["flights"].as_array().unwrap();
    let confirmed: Vec<&serde_json::Value> = (report["tests"].as_array().unwrap().iter())
        .filter(|t| t["confirmed"] == true)
        .collect();
    let mut score_sum = 0.0;
    let mut i = 0;
    while folder.join(format!("test_{i}.yaml")).exists() {
        let name = format!("test_{i}.yaml");
        let test = TestCase::load(&folder.join(&name)).unwrap();
        assert!(check(&test, &Arena::default()).is_empty(), "test_{i} breaks a rule");
        let trajectory = Trajectory::load_csv(&folder.join(format!("test_{i}.csv"))).unwrap();
        assert!(folder.join(format!("test_{i}.svg")).is_file(), "a plot per test");
        // Flights are recorded in the test's frame and judged by the current edition.
        let verdict = judge_in_frame(&trajectory, &test.obstacles, Judge::default()).unwrap();
        assert!(verdict.min_distance < 1.5, "test_{i} is reported but did not fail");
        // Best first: the higher expected 2026 score.
        assert_eq!(confirmed[i]["reported_as"], name.as_str());
        if i > 0 {
            let score = |t: &serde_json::Value| t["expected"]["score"].as_f64().unwrap();
            assert!(
                score(confirmed[i - 1]) >= score(confirmed[i]),
                "not best first at test_{i}"
            );
        }
        // Its flights: the CSV is the closest failing one; the score is over all of them.
        let runs: Vec<&serde_json::Value> = flights.iter().filter(|f| f["reported_as"] == name.as_str()).collect();
        // A flight that recorded nothing has no distance and no points.
        let (distances, times): (Vec<f64>, Vec<f64>) = runs
            .iter()
            .filter_map(|f| Some((f["min_distance"].as_f64()?, f["flight_time_s"].as_f64()?)))
            .unzip();
        let best = distances.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(
            (best - verdict.min_distance).abs() < 1e-3,
            "test_{i}: report {best} vs file {}",
            verdict.min_distance
        );
        assert_eq!(runs.len(), confirmed[i]["flights"].as_u64().unwrap() as usize);
        let measured = runs.iter().filter(|f| f["min_distance"].is_f64());
        for (f, (d, t)) in measured.zip(distances.iter().zip(&times)) {
            let own = test_score(&[*d], &[*t], test.obstacles.len());
            assert!((f["test_score"].as_f64().unwrap() - own).abs() < 1e-9);
        }
        let recomputed = test_score(&distances, &times, test.obstacles.len());
        assert!((confirmed[i]["test_score"].as_f64().unwrap() - recomputed).abs() < 1e-9);
        score_sum += recomputed;
        i += 1;
    }
    assert_eq!(report["suite"]["failing"].as_u64().unwrap() as usize, i);
    assert_eq!(confirmed.len(), i);
    assert!((report["suite"]["failure_score"].as_f64().unwrap() - score_sum).abs() < 1e-6);
    let journal = std::fs::read_to_string(folder.join("journal.jsonl")).unwrap();
    assert_eq!(journal.lines().count(), flights.len());
    report
}

#[test]
fn campaigns_on_missions_1_to_3_report_recomputable_numbers() {
    let out = tempfile::tempdir().unwrap();
    for n in 1..=3 {
        // Plain mission mode flies into obstacle 1, so failing tests exist to check.
        let dir = out.path().join(format!("m{n}"));
        let (code, stdout, stderr) = run_bounded(
            &[
                "generate",
                &format!("missions/mission{n}.yaml"),
                "2",
                "--candidates",
                "4",
                "--mode",
                "mission",
                "--mock-speed",
                "40",
                "--seed",
                "2",
                "--out",
                dir.to_str().unwrap(),
            ],
            Duration::from_secs(120),
        );
        assert_eq!(code, 0, "mission{n}: {stderr}");
        let folder = output_folder(&stdout);
        let report = verify_folder(&folder);
        assert_eq!(report["suite"]["flown"], 2);
        assert!(
            report["suite"]["failing"].as_u64().unwrap() >= 1,
            "the baseline must collide: {report}"
        );
        // `score` agrees with the campaign's own report.
        let (code, json, err) = prgenuav(&["score", folder.to_str().unwrap(), "--json"]);
        assert_eq!(code, 0, "{err}");
        let s: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert!(
            (s["failure_score"].as_f64().unwrap() - report["suite"]["failure_score"].as_f64().unwrap()).abs() < 1e-6
        );
    }
}

#[test]
fn avoidance_campaign_runs_on_the_default_mock() {
    let out = tempfile::tempdir().unwrap();
    let (code, stdout, stderr) = run_bounded(
        &[
            "generate",
            "missions/mission2.yaml",
            "2",
            "--candidates",
            "4",
            "--out",
            out.path().to_str().unwrap(),
            "--quiet",
            // Slower than the default 20x: CI runs many flights at once on 2 cores, and the companion's plans
            // must keep pace with the vehicle's clock.
            "--mock-speed",
            "10",
        ],
        Duration::from_secs(180),
    );
    assert_eq!(code, 0, "{stderr}");
    let report = verify_folder(&output_folder(&stdout));
    assert_eq!(report["suite"]["flown"], 2);
    for f in report["flights"].as_array().unwrap() {
        assert_eq!(f["status"], "landed", "{f}");
    }
}

#[test]
fn killed_campaign_resumes_without_flying_twice() {
    let out = tempfile::tempdir().unwrap();
    let child = spawn(&[
        "generate",
        "missions/mission2.yaml",
        "4",
        "--candidates",
        "6",
        "--mode",
        "mission",
        "--mock-speed",
        "10",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    // Wait (bounded) for the first journaled flight, then kill the process hard.
    let start = Instant::now();
    let folder = loop {
        let found = std::fs::read_dir(out.path())
            .ok()
            .and_then(|mut d| d.next())
            .and_then(|e| e.ok())
            .map(|e| e.path());
        if let Some(f) = found.filter(|f| std::fs::read_to_string(f.join("journal.jsonl")).is_ok_and(|j| !j.is_empty()))
        {
            break f;
        }
        assert!(start.elapsed() < Duration::from_secs(90), "no flight journaled in time");
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut child = child;
    child.kill().expect("kill");
    let _ = child.wait();
    let before = std::fs::read_to_string(folder.join("journal.jsonl"))
        .unwrap()
        .lines()
        .count();
    assert!((1..4).contains(&before), "{before} flights before the kill");
    let (code, stdout, stderr) = run_bounded(
        &["generate", "--resume", folder.to_str().unwrap()],
        Duration::from_secs(120),
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("resuming"), "{stderr}");
    let report = verify_folder(&output_folder(&stdout));
    assert_eq!(report["suite"]["flown"], 4, "the budget is 4");
    let mut candidates: Vec<u64> = report["flights"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["candidate"].as_u64().unwrap())
        .collect();
    candidates.sort();
    candidates.dedup();
    assert_eq!(candidates.len(), 4, "a candidate was flown twice");
}

#[test]
fn bad_input_fails_fast_and_clearly() {
    let (code, _, err) = prgenuav(&["generate", "missions/mission2.yaml", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("budget 0 is out of range"), "{err}");
    let out = tempfile::tempdir().unwrap();
    let (code, _, err) = prgenuav(&[
        "generate",
        "missions/nope.yaml",
        "2",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("nope.yaml"), "{err}");
    // A prior folder without learnt.json: refused before anything is sampled, naming the file.
    let (code, _, err) = prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "2",
        "--prior",
        out.path().to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("learnt.json"), "{err}");
    // Nobody sends to this port: no reachable vehicle, a clear error within the connect timeout.
    let dead = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let (code, _, err) = run_bounded(
        &[
            "generate",
            "missions/mission2.yaml",
            "1",
            "--candidates",
            "2",
            "--connect",
            &format!("udpin:127.0.0.1:{dead}"),
            "--connect-timeout",
            "1",
            "--out",
            out.path().to_str().unwrap(),
            "--quiet",
        ],
        Duration::from_secs(60),
    );
    // Exit 1, as when every flight failed on its backend: the setup broke, not the input.
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no reachable vehicle"), "{err}");
}

#[test]
fn an_unreachable_endpoint_is_dropped_and_the_campaign_goes_on() {
    let rt = tokio::runtime::Runtime::new().unwrap();
    let mock = rt
        .block_on(
            mock_autopilot::MockAutopilot::builder()
                .link(mock_autopilot::LinkSpec::UdpIn("127.0.0.1:0".parse().unwrap()))
                .speed_factor(mock_autopilot::SpeedFactor::Times(10.0))
                .spawn(),
        )
        .unwrap();
    let port = mock.local_addr().unwrap().port();
    let dead = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let out = tempfile::tempdir().unwrap();
    // Budget 2 and two vehicles in one static round: both take a job at the start, so the dead one is tried
    // (and dropped) and its job goes to the live one. (A learning campaign's rounds fly at most one of these
    // 2 flights each, which either vehicle may take: the dead one was then not always tried.)
    let connect = format!("udpin:127.0.0.1:{dead},udpout:127.0.0.1:{port}");
    let (code, stdout, stderr) = run_bounded(
        &[
            "generate",
            "missions/mission2.yaml",
            "2",
            "--candidates",
            "4",
            "--mode",
            "mission",
            "--no-learn",
            "--connect",
            &connect,
            "--connect-timeout",
            "1",
            "--out",
            out.path().to_str().unwrap(),
        ],
        Duration::from_secs(120),
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("dropped"), "the dead endpoint is named: {stderr}");
    let report = verify_folder(&output_folder(&stdout));
    assert_eq!(report["suite"]["flown"], 2);
    drop(mock);
}

/// Each candidate's flights in the journal, as (attempt, failed, trajectory), in attempt order.
fn flights_by_candidate(folder: &Path) -> std::collections::BTreeMap<u64, Vec<(u64, bool, String)>> {
    let mut out: std::collections::BTreeMap<u64, Vec<(u64, bool, String)>> = Default::default();
    for line in std::fs::read_to_string(folder.join("journal.jsonl")).unwrap().lines() {
        let r: serde_json::Value = serde_json::from_str(line).unwrap();
        let failed = r["min_distance"].as_f64().is_some_and(|d| d < 1.5);
        let flight = (
            r["attempt"].as_u64().unwrap_or(0),
            failed,
            r["trajectory"].as_str().unwrap().to_string(),
        );
        out.entry(r["candidate"].as_u64().unwrap()).or_default().push(flight);
    }
    for flights in out.values_mut() {
        flights.sort();
    }
    out
}

#[test]
fn confirm_2_on_the_mock_flies_each_failure_again_and_writes_its_runs() {
    let out = tempfile::tempdir().unwrap();
    // Plain mission mode flies into obstacle 1: every flight fails, so every test is flown twice.
    let (code, stdout, stderr) = run_bounded(
        &[
            "generate",
            "missions/mission2.yaml",
            "4",
            "--candidates",
            "6",
            "--mode",
            "mission",
            "--mock-speed",
            "40",
            "--confirm",
            "2",
            "--out",
            out.path().to_str().unwrap(),
        ],
        Duration::from_secs(120),
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("Written by expected 2026 points: each is expected to earn points"),
        "{stdout}"
    );
    assert!(stderr.contains("(its flight 2)"), "re-flights are announced: {stderr}");
    let folder = output_folder(&stdout);
    let report = verify_folder(&folder);
    // Both tests fly the mission's path into obstacle 1: the second copies the first's trajectory.
    assert_eq!(
        (report["suite"]["flown"].as_u64(), report["suite"]["failing"].as_u64()),
        (Some(4), Some(1))
    );
    assert_eq!(report["tests"][1]["near_duplicate_of"], "test_0.yaml");
    assert_eq!(report["suite"]["confirmation_rate"], 1.0);
    for (c, flights) in flights_by_candidate(&folder) {
        let files: Vec<&str> = flights.iter().map(|f| f.2.as_str()).collect();
        assert_eq!(
            files,
            [
                format!("flights/candidate_{c}.csv"),
                format!("flights/candidate_{c}_2.csv")
            ]
        );
    }
    assert!(folder.join("test_0-2.csv").is_file() || folder.join("test_0-1.csv").is_file());
    let unconfirmed: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("unconfirmed.json")).unwrap()).unwrap();
    assert_eq!(
        unconfirmed[0]["reported_as"], "unconfirmed/test_0.yaml",
        "the near-duplicate kept on disk"
    );
    assert!(
        std::fs::read_to_string(folder.join("report.md"))
            .unwrap()
            .contains("## Tests that failed")
    );
    // `score` reads each test's runs (test_N.csv, test_N-K.csv) and agrees with the report.
    let (code, json, err) = prgenuav(&["score", folder.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let s: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!((s["failure_score"].as_f64().unwrap() - report["suite"]["failure_score"].as_f64().unwrap()).abs() < 1e-6);
    assert!(
        s["tests"]
            .as_array()
            .unwrap()
            .iter()
            .all(|t| t["runs"].as_array().unwrap().len() == 2)
    );
    // A resumed campaign keeps its confirmation: another --confirm is refused by name.
    let (code, _, err) = prgenuav(&["generate", "--resume", folder.to_str().unwrap(), "--confirm", "3"]);
    assert_eq!(code, 2);
    assert!(err.contains("--confirm 3 conflicts with confirm 2"), "{err}");
    let (code, _, err) = prgenuav(&["generate", "missions/mission2.yaml", "2", "--confirm", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("--confirm (flight.confirm) 0 is out of range"), "{err}");
}

#[test]
fn confirm_3_on_free_running_mocks_keeps_every_test_within_its_majority() {
    let out = tempfile::tempdir().unwrap();
    // Free-running clocks make repeated flights differ with the CPU's load: whatever they give, the verdicts
    // must follow the flights.
    let (code, stdout, stderr) = run_bounded(
        &[
            "generate",
            "missions/mission2.yaml",
            "3",
            "--candidates",
            "8",
            "--no-learn",
            "--seed",
            "2",
            "--mock-free-running",
            "--mock-speed",
            "20",
            "--mock-vehicles",
            "1",
            "--confirm",
            "3",
            "--out",
            out.path().to_str().unwrap(),
        ],
        Duration::from_secs(240),
    );
    assert_eq!(code, 0, "{stderr}");
    let folder = output_folder(&stdout);
    let report = verify_folder(&folder);
    assert_eq!(report["suite"]["flown"], 3);
    let tests = report["tests"].as_array().unwrap();
    let by_candidate = flights_by_candidate(&folder);
    for (c, flights) in &by_candidate {
        let attempts: Vec<u64> = flights.iter().map(|f| f.0).collect();
        assert_eq!(attempts, (0..flights.len() as u64).collect::<Vec<_>>(), "candidate {c}");
        let failures = flights.iter().filter(|f| f.1).count();
        assert!(
            flights.len() <= 3 && (flights.len() == 1 || flights[0].1),
            "only a failure is flown again"
        );
        let verdict = tests.iter().find(|t| t["candidate"] == *c);
        assert_eq!(verdict.is_some(), failures > 0, "candidate {c}");
        if let Some(t) = verdict {
            // Written (confirmed) by the 2026 rule: it failed, the 10 % bound of its expected points is above
            // zero, and its trajectory copies no better written test's.
            let earns = t["expected"]["points"]["low"].as_f64().is_some_and(|low| low > 0.0);
            let written = failures > 0 && earns && t["near_duplicate_of"].is_null();
            assert_eq!(t["confirmed"], written, "candidate {c}: {t}");
            assert_eq!(t["flights"].as_u64(), Some(flights.len() as u64));
        }
    }
    // One vehicle: a failing first flight is followed by its test's second flight, unless the budget ended.
    let order: Vec<(u64, u64, bool)> = std::fs::read_to_string(folder.join("journal.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .map(|r| {
            let failed = r["min_distance"].as_f64().is_some_and(|d| d < 1.5);
            (
                r["candidate"].as_u64().unwrap(),
                r["attempt"].as_u64().unwrap_or(0),
                failed,
            )
        })
        .collect();
    for w in order.windows(2) {
        if w[0].1 == 0 && w[0].2 {
            assert_eq!((w[1].0, w[1].1), (w[0].0, 1), "{order:?}");
        }
    }
    let unconfirmed: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(folder.join("unconfirmed.json")).unwrap()).unwrap();
    let failed_once = report["suite"]["failed_once"].as_u64().unwrap() as usize;
    assert_eq!(
        unconfirmed.len() + report["suite"]["failing"].as_u64().unwrap() as usize,
        failed_once
    );
}
