//! `evaluate`'s folder as a trust boundary and its runs as a user meets them: links where it writes, journal
//! lines naming files elsewhere, flights that left nothing to judge, backends that fail, tests `check`
//! refuses, folders of any test names, and the stop.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use prgenuav::model::{Obstacle, Spelling};
use serde_json::Value;

use super::{case, prgenuav, valid_pair};

fn write_test(dir: &Path, name: &str, obstacles: Vec<Obstacle>) {
    case(2)
        .with_obstacles(obstacles)
        .save(&dir.join(name), Spelling::Old)
        .unwrap();
}

fn json(out: &str) -> Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn an_evaluation_folder_or_subfolder_that_is_a_link_is_refused_and_nothing_written_through_it() {
    for sub in ["", "flights", "averages"] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        write_test(d, "test_0.yaml", valid_pair());
        let elsewhere = tempfile::tempdir().unwrap();
        std::fs::write(elsewhere.path().join("report.md"), "precious").unwrap();
        let link = if sub.is_empty() {
            d.join("evaluation")
        } else {
            std::fs::create_dir(d.join("evaluation")).unwrap();
            d.join("evaluation").join(sub)
        };
        std::os::unix::fs::symlink(elsewhere.path(), &link).unwrap();
        let (code, _, err) = prgenuav(&["evaluate", d.to_str().unwrap(), "--runs", "1"]);
        assert_eq!(code, 2, "{sub}: {err}");
        assert!(
            err.contains(link.to_str().unwrap()) && err.contains("not a folder of its own"),
            "{sub}: {err}"
        );
        assert_eq!(files_in(elsewhere.path()), ["report.md"], "{sub}");
        assert_eq!(
            std::fs::read_to_string(elsewhere.path().join("report.md")).unwrap(),
            "precious"
        );
    }
}

/// A suite of one valid test evaluated with one run on the mock; its folder and journal line.
fn evaluated_once(d: &Path) -> Value {
    write_test(d, "test_0.yaml", valid_pair());
    let (code, _, err) = prgenuav(&["evaluate", d.to_str().unwrap(), "--runs", "1", "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let journal = std::fs::read_to_string(d.join("evaluation/journal.jsonl")).unwrap();
    json(journal.lines().next().unwrap())
}

fn rewrite_journal(d: &Path, line: &Value) {
    std::fs::write(d.join("evaluation/journal.jsonl"), format!("{line}\n")).unwrap();
}

#[test]
fn a_journal_naming_a_trajectory_outside_the_folder_is_refused_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut line = evaluated_once(d);
    let other = tempfile::tempdir().unwrap();
    let outside = other.path().join("test_0-2.csv");
    std::fs::copy(
        d.join("evaluation").join(line["trajectory"].as_str().unwrap()),
        &outside,
    )
    .unwrap();
    for named in [outside.to_str().unwrap().to_string(), "../../other/test_0-2.csv".into()] {
        line["trajectory"] = Value::from(named.clone());
        rewrite_journal(d, &line);
        let (code, out, err) = prgenuav(&["evaluate", d.to_str().unwrap(), "--runs", "1", "--json"]);
        assert_eq!(code, 2, "{named}: {out}{err}");
        assert!(
            err.contains("journal.jsonl:1") && err.contains("not a file inside"),
            "{named}: {err}"
        );
    }
}

#[test]
fn a_run_that_left_nothing_to_judge_is_flown_again() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut line = evaluated_once(d);
    // The flight's file deleted; then a flight journaled link_lost with no trajectory at all.
    std::fs::remove_file(d.join("evaluation").join(line["trajectory"].as_str().unwrap())).unwrap();
    let (code, out, err) = prgenuav(&["evaluate", d.to_str().unwrap(), "--runs", "1", "--json"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("left nothing to judge") && err.contains("flown again"),
        "{err}"
    );
    let j = json(&out);
    assert_eq!(j["missing_flights"], 0);
    assert!(
        j["tests"][0]["runs"][0]["trajectory"]
            .as_str()
            .unwrap()
            .ends_with("candidate_0_2.csv")
    );
    line["status"] = Value::from("link_lost");
    line["reason"] = Value::from("uploading the mission: no answer from the vehicle after 10 retries");
    line["trajectory"] = Value::from("");
    line["flight_time_s"] = Value::from(1.27);
    rewrite_journal(d, &line);
    let (code, out, err) = prgenuav(&["evaluate", d.to_str().unwrap(), "--runs", "1", "--json"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("no trajectory was recorded") && err.contains("uploading the mission"),
        "{err}"
    );
    assert_eq!(json(&out)["missing_flights"], 0);
}

#[test]
fn flights_that_all_failed_on_the_backend_say_why_on_stderr_and_in_the_report_without_negative_zeros() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_test(d, "test_0.yaml", valid_pair());
    write_test(d, "test_1.yaml", vec![Obstacle::new(10.0, 2.0, 20.0, -20.0, 20.0, 0.0)]);
    let args = [
        "evaluate",
        d.to_str().unwrap(),
        "--runs",
        "1",
        "--quiet",
        "--runner",
        "false {test}",
    ];
    let (code, _, err) = prgenuav(&args);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("incomplete: 2 flight(s) missing") && err.contains("failed on its backend"),
        "{err}"
    );
    let md = std::fs::read_to_string(d.join("evaluation/report.md")).unwrap();
    assert!(md.contains("failed on its backend"), "{md}");
    let report = std::fs::read_to_string(d.join("evaluation/report.json")).unwrap();
    for text in [&md, &report] {
        assert!(!text.contains("-0.0"), "a negative zero: {text}");
    }
    assert!(
        json(&report)["missing_why"][0].as_str().unwrap().contains("backend"),
        "{report}"
    );
    assert!(md.contains("No pair of average trajectories"), "{md}");
}

#[test]
fn tests_check_refuses_are_refused_naming_the_file_and_rule_and_check_agrees_on_no_obstacles() {
    let mut long = valid_pair();
    long[0].size.l = -2.0;
    let mut wide = valid_pair();
    wide[1].size.w = 1e9;
    for (obstacles, rule) in [(long, "size.l"), (wide, "size.w"), (Vec::new(), "at least 1 obstacle")] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        write_test(d, "test_0.yaml", obstacles.clone());
        let (code, _, err) = prgenuav(&["evaluate", d.to_str().unwrap(), "--runs", "1"]);
        assert_eq!(code, 2, "{rule}: {err}");
        assert!(err.contains("test_0.yaml") && err.contains(rule), "{rule}: {err}");
        assert!(!d.join("evaluation").exists(), "nothing flown or written");
        let (code, out, _) = prgenuav(&["check", d.join("test_0.yaml").to_str().unwrap()]);
        if obstacles.is_empty() {
            assert_eq!(code, 0, "a case study is valid as one");
            assert!(
                out.contains("not a test evaluate or score can judge") && out.contains(rule),
                "{out}"
            );
        } else {
            assert_eq!(code, 1, "{out}");
        }
    }
}

#[test]
fn a_folder_of_tests_with_any_names_evaluates_and_top_reads_only_its_tests() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_test(d, "alpha.yaml", valid_pair());
    std::fs::write(d.join("beta.yaml"), "this: [is not a test").unwrap();
    let args = [
        "evaluate",
        d.to_str().unwrap(),
        "--runs",
        "1",
        "--top",
        "1",
        "--json",
        "--quiet",
    ];
    let (code, out, err) = prgenuav(&args);
    assert_eq!(code, 0, "{err}");
    let j = json(&out);
    assert_eq!(j["tests"].as_array().unwrap().len(), 1);
    assert!(j["tests"][0]["test"].as_str().unwrap().ends_with("alpha.yaml"), "{out}");
}

#[test]
fn ctrl_c_says_how_evaluate_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_test(d, "test_0.yaml", valid_pair());
    let mut child = Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args(["evaluate", d.to_str().unwrap(), "--runs", "5", "--jobs", "1"])
        .current_dir(super::repo())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    // The first flight landed: the signal handlers are in place.
    for l in lines.by_ref() {
        if l.unwrap().starts_with("flight candidate") {
            break;
        }
    }
    // SAFETY: kill(2) on the child this test started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let said: Vec<String> = lines.map(Result::unwrap).collect();
    let _ = child.wait();
    let said = said.join("\n");
    assert!(said.contains("run the same evaluate command again"), "{said}");
    assert!(!said.contains("--resume"), "{said}");
}

#[test]
fn evaluate_takes_q_for_quiet_as_generate_does() {
    let empty = tempfile::tempdir().unwrap();
    let (code, _, err) = prgenuav(&["evaluate", empty.path().to_str().unwrap(), "-q"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("holds no test") && !err.contains("unexpected argument"),
        "{err}"
    );
}
