use super::*;
use crate::campaign::ground::flight_status::FlightStatus;
use crate::model::Obstacle;

fn settings(template: &str, folder: &Path, timeout_ms: u64) -> RunnerSettings {
    RunnerSettings {
        template: Template::parse(template).unwrap(),
        timeout: Duration::from_millis(timeout_ms),
        judge: Judge::E2026,
        spelling: Spelling::New,
        campaign_folder: folder.to_path_buf(),
        cancel: None,
    }
}

fn test_case() -> TestCase {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
    TestCase::load(&path)
        .unwrap()
        .with_obstacles(vec![Obstacle::new(2.0, 2.0, 20.0, 20.0, 3.0, 0.0)])
}

fn fly(template: &str, timeout_ms: u64) -> (tempfile::TempDir, Result<Flown, VehicleError>, RunnerVehicle) {
    let tmp = tempfile::tempdir().unwrap();
    let mut v = RunnerVehicle::new(0, Arc::new(settings(template, tmp.path(), timeout_ms)));
    let csv = tmp.path().join("flights/candidate_7.csv");
    let r = v.fly(&test_case(), &csv, &AtomicBool::new(false));
    (tmp, r, v)
}

#[test]
fn a_job_leaving_a_trajectory_is_a_judged_flight() {
    let (tmp, r, v) = fly(
        "test -f {test} && printf 'timestamp,x,y,z,r\\n0,0,0,5,\\n1000000,40,0,5,\\n' > {dir}/out.csv",
        10_000,
    );
    let f = r.unwrap();
    assert_eq!(f.status, FlightStatus::LANDED, "{f:?}");
    assert!(f.min_distance.is_some());
    assert_eq!(v.name(), "runner#0");
    let csv = std::fs::read_to_string(tmp.path().join("flights/candidate_7.csv")).unwrap();
    assert!(csv.starts_with("timestamp,x,y,z,r\n0,"), "{csv}");
    let command = std::fs::read_to_string(tmp.path().join("jobs/candidate_7").join(COMMAND_FILE)).unwrap();
    assert!(command.contains("jobs/candidate_7/test.yaml"), "{command}");
}

#[test]
fn a_failing_job_is_retried_once_then_backend_failed_with_its_stderr() {
    let (tmp, r, _) = fly(
        "echo \"no docker daemon\" >&2; echo {id} >> ../ids; exit 7; : {test}",
        10_000,
    );
    let f = r.unwrap();
    assert_eq!(f.status, FlightStatus::BackendFailed);
    let reason = f.reason.unwrap();
    assert!(
        reason.contains("attempt 1: exited with code 7") && reason.contains("attempt 2"),
        "{reason}"
    );
    assert!(reason.contains("no docker daemon"), "{reason}");
    // Two runs, two ids; the first attempt's folder kept aside.
    let ids = std::fs::read_to_string(tmp.path().join("jobs/ids")).unwrap();
    let ids: Vec<&str> = ids.lines().collect();
    assert_eq!(ids.len(), 2);
    assert!(ids[0].ends_with("-7-1") && ids[1].ends_with("-7-2"), "{ids:?}");
    assert!(tmp.path().join("jobs/candidate_7.attempt1").is_dir());
}

#[test]
fn a_job_that_leaves_nothing_or_hangs_fails_clearly() {
    let (_t, r, _) = fly("true {test}", 10_000);
    let reason = r.unwrap().reason.unwrap();
    assert!(reason.contains("no trajectory"), "{reason}");
    let (_t, r, _) = fly("sleep 20; : {test}", 200);
    let reason = r.unwrap().reason.unwrap();
    assert!(reason.contains("timed out after"), "{reason}");
}

#[test]
fn a_broken_runner_is_dropped_after_failing_flights_in_a_row() {
    let tmp = tempfile::tempdir().unwrap();
    let mut v = RunnerVehicle::new(1, Arc::new(settings("exit 1 {test}", tmp.path(), 5000)));
    let no = AtomicBool::new(false);
    for n in 0..crate::campaign::fly::retry::IN_A_ROW_TO_DROP {
        let csv = tmp.path().join(format!("flights/candidate_{n}.csv"));
        let r = v.fly(&test_case(), &csv, &no);
        if n + 1 < crate::campaign::fly::retry::IN_A_ROW_TO_DROP {
            assert_eq!(r.unwrap().status, FlightStatus::BackendFailed);
        } else {
            let e = r.unwrap_err().to_string();
            assert!(e.contains("runner#1") && e.contains("in a row"), "{e}");
        }
    }
}

#[test]
fn a_stopped_campaign_stops_the_job() {
    let tmp = tempfile::tempdir().unwrap();
    let mut v = RunnerVehicle::new(0, Arc::new(settings("sleep 30; : {test}", tmp.path(), 60_000)));
    let r = v.fly(&test_case(), &tmp.path().join("c.csv"), &AtomicBool::new(true));
    assert_eq!(r.unwrap().status, FlightStatus::ABORTED);
}

#[test]
fn a_job_stopped_or_timed_out_is_cancelled_in_its_engine_by_its_id() {
    let tmp = tempfile::tempdir().unwrap();
    let cancel = Template::parse_cancel("echo {id} >> ../../cancelled").unwrap();
    let with_cancel = |template: &str, timeout_ms| RunnerSettings {
        cancel: Some(cancel.clone()),
        ..settings(template, tmp.path(), timeout_ms)
    };
    let mut v = RunnerVehicle::new(0, Arc::new(with_cancel("sleep 30; : {test}", 60_000)));
    let stop = Arc::new(AtomicBool::new(false));
    let raise = stop.clone();
    let t = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(300));
        raise.store(true, std::sync::atomic::Ordering::SeqCst);
    });
    let f = v
        .fly(&test_case(), &tmp.path().join("flights/candidate_3.csv"), &stop)
        .unwrap();
    t.join().unwrap();
    assert_eq!(f.status, FlightStatus::ABORTED);
    let reason = f.reason.unwrap();
    assert!(reason.contains("asked the engine to cancel it"), "{reason}");
    let ids = std::fs::read_to_string(tmp.path().join("cancelled")).unwrap();
    assert_eq!(ids, format!("{}\n", job_id(tmp.path(), "candidate_3", 1)));
    // Past its time limit, each attempt's job is cancelled under its own id.
    std::fs::remove_file(tmp.path().join("cancelled")).unwrap();
    let mut v = RunnerVehicle::new(0, Arc::new(with_cancel("sleep 30; : {test}", 200)));
    let f = v.fly(
        &test_case(),
        &tmp.path().join("flights/candidate_4.csv"),
        &AtomicBool::new(false),
    );
    assert_eq!(f.unwrap().status, FlightStatus::BackendFailed);
    let ids = std::fs::read_to_string(tmp.path().join("cancelled")).unwrap();
    let want: Vec<String> = (1..=2).map(|n| job_id(tmp.path(), "candidate_4", n)).collect();
    assert_eq!(ids.lines().collect::<Vec<_>>(), want);
}

#[test]
fn a_job_whose_command_failed_is_cancelled_in_its_engine_before_the_retry() {
    let tmp = tempfile::tempdir().unwrap();
    let settings = RunnerSettings {
        cancel: Some(Template::parse_cancel("echo {id} >> ../../cancelled").unwrap()),
        ..settings("echo lost the controller >&2; exit 1; : {test}", tmp.path(), 60_000)
    };
    let mut v = RunnerVehicle::new(0, Arc::new(settings));
    let f = v.fly(
        &test_case(),
        &tmp.path().join("flights/candidate_5.csv"),
        &AtomicBool::new(false),
    );
    let f = f.unwrap();
    assert_eq!(f.status, FlightStatus::BackendFailed);
    let reason = f.reason.unwrap();
    assert!(reason.contains("asked the engine to cancel it"), "{reason}");
    let ids = std::fs::read_to_string(tmp.path().join("cancelled")).unwrap();
    let want: Vec<String> = (1..=2).map(|n| job_id(tmp.path(), "candidate_5", n)).collect();
    assert_eq!(ids.lines().collect::<Vec<_>>(), want);
}

#[test]
fn no_job_slots_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let e = RunnerVehicle::fleet(settings("x {test}", tmp.path(), 1), 0)
        .err()
        .unwrap();
    assert!(e.contains("--jobs"));
    assert_eq!(
        RunnerVehicle::fleet(settings("x {test}", tmp.path(), 1), 3)
            .unwrap()
            .len(),
        3
    );
}

#[test]
fn job_ids_are_names_slurm_and_kubernetes_accept() {
    let id = job_id(Path::new("/runs/generated_tests/26-11-2026_10-00"), "candidate_12", 2);
    assert!(id.starts_with("prg-") && id.ends_with("-12-2"), "{id}");
    assert!(
        id.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
    );
    assert_ne!(id, job_id(Path::new("/other"), "candidate_12", 2));
}

#[test]
fn a_re_flight_and_another_candidate_get_different_ids_of_kubernetes_length() {
    let folder = Path::new("/runs/generated_tests/26-11-2026_10-00");
    let (a, b) = (job_id(folder, "candidate_1_2", 1), job_id(folder, "candidate_12", 1));
    assert_ne!(a, b);
    assert!(a.ends_with("-1-2-1") && b.ends_with("-12-1"), "{a} {b}");
    let long = job_id(folder, &format!("candidate_{}", "9".repeat(200)), 2);
    assert!(long.len() <= 63, "{long}");
    assert!(long.ends_with(|c: char| c.is_ascii_alphanumeric()), "{long}");
}
