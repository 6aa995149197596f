//! `score`: the competition's metrics over a folder of tests with CSV and ULog flights.

use prgenuav::campaign::evaluation::folder_score::score_folder;
use prgenuav::judge::Judge;
use prgenuav::model::{Obstacle, Spelling, load_ulog_trajectory};

use super::ulog::ULogWriter;
use super::{case, prgenuav};

/// A straight flight north-east along y = 0 .. 50 at x = `x`, 10 m up, lasting `secs` seconds, as CSV.
fn csv_flight(x: f64, secs: f64) -> String {
    let mut s = String::from("timestamp,x,y,z,r\n0,0,0,0,\n");
    let n = 100;
    for i in 1..=n {
        let t = secs * i as f64 / n as f64;
        s += &format!("{},{x},{},10,\n", (t * 1e6) as i64, 50.0 * i as f64 / n as f64);
    }
    s
}

fn write_test(dir: &std::path::Path, i: usize, obstacles: Vec<Obstacle>) {
    case(2)
        .with_obstacles(obstacles)
        .save(&dir.join(format!("test_{i}.yaml")), Spelling::Old)
        .unwrap();
}

#[test]
fn ulog_local_position_is_read_with_height_up() {
    let bytes = ULogWriter::new()
        .local_position_format()
        .sample(1_000_000, 0.0, 0.0, -0.0, 0.5)
        .sample(1_500_000, 1.0, 2.0, -3.0, 0.6)
        .finish();
    let (_d, path) = super::temp_file("f.ulg", &bytes);
    let t = load_ulog_trajectory(&path).unwrap();
    assert_eq!(t.samples.len(), 2);
    let s = t.samples[1];
    assert_eq!((s.t_s, s.x, s.y, s.z), (0.5, 1.0, 2.0, 3.0));
    assert!((s.r.unwrap() - 0.6).abs() < 1e-6);
    let (_d2, junk) = super::temp_file("junk.ulg", b"ULog\x01\x12\x35garbage");
    assert!(load_ulog_trajectory(&junk).is_err());
}

#[test]
fn folder_scores_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Box at x = 3 .. 5 (centre 4, l = 2 along x), y = 24 .. 26: a flight along x = 0 passes 3 m away,
    // one along x = 2.5 passes 0.5 m away.
    let box_a = Obstacle::new(2.0, 2.0, 20.0, 4.0, 25.0, 0.0);
    write_test(d, 0, vec![box_a]);
    std::fs::write(d.join("test_0-1.csv"), csv_flight(2.5, 60.0)).unwrap(); // 0.5 m: 2 points
    std::fs::write(d.join("test_0-2.csv"), csv_flight(0.0, 30.0)).unwrap(); // 3 m: 0 points
    // The same box again: a duplicate, flown through (0.1 m: 5 points) but not counted.
    write_test(d, 1, vec![box_a]);
    std::fs::write(d.join("test_1.csv"), csv_flight(2.9, 60.0)).unwrap();
    // A test without flights.
    write_test(d, 2, vec![Obstacle::new(2.0, 2.0, 20.0, -20.0, 25.0, 0.0)]);
    // A ULog flight 1.2 m away (1 point), 2 minutes.
    write_test(d, 3, vec![Obstacle::new(2.0, 2.0, 20.0, -10.0, 25.0, 0.0)]);
    let mut w = ULogWriter::new().local_position_format().sample(0, 0.0, 0.0, 0.0, 0.0);
    for i in 1..=120 {
        w = w.sample(i * 1_000_000, -7.8, 50.0 * i as f32 / 120.0, -10.0, 0.0);
    }
    std::fs::write(d.join("test_3.ulg"), w.finish()).unwrap();

    let s = score_folder(d, Judge::E2025).unwrap();
    assert_eq!(s.judge, Judge::E2025);
    assert_eq!(s.tests.len(), 4);
    let t0 = &s.tests[0];
    assert_eq!(t0.runs.len(), 2);
    assert_eq!(t0.runs.iter().map(|r| r.points).collect::<Vec<_>>(), vec![2, 0]);
    // mean points 1 x 10 / (1^2 x 0.75 min) = 13.333
    assert!((t0.score - 10.0 / 0.75).abs() < 1e-9, "{}", t0.score);
    assert!(t0.failed);
    assert_eq!(s.tests[1].duplicate_of, Some(0));
    assert_eq!(s.tests[1].score, 0.0);
    assert!(s.tests[2].runs.is_empty());
    let t3 = &s.tests[3];
    assert_eq!(t3.runs[0].points, 1, "{:?}", t3.runs);
    // Box x -11 .. -9, path at x = -7.8 from t = 1 s: 1.2 m (the first bin averages in the origin sample,
    // which only moves that bin away from the box).
    assert!(
        (t3.runs[0].min_distance - 1.2).abs() < 1e-5,
        "{}",
        t3.runs[0].min_distance
    );
    assert!((t3.runs[0].flight_time_s - 120.0).abs() < 1e-9);
    // The 2026 edition measures from the path buffered by half the vehicle width: 0.125 m closer.
    let s26 = score_folder(d, Judge::E2026).unwrap();
    assert!((s26.tests[3].runs[0].min_distance - 1.075).abs() < 1e-5);
    assert_eq!(s.evaluated, 3);
    assert_eq!(s.failing, 2);
    assert!((s.failure_score - (t0.score + t3.score)).abs() < 1e-9);
}

#[test]
fn score_cli_json_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    write_test(dir.path(), 0, vec![Obstacle::new(2.0, 2.0, 20.0, 4.0, 25.0, 0.0)]);
    std::fs::write(dir.path().join("test_0.csv"), csv_flight(2.5, 60.0)).unwrap();
    let (code, out, err) = prgenuav(&["score", dir.path().to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["failing"], 1);
    assert_eq!(j["tests"][0]["runs"][0]["points"], 2);
    let empty = tempfile::tempdir().unwrap();
    let (code, _, err) = prgenuav(&["score", empty.path().to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("no test_N.yaml"), "{err}");
    std::fs::write(dir.path().join("test_0.csv"), "timestamp,x\n1,2\n").unwrap();
    let (code, _, err) = prgenuav(&["score", dir.path().to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("test_0.csv"), "{err}");
}

#[test]
fn score_json_names_its_files_by_absolute_paths() {
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("suite");
    std::fs::create_dir(&suite).unwrap();
    super::anywhere::copy_missions(dir.path());
    write_test(&suite, 0, vec![Obstacle::new(2.0, 2.0, 20.0, 4.0, 25.0, 0.0)]);
    write_test(&suite, 1, vec![Obstacle::new(2.0, 2.0, 20.0, -4.0, 25.0, 0.0)]);
    std::fs::write(suite.join("test_0.csv"), csv_flight(2.5, 60.0)).unwrap();
    std::fs::write(suite.join("test_1.csv"), csv_flight(-2.5, 60.0)).unwrap();
    let args = ["score", "suite", "--json", "--averages", "averages"];
    let (code, out, err) = super::anywhere::prgenuav_in(dir.path(), &args);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let e = &j["evaluation_2026"];
    let t = &e["tests"][0];
    super::anywhere::assert_absolute_files(&[
        &t["test"],
        &t["runs"][0]["trajectory"],
        &t["average_trajectory"],
        &e["pairs"][0]["a"],
        &e["pairs"][0]["b"],
    ]);
}

/// A flight whose first row is 0 and the rest epoch microseconds, as a log stitched from two clocks.
fn mixed_clock_flight() -> String {
    let mut s = String::from("timestamp,x,y,z,r\n0,0,0,0,\n");
    for i in 0..100 {
        s += &format!("{},0,{},10,\n", 1_700_000_000_000_000u64 + i * 100_000, i as f64 / 10.0);
    }
    s
}

#[test]
fn flights_with_absurd_clocks_are_refused_at_once_naming_the_row() {
    let dir = tempfile::tempdir().unwrap();
    write_test(dir.path(), 0, vec![Obstacle::new(2.0, 2.0, 20.0, 4.0, 25.0, 0.0)]);
    let test = dir.path().join("test_0.yaml");
    for (csv, line) in [
        (
            "timestamp,x,y,z,r\n0,0,0,0,\n1000000000000000000,0,0,10,\n".to_string(),
            ":3",
        ),
        (mixed_clock_flight(), ":3"),
        (
            "timestamp,x,y,z,r\n0,0,0,0,\n2000000,0,0,10,\n1000000,0,0,10,\n".to_string(),
            ":4",
        ),
    ] {
        std::fs::write(dir.path().join("test_0.csv"), &csv).unwrap();
        let flight = dir.path().join("test_0.csv");
        let clock = std::time::Instant::now();
        let (code, _, err) = prgenuav(&["distance", test.to_str().unwrap(), flight.to_str().unwrap()]);
        let (score_code, _, score_err) = prgenuav(&["score", dir.path().to_str().unwrap()]);
        assert!(clock.elapsed().as_secs() < 5, "{:?}", clock.elapsed());
        assert_eq!((code, score_code), (2, 2), "{err} / {score_err}");
        for e in [&err, &score_err] {
            assert!(
                e.contains(&format!("test_0.csv{line}")) && !e.contains("panicked"),
                "{e}"
            );
        }
    }
}

#[test]
fn a_ulog_pausing_over_an_hour_is_refused_naming_the_sample() {
    let bytes = ULogWriter::new()
        .local_position_format()
        .sample(1_000_000, 0.0, 0.0, -0.0, 0.5)
        .sample(1_500_000, 1.0, 2.0, -3.0, 0.6)
        .sample(1_000_000_000_000_000_000, 1.0, 2.0, -3.0, 0.6)
        .finish();
    let (_d, path) = super::temp_file("f.ulg", &bytes);
    let e = load_ulog_trajectory(&path).unwrap_err().to_string();
    assert!(
        e.contains("f.ulg") && e.contains("sample 3") && e.contains("at most 3600 s"),
        "{e}"
    );
}

#[test]
fn a_px4_flight_over_a_low_box_is_judged_0_m_and_said_to_be_above_its_top() {
    // A competitor's 10.19 m box under the 10 m flight, flown by PX4 v1.14 SIH with our planner.
    let case_file = super::repo().join("tests/data/hfs-flights/case_gulicatta_005.json");
    let case_json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(case_file).unwrap()).unwrap();
    let boxes: Vec<Obstacle> = (case_json["obstacles"].as_array().unwrap().iter())
        .map(|o| {
            let f = |k: &str| o[k].as_f64().unwrap();
            Obstacle::new(f("l"), f("w"), f("h"), f("x"), f("y"), f("r"))
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    case(1)
        .with_obstacles(boxes)
        .save(&dir.path().join("test_0.yaml"), Spelling::Old)
        .unwrap();
    let flight = super::repo().join("tests/data/px4-flights/traj/case_gulicatta_005.csv");
    std::fs::copy(flight, dir.path().join("test_0-0.csv")).unwrap();
    let (code, out, err) = prgenuav(&["score", dir.path().to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("1 run(s) came closest to a box above its top (the lowest 3.30 m above)"),
        "{out}"
    );
    let (_, out, _) = prgenuav(&["score", dir.path().to_str().unwrap(), "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let run = &j["evaluation_2026"]["tests"][0]["runs"][0];
    assert_eq!(
        (run["min_distance"].as_f64(), run["points"].as_u64()),
        (Some(0.0), Some(5))
    );
    assert_eq!(run["above_top"]["obstacle"], 1);
}
