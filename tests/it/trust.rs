//! The campaign folder as a trust boundary, attacked as a hostile file or user would: links planted where the
//! campaign writes, journal lines naming files outside the folder or impossible distances, a deleted lock,
//! numbers without bounds, FIFOs and devices as inputs, and a scheduler's SIGTERM with a runner job that left
//! a detached grandchild. Each case runs the binary as a user would.

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

/// A small static mock campaign's arguments.
fn small<'a>(budget: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "generate",
        "missions/mission2.yaml",
        budget,
        "--candidates",
        "6",
        "--no-learn",
        "--mode",
        "mission",
        "--mock-vehicles",
        "1",
        "--quiet",
        "--out",
        out,
    ]
}

fn folder_of(stdout: &str) -> PathBuf {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("output folder:"))
        .unwrap_or_else(|| panic!("no output folder in {stdout:?}"));
    PathBuf::from(line.trim_start_matches("output folder:").trim())
}

/// A finished campaign of `budget` flights; its folder.
fn finished(out: &Path, budget: &str) -> PathBuf {
    let (code, stdout, stderr) = prgenuav(&small(budget, out.to_str().unwrap()));
    assert_eq!(code, 0, "{stderr}");
    folder_of(&stdout)
}

fn journal_lines(folder: &Path) -> Vec<Value> {
    std::fs::read_to_string(folder.join("journal.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn write_journal(folder: &Path, lines: &[Value]) {
    let text: String = lines.iter().map(|v| format!("{v}\n")).collect();
    std::fs::write(folder.join("journal.jsonl"), text).unwrap();
}

fn resume(folder: &Path) -> (i32, String, String) {
    prgenuav(&["generate", "--resume", folder.to_str().unwrap(), "--quiet"])
}

#[test]
fn a_link_planted_where_a_flight_is_recorded_is_replaced_and_its_target_untouched() {
    let out = tempfile::tempdir().unwrap();
    let folder = finished(out.path(), "2");
    let mut lines = journal_lines(&folder);
    // The last flight "was in the air when the campaign died": its record is gone, a link waits in its place.
    let last = lines.pop().unwrap();
    write_journal(&folder, &lines);
    let victim = out.path().join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    let trajectory = folder.join(last["trajectory"].as_str().unwrap());
    std::fs::remove_file(&trajectory).unwrap();
    std::os::unix::fs::symlink(&victim, &trajectory).unwrap();
    std::os::unix::fs::symlink(&victim, folder.join("report.json.lnk")).unwrap();
    std::fs::remove_file(folder.join("report.json")).unwrap();
    std::os::unix::fs::symlink(&victim, folder.join("report.json")).unwrap();

    let (code, _, stderr) = resume(&folder);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    for written in [&trajectory, &folder.join("report.json")] {
        let meta = std::fs::symlink_metadata(written).unwrap();
        assert!(meta.file_type().is_file(), "{written:?} is a file of its own now");
    }
    assert_eq!(journal_lines(&folder).len(), 2);
}

#[test]
fn journal_lines_naming_files_outside_the_folder_or_impossible_distances_are_refused_naming_the_line() {
    let out = tempfile::tempdir().unwrap();
    let folder = finished(out.path(), "2");
    let good = journal_lines(&folder);
    let edits: [(&str, Value, &str); 5] = [
        (
            "trajectory",
            Value::from("../../../../etc/hostname"),
            "../../../../etc/hostname",
        ),
        ("trajectory", Value::from("/etc/hostname"), "/etc/hostname"),
        ("min_distance", Value::from(-1.0), "min_distance -1"),
        ("min_distance", Value::from(1e300), "min_distance 1e300"),
        ("flight_time_s", Value::from(-5.0), "flight_time_s -5"),
    ];
    for (field, value, needle) in edits {
        let mut lines = good.clone();
        lines[1][field] = value;
        write_journal(&folder, &lines);
        let t0 = Instant::now();
        let (code, _, stderr) = resume(&folder);
        assert_eq!(code, 2, "{field}: {stderr}");
        assert!(
            stderr.contains("journal.jsonl:2") && stderr.contains(needle),
            "{field}: {stderr}"
        );
        assert!(t0.elapsed() < Duration::from_secs(10));
    }
    write_journal(&folder, &good);
    let (code, _, stderr) = resume(&folder);
    assert_eq!(code, 0, "the restored journal resumes: {stderr}");
    let report = std::fs::read_to_string(folder.join("report.json")).unwrap();
    assert!(!report.contains("/etc/"), "nothing outside the folder is named");
}

/// Starts a slowed campaign and returns it once a flight is in the air, with its folder.
fn start_flying(out: &Path, extra: &[&str]) -> (Child, PathBuf) {
    let o = out.to_str().unwrap();
    let mut args = vec![
        "generate",
        "missions/mission2.yaml",
        "6",
        "--candidates",
        "8",
        "--no-learn",
        "--mode",
        "mission",
        "--out",
        o,
    ];
    args.extend_from_slice(extra);
    let mut child = binary()
        .args(&args)
        .stderr(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    // Read on a thread, so a campaign that never says `[fly]` fails the test in 3 minutes instead of hanging it.
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let t0 = Instant::now();
    let mut seen = Vec::new();
    loop {
        let left = Duration::from_secs(180).saturating_sub(t0.elapsed());
        match rx.recv_timeout(left) {
            Ok(line) if line.starts_with("[fly]") => break,
            Ok(line) => seen.push(line),
            Err(e) => {
                let _ = child.kill();
                panic!("no `[fly]` stage ({e:?}); stderr so far:\n{}", seen.join("\n"));
            }
        }
    }
    let folder = std::fs::read_dir(out).unwrap().next().unwrap().unwrap().path();
    (child, folder)
}

fn signal(child: &Child, name: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
}

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

#[test]
fn a_deleted_lock_file_lets_no_second_writer_in() {
    let out = tempfile::tempdir().unwrap();
    let (mut child, folder) = start_flying(out.path(), &["--mock-speed", "4", "--mock-vehicles", "1"]);
    std::fs::remove_file(folder.join("campaign.lock")).unwrap();
    let (code, _, stderr) = resume(&folder);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("one writer per campaign folder"), "{stderr}");
    signal(&child, "INT");
    wait_bounded(&mut child, Duration::from_secs(25));
}

#[test]
fn sigterm_lands_the_flights_journals_them_interrupted_and_exits_as_ctrl_c_does() {
    let out = tempfile::tempdir().unwrap();
    let (mut child, folder) = start_flying(out.path(), &["--mock-speed", "4", "--mock-vehicles", "2"]);
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, "TERM");
    let (code, took) = wait_bounded(&mut child, Duration::from_secs(25));
    assert_eq!(code, Some(1), "a stopped campaign exits 1, not 143 (took {took:?})");
    let lines = journal_lines(&folder);
    assert!(
        lines.iter().any(|r| r["status"] == "interrupted"),
        "the flights in the air are journaled: {lines:?}"
    );
    assert!(folder.join("report.json").exists());
    let (code, _, stderr) = resume(&folder);
    assert_eq!(code, 0, "{stderr}");
}

#[test]
fn fly_stops_on_sigterm_as_on_ctrl_c() {
    // No vehicle answers on this port: `fly` waits for one until a scheduler's SIGTERM comes.
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .unwrap()
        .port();
    let (_dir, test) = super::test_file(2, super::valid_pair());
    let url = format!("udpin:127.0.0.1:{port}");
    let mut child = binary()
        .args(["fly", test.to_str().unwrap(), "--connect", &url, "--no-predict"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    while !seen.contains("waiting for a vehicle") {
        let mut line = String::new();
        assert!(
            stderr.read_line(&mut line).unwrap() > 0,
            "fly ended before waiting: {seen}"
        );
        seen.push_str(&line);
    }
    signal(&child, "TERM");
    let (code, took) = wait_bounded(&mut child, Duration::from_secs(20));
    let mut rest = String::new();
    let _ = std::io::Read::read_to_string(&mut stderr, &mut rest);
    assert!(
        code.is_some_and(|c| c != 143),
        "fly ends through its own stop, not the signal's default ({code:?} after {took:?}): {rest}"
    );
    assert!(rest.contains("SIGTERM: landing the vehicle"), "{rest}");
}

#[test]
fn sigterm_stops_a_runner_job_and_the_grandchild_it_detached() {
    let out = tempfile::tempdir().unwrap();
    let pids = tempfile::tempdir().unwrap();
    // The job detaches a grandchild into a session of its own, then waits as a long flight would.
    let runner = format!(
        "setsid sh -c 'echo $$ > {}/$$.pid; exec sleep 300' </dev/null >/dev/null 2>&1 & sleep 300 # {{test}}",
        pids.path().display()
    );
    let (mut child, folder) = start_flying(out.path(), &["--runner", &runner, "--jobs", "2"]);
    let t0 = Instant::now();
    while std::fs::read_dir(pids.path()).unwrap().count() < 1 {
        assert!(t0.elapsed() < Duration::from_secs(30), "no job started");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, "TERM");
    let (code, _) = wait_bounded(&mut child, Duration::from_secs(30));
    assert_eq!(code, Some(1));
    std::thread::sleep(Duration::from_millis(200));
    for entry in std::fs::read_dir(pids.path()).unwrap().flatten() {
        let pid: i32 = std::fs::read_to_string(entry.path()).unwrap().trim().parse().unwrap();
        let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
        let alive = !stat.is_empty() && !stat.contains(") Z ");
        assert!(!alive, "the detached grandchild {pid} of {:?} survived", entry.path());
    }
    assert!(
        journal_lines(&folder).iter().any(|r| r["status"] == "interrupted"),
        "the stopped jobs' flights are journaled interrupted"
    );
}

#[test]
fn sigterm_cancels_the_jobs_an_engine_holds_with_the_runner_cancel_command() {
    let out = tempfile::tempdir().unwrap();
    let queue = tempfile::tempdir().unwrap();
    let q = queue.path().display();
    // A stand-in engine: the job it holds is no process of the campaign's (no job marker, its own session),
    // as a Slurm or Kubernetes job is not; only its cancel command, by `{id}`, ends it.
    let runner = format!(
        "env -u PRGENUAV_JOB_DIR setsid sh -c 'echo $$ > {q}/{{id}}.pid; exec sleep 300' </dev/null >/dev/null \
         2>&1 & sleep 300 # {{test}}"
    );
    let cancel = format!("kill $(cat {q}/{{id}}.pid)");
    let args = ["--runner", &runner, "--jobs", "2", "--runner-cancel", &cancel];
    let (mut child, folder) = start_flying(out.path(), &args);
    let t0 = Instant::now();
    while std::fs::read_dir(queue.path()).unwrap().count() < 2 {
        assert!(t0.elapsed() < Duration::from_secs(30), "no job started");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, "TERM");
    let (code, took) = wait_bounded(&mut child, Duration::from_secs(30));
    assert_eq!(code, Some(1));
    std::thread::sleep(Duration::from_millis(200));
    let mut survivors = Vec::new();
    for entry in std::fs::read_dir(queue.path()).unwrap().flatten() {
        let pid: i32 = std::fs::read_to_string(entry.path()).unwrap().trim().parse().unwrap();
        let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
        if !stat.is_empty() && !stat.contains(") Z ") {
            // SAFETY: kill(2) on the stand-in job this test started.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            survivors.push(entry.path());
        }
    }
    assert!(
        survivors.is_empty(),
        "jobs the engine held survived the stop: {survivors:?}"
    );
    assert!(took < Duration::from_secs(20), "stopped in {took:?}");
    let reasons: Vec<String> = journal_lines(&folder)
        .iter()
        .filter(|r| r["status"] == "interrupted")
        .map(|r| r["reason"].to_string())
        .collect();
    assert!(
        reasons.iter().any(|r| r.contains("asked the engine to cancel it")),
        "{reasons:?}"
    );
}

#[test]
fn numbers_beyond_their_documented_range_are_refused_before_anything_starts() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let generate = |extra: &[&'static str]| {
        let mut a: Vec<String> = ["generate", "missions/mission2.yaml", "3", "--out", o]
            .iter()
            .map(|s| s.to_string())
            .collect();
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let fly = |extra: &[&'static str]| {
        let mut a: Vec<String> = [
            "fly",
            "missions/mission2.yaml",
            "--no-predict",
            "--connect",
            "udpin:127.0.0.1:0",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let suite = tempfile::tempdir().unwrap();
    let folder = suite.path().to_str().unwrap();
    let on_suite = |command: &str, extra: &[&'static str]| {
        let mut a = vec![command.to_string(), folder.to_string()];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let evaluate = |extra: &[&'static str]| on_suite("evaluate", extra);
    let cases: Vec<(Vec<String>, &str)> = vec![
        (evaluate(&["--runs", "0"]), "--runs"),
        (evaluate(&["--runs", "21"]), "--runs"),
        (evaluate(&["--top", "0"]), "--top"),
        (evaluate(&["--jobs", "0"]), "--jobs"),
        (evaluate(&["--jobs", "100000"]), "--jobs on the embedded mocks"),
        (
            evaluate(&["--runner", "true {test}", "--jobs", "100000000"]),
            "1 to 1024",
        ),
        (evaluate(&["--similar-below=-1"]), "--similar-below"),
        (evaluate(&["--similar-below", "1e300"]), "--similar-below"),
        (on_suite("score", &["--similar-below", "nan"]), "--similar-below"),
        (generate(&["--mock-speed", "1e300"]), "--mock-speed"),
        (generate(&["--mock-speed", "0.5"]), "--mock-speed"),
        (generate(&["--connect-time-scale", "1e300"]), "--connect-time-scale"),
        (generate(&["--timeout", "1e300"]), "--timeout"),
        (generate(&["--connect-timeout", "1e300"]), "--connect-timeout"),
        (generate(&["--mock-latency", "1e300"]), "--mock-latency"),
        (generate(&["--threshold", "1e300"]), "--threshold"),
        (generate(&["--threshold", "0"]), "--threshold"),
        (generate(&["--confirm", "1000"]), "--confirm"),
        (generate(&["--mock-vehicles", "100000"]), "--mock-vehicles"),
        (
            generate(&["--runner", "true {test}", "--jobs", "100000000"]),
            "1 to 1024",
        ),
        (
            generate(&["--runner", "true {test}", "--job-timeout", "1e19"]),
            "--job-timeout",
        ),
        (generate(&["--instances", "100000"]), "--instances"),
        (fly(&["--time-scale", "1e300"]), "--time-scale"),
        (fly(&["--ready-timeout", "1e300"]), "--ready-timeout"),
        (fly(&["--timeout", "1e300"]), "--timeout"),
    ];
    for (args, needle) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let t0 = Instant::now();
        let (code, _, err) = prgenuav(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(needle) && err.contains("range"), "{args:?}: {err}");
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "{args:?} took {:?}",
            t0.elapsed()
        );
    }
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0, "no campaign folder");
    assert_eq!(
        std::fs::read_dir(suite.path()).unwrap().count(),
        0,
        "no evaluation folder"
    );
    every_declared_range_is_refused_in_the_campaign_toml(o);
}

/// A value beyond `s`'s declared range, as a TOML value (both ends of a range setting).
fn beyond(s: &prgenuav::campaign::settings::Setting) -> Option<String> {
    let l = s.range?;
    let v = if l.whole {
        format!("{}", (l.max_here() as u64).saturating_mul(2) + 1)
    } else {
        format!("{:?}", l.max * 1.01 + 1.0)
    };
    let is_range = matches!(s.default_value(), Some(toml::Value::Table(_)));
    Some(if is_range {
        format!("{{ min = {v}, max = {v} }}")
    } else {
        v
    })
}

/// Every setting the campaign TOML takes with a declared range, `generator.*` included, set beyond it there.
fn every_declared_range_is_refused_in_the_campaign_toml(out: &str) {
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for s in prgenuav::campaign::settings::all().filter(|s| s.in_file()) {
        let Some(v) = beyond(s) else { continue };
        let file = dir.path().join(format!("{}_{}.toml", s.section, s.key));
        std::fs::write(&file, format!("[{}]\n{} = {v}\n", s.section, s.key)).unwrap();
        let f = file.to_str().unwrap();
        let args = ["generate", "missions/mission2.yaml", "3", "--out", out, "--config", f];
        let (code, _, err) = prgenuav(&args);
        assert_eq!(code, 2, "{}: {err}", s.toml_key());
        assert!(err.contains(s.key) && err.contains("range"), "{}: {err}", s.toml_key());
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} ranges declared");
    assert_eq!(std::fs::read_dir(out).unwrap().count(), 0, "no campaign folder");
}

#[test]
fn a_fifo_and_a_device_as_flights_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    super::case(2)
        .with_obstacles(super::valid_pair())
        .save(&dir.path().join("test_0.yaml"), prgenuav::model::Spelling::New)
        .unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("test_0-1.csv")).unwrap();
    let fifo = std::ffi::CString::new(dir.path().join("test_0-2.csv").to_str().unwrap()).unwrap();
    // SAFETY: mkfifo(3) on a path we own; no memory is shared.
    assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) }, 0);
    let t0 = Instant::now();
    let (_, out, err) = prgenuav(&["score", dir.path().to_str().unwrap()]);
    assert!(t0.elapsed() < Duration::from_secs(10), "took {:?}", t0.elapsed());
    let said = format!("{out}{err}");
    assert!(said.contains("a device") || said.contains("a FIFO"), "{said}");
}

#[test]
fn bad_inputs_are_refused_at_once_naming_the_file_and_the_cause_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fifo = d.join("fifo.toml");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo(3) on a path we own; no memory is shared.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    std::fs::create_dir(d.join("dir.yaml")).unwrap();
    std::fs::write(d.join("bytes.toml"), b"seed = \xff\n").unwrap();
    let name = |f: &str| d.join(f).to_str().unwrap().to_string();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "generate".into(),
                "missions/mission2.yaml".into(),
                "3".into(),
                "--config".into(),
                name("fifo.toml"),
            ],
            "a FIFO",
        ),
        (
            vec![
                "generate".into(),
                "missions/mission2.yaml".into(),
                "3".into(),
                "--config".into(),
                "/dev/zero".into(),
            ],
            "a device",
        ),
        (
            vec![
                "generate".into(),
                "missions/mission2.yaml".into(),
                "3".into(),
                "--config".into(),
                name("dir.yaml"),
            ],
            "it is a folder",
        ),
        (
            vec![
                "generate".into(),
                "missions/mission2.yaml".into(),
                "3".into(),
                "--config".into(),
                name("bytes.toml"),
            ],
            "not UTF-8",
        ),
        (
            vec![
                "generate".into(),
                "missions/mission2.yaml".into(),
                "3".into(),
                "--config".into(),
                name("gone.toml"),
            ],
            "No such file",
        ),
        (vec!["check".into(), name("gone.yaml")], "No such file"),
        (vec!["check".into(), name("dir.yaml")], "it is a folder"),
        (vec!["simulate".into(), name("fifo.toml")], "a FIFO"),
        (vec!["evaluate".into(), name("gone")], "No such file"),
    ];
    for (args, cause) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let t0 = Instant::now();
        let (code, _, err) = prgenuav(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "{args:?} took {:?}",
            t0.elapsed()
        );
        let file = args.last().unwrap();
        assert!(err.contains(file) && err.contains(cause), "{args:?}: {err}");
        assert_eq!(err.matches(cause).count(), 1, "the cause twice: {err}");
        assert!(err.matches("os error").count() <= 1, "the cause twice: {err}");
    }
}

#[test]
fn ctrl_c_during_screening_exits_1_with_a_report_and_the_resume_command() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let mut child = binary()
        .args([
            "generate",
            "missions/mission2.yaml",
            "5",
            "--candidates",
            "5000",
            "--no-learn",
            "--out",
            o,
        ])
        .stderr(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(60) {
        match lines.next() {
            Some(Ok(line)) if line.starts_with("[screen]") => break,
            Some(_) => {}
            None => panic!("generate ended before screening"),
        }
    }
    signal(&child, "INT");
    let stderr = std::thread::spawn(move || lines.map_while(Result::ok).collect::<Vec<_>>().join("\n"));
    let (code, _) = wait_bounded(&mut child, Duration::from_secs(25));
    let mut stdout = String::new();
    std::io::Read::read_to_string(&mut child.stdout.take().unwrap(), &mut stdout).unwrap();
    let stderr = stderr.join().unwrap();
    assert_eq!(code, Some(1), "{stderr}");
    let folder = folder_of(&stdout);
    assert!(folder.join("report.json").exists(), "{stderr}");
    assert!(stderr.contains(&format!("--resume {}", folder.display())), "{stderr}");
}

#[test]
fn a_campaign_stores_its_case_absolute_and_another_spelling_of_it_is_no_conflict() {
    let out = tempfile::tempdir().unwrap();
    let folder = finished(out.path(), "2");
    let stored: Value = serde_json::from_str(&std::fs::read_to_string(folder.join("campaign.json")).unwrap()).unwrap();
    assert!(
        Path::new(stored["campaign"]["case"].as_str().unwrap()).is_absolute(),
        "{stored}"
    );
    let f = folder.to_str().unwrap();
    let (code, _, stderr) = prgenuav(&["generate", "./missions/mission2.yaml", "--resume", f, "--quiet"]);
    assert_eq!(code, 0, "the same file under another spelling: {stderr}");
    assert!(
        !stderr.contains("resuming as"),
        "unchanged settings are not shown: {stderr}"
    );
    // Changed by hand since the first run: the resume names what changed, with both values.
    let path = folder.join("campaign.json");
    let mut edited = stored.clone();
    edited["campaign"]["budget"] = 1.into();
    edited["screening"]["max_iou"] = 0.25.into();
    std::fs::write(&path, serde_json::to_string_pretty(&edited).unwrap()).unwrap();
    let (code, _, stderr) = prgenuav(&["generate", "--resume", f, "--quiet"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("campaign.json differs from what the campaign's first run wrote")
            && stderr.contains("campaign.budget 2 -> 1; screening.max_iou 0.5 -> 0.25")
            && stderr.contains("resuming as"),
        "{stderr}"
    );
}
