//! `score` on the folders a user hands it: averages asked into the folder scored, flights of a moment, a
//! folder without flights, one test alone, the 2025 judge, and a CSV written by a spreadsheet.

use std::path::Path;

use prgenuav::model::{Obstacle, Spelling, Trajectory};

use super::{case, prgenuav};

fn write_test(dir: &Path, i: usize, obstacles: Vec<Obstacle>) {
    case(2)
        .with_obstacles(obstacles)
        .save(&dir.join(format!("test_{i}.yaml")), Spelling::Old)
        .unwrap();
}

/// A flight north along `x`, 10 m up, `secs` long, `n` samples, as an Aerialist CSV.
fn csv_flight(x: f64, secs: f64, n: u32) -> String {
    let mut s = String::from("timestamp,x,y,z,r\n0,0,0,0,\n");
    for i in 1..=n {
        let t = secs * f64::from(i) / f64::from(n);
        s += &format!("{},{x},{},10,\n", (t * 1e6) as i64, 50.0 * f64::from(i) / f64::from(n));
    }
    s
}

fn near_box() -> Obstacle {
    Obstacle::new(2.0, 2.0, 20.0, 4.0, 25.0, 0.0)
}

fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    files.sort();
    files
}

#[test]
fn averages_asked_into_the_scored_folder_are_refused_and_averages_never_run_back_in_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_test(d, 0, vec![near_box()]);
    std::fs::write(d.join("test_0-1.csv"), csv_flight(2.5, 60.0, 100)).unwrap();
    std::fs::write(d.join("test_0-2.csv"), csv_flight(2.0, 150.0, 300)).unwrap();
    write_test(d, 1, vec![Obstacle::new(2.0, 2.0, 20.0, -20.0, 25.0, 0.0)]);
    std::fs::write(d.join("test_1.csv"), csv_flight(-18.0, 40.0, 80)).unwrap();
    let before = snapshot(d);
    let (code, _, err) = prgenuav(&["score", d.to_str().unwrap(), "--averages", d.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("the folder scored") && err.contains("averages"), "{err}");
    assert_eq!(snapshot(d), before, "no flight replaced, no file added");
    let avg = d.join("averages");
    let (code, _, err) = prgenuav(&["score", d.to_str().unwrap(), "--averages", avg.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    for f in ["test_0.csv", "test_1.csv"] {
        Trajectory::load_csv(&avg.join(f)).unwrap_or_else(|e| panic!("{e}"));
    }
    assert_eq!(prgenuav(&["score", d.to_str().unwrap()]).0, 0);
}

#[test]
fn a_flight_of_a_moment_is_refused_naming_the_file_and_the_rule() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_test(d, 0, vec![near_box()]);
    std::fs::write(
        d.join("test_0.csv"),
        "timestamp,x,y,z,r\n0,2.5,25,10,\n1,2.5,25.1,10,\n",
    )
    .unwrap();
    let (code, out, err) = prgenuav(&["score", d.to_str().unwrap()]);
    assert_eq!(code, 2, "{out}{err}");
    assert!(err.contains("test_0.csv") && err.contains("shorter than 10 s"), "{err}");
}

#[test]
fn a_folder_without_flights_is_an_error_and_one_test_has_no_pair() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_test(d, 0, vec![near_box()]);
    let (code, out, err) = prgenuav(&["score", d.to_str().unwrap()]);
    assert_ne!(code, 0, "{out}");
    assert!(err.contains("nothing to score") && err.contains("1 test"), "{err}");
    // One test with a flight, written by a spreadsheet (a byte-order mark first).
    std::fs::write(d.join("test_0.csv"), format!("\u{feff}{}", csv_flight(2.5, 60.0, 100))).unwrap();
    let (code, out, err) = prgenuav(&["score", d.to_str().unwrap(), "--judge", "2025"]);
    assert_eq!(code, 0, "{err}");
    let line = out
        .lines()
        .find(|l| l.contains("final score"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(line.contains("judge 2025") && !line.starts_with("2026:"), "{line}");
    assert!(line.contains("no pair to compare") && !line.contains("n/a m"), "{line}");
}
