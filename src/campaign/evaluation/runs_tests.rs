use super::*;
use crate::campaign::store::journal::test_record;
use crate::model::Sample;

fn tests() -> Vec<(PathBuf, TestCase)> {
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
    vec![(PathBuf::from("test_0.yaml"), TestCase::load(&case).unwrap())]
}

fn record(attempt: u32, trajectory: &str) -> FlightRecord {
    FlightRecord {
        attempt,
        trajectory: trajectory.into(),
        ..test_record(0, 1.0, Some(2.0))
    }
}

fn write_flight(folder: &Path, name: &str, secs: f64) {
    let samples = (0..=10)
        .map(|i| Sample {
            t_s: secs * f64::from(i) / 10.0,
            x: f64::from(i),
            y: 0.0,
            z: 10.0,
            r: None,
        })
        .collect();
    let path = folder.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, Trajectory::new(samples).to_csv()).unwrap();
}

#[test]
fn a_run_whose_flight_left_nothing_is_flown_again_as_its_next_flight() {
    let dir = tempfile::tempdir().unwrap();
    let records = [(1, record(0, "flights/candidate_0.csv"))];
    let runs = read_runs(&tests(), &records, dir.path(), 1);
    let run = &runs[0];
    assert!(run.judged.is_none() && run.flies_again());
    assert!(
        run.unjudged[0].why.contains("candidate_0.csv"),
        "{}",
        run.unjudged[0].why
    );
    assert_eq!(run.job(&tests()[0].1).tally.next_attempt, 1);
    // Its next flight is judged.
    write_flight(dir.path(), "flights/candidate_0_2.csv", 60.0);
    let records = [(1, records[0].1.clone()), (2, record(1, "flights/candidate_0_2.csv"))];
    let runs = read_runs(&tests(), &records, dir.path(), 1);
    assert!(runs[0].judged.is_some() && !runs[0].flies_again());
}

#[test]
fn a_record_of_a_moment_is_not_judged() {
    let dir = tempfile::tempdir().unwrap();
    write_flight(dir.path(), "flights/candidate_0.csv", 1e-6);
    let runs = read_runs(&tests(), &[(1, record(0, "flights/candidate_0.csv"))], dir.path(), 1);
    assert!(runs[0].judged.is_none());
    assert!(
        runs[0].unjudged[0].why.contains("shorter than 10 s"),
        "{}",
        runs[0].unjudged[0].why
    );
}

#[test]
fn after_its_last_try_a_run_says_exactly_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let records: Vec<(usize, FlightRecord)> = (0..MAX_TRIES as u32).map(|a| (a as usize + 4, record(a, ""))).collect();
    let runs = read_runs(&tests(), &records, dir.path(), 1);
    assert!(!runs[0].flies_again());
    let said = runs[0]
        .stuck(Path::new("test_0.yaml"), Path::new("evaluation/journal.jsonl"))
        .unwrap();
    assert!(
        said.contains("its 3 flights all left nothing to judge")
            && said.contains("delete lines 4, 5, 6 of evaluation/journal.jsonl")
            && said.contains("no trajectory was recorded"),
        "{said}"
    );
}
