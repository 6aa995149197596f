//! Confirmed failures (`--confirm`) through the whole campaign, static and learning, with a vehicle whose
//! repeated flights differ: an even candidate that failed passes when flown again, an odd one fails again.

use crate::campaign::ground::flight_status::FlightStatus;
use std::collections::BTreeMap;

use super::*;
use crate::campaign::store::journal::FlightRecord;

/// The candidate and flight number of a trajectory file `candidate_N.csv` / `candidate_N_K.csv`.
fn flight_of(csv: &Path) -> (u64, u32) {
    let stem = csv.file_stem().unwrap().to_string_lossy();
    let mut parts = stem.trim_start_matches("candidate_").split('_');
    let candidate = parts.next().unwrap().parse().unwrap();
    let attempt = parts.next().map_or(0, |k| k.parse::<u32>().unwrap() - 1);
    (candidate, attempt)
}

/// Flies as [`ScriptedVehicle`]; a later flight of an even candidate passes by 2 m. Cancels the campaign
/// after the first failing flight when `stop_at_failure`.
struct Flaky {
    flown: Arc<Mutex<Vec<(u64, u32)>>>,
    stop_at_failure: bool,
}

impl Vehicle for Flaky {
    fn name(&self) -> String {
        "flaky".into()
    }
    fn fly(&mut self, test: &TestCase, csv: &Path, cancel: &AtomicBool) -> Result<Flown, VehicleError> {
        std::fs::write(csv, "timestamp,x,y,z,r\n0,0,0,0,\n1000000,0,10,10,\n").unwrap();
        let (candidate, attempt) = flight_of(csv);
        self.flown.lock().unwrap().push((candidate, attempt));
        let mut d = (test.obstacles[0].position.y - 20.0).abs() / 2.0 + 0.2;
        if attempt > 0 && candidate % 2 == 0 {
            d += 2.0;
        }
        if self.stop_at_failure && d < 1.5 {
            cancel.store(true, Ordering::SeqCst);
        }
        Ok(landed(d))
    }
}

fn flaky(flown: &Arc<Mutex<Vec<(u64, u32)>>>, stop_at_failure: bool) -> Vec<Box<dyn Vehicle>> {
    vec![Box::new(Flaky {
        flown: flown.clone(),
        stop_at_failure,
    })]
}

/// Every test's flights in the journal: (candidate, flights, failures), by candidate.
fn per_test(journal: &[FlightRecord]) -> Vec<(u64, usize, usize)> {
    let mut out: Vec<(u64, usize, usize)> = Vec::new();
    for r in journal {
        let fail = usize::from(r.flown.min_distance.unwrap() < 1.5);
        match out.iter_mut().find(|t| t.0 == r.candidate.0) {
            Some(t) => (t.1, t.2) = (t.1 + 1, t.2 + fail),
            None => out.push((r.candidate.0, 1, fail)),
        }
    }
    out.sort();
    out
}

/// What a finished confirmed campaign in `dir` must show, whatever its schedule.
fn check_confirmed(dir: &Path, r: &crate::campaign::run::Report, budget: usize) {
    let journal = Journal::read(&dir.join("journal.jsonl")).unwrap();
    assert_eq!(
        (journal.len(), r.suite.flown),
        (budget, budget),
        "re-flights are charged"
    );
    let tests = per_test(&journal);
    for &(c, flights, failures) in &tests {
        assert!(flights <= 3, "candidate {c} flown {flights} times");
        let expected = if failures == 0 {
            1
        } else if c % 2 == 0 {
            3 // fails, passes, passes: 1 of 3
        } else {
            2 // fails twice: settled
        };
        // Only the last tests flown may have been cut by the budget.
        assert!(
            flights == expected || journal.iter().rev().take(3).any(|x| x.candidate.0 == c),
            "{c}"
        );
    }
    // Written: every test expected to earn points, less near-duplicate trajectories (the fake vehicle flies
    // every test the same way); an odd candidate (2 of 2 failed) always earns.
    let earning = r.tests.iter().filter(|t| t.expected.is_some_and(|e| e.points.earns()));
    let near_duplicates = r.tests.iter().filter(|t| t.near_duplicate_of.is_some()).count();
    assert_eq!(r.suite.failing + near_duplicates, earning.count());
    let twice = r.tests.iter().filter(|t| t.failures == 2 && t.flights == 2);
    assert!(twice.clone().all(|t| t.candidate.0 % 2 == 1));
    assert!(twice.clone().all(|t| t.confirmed || t.near_duplicate_of.is_some()));
    assert_eq!(r.suite.failed_once, tests.iter().filter(|t| t.2 > 0).count());
    for i in 0..r.suite.failing {
        assert!(dir.join(format!("test_{i}.yaml")).is_file() && dir.join(format!("test_{i}-2.csv")).is_file());
    }
    assert!(!dir.join(format!("test_{}.yaml", r.suite.failing)).exists());
    let unconfirmed: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("unconfirmed.json")).unwrap()).unwrap();
    let unconfirmed = unconfirmed.as_array().unwrap();
    assert_eq!(unconfirmed.len(), r.suite.failed_once - r.suite.failing);
    // An odd candidate is unconfirmed only as a near-duplicate, or when the budget ran out before its second
    // flight.
    let pending = |t: &serde_json::Value| t["settled"] == false && t["flights"] == 1;
    let copy = |t: &serde_json::Value| !t["near_duplicate_of"].is_null();
    assert!(
        unconfirmed
            .iter()
            .all(|t| t["candidate"].as_u64().unwrap() % 2 == 0 || pending(t) || copy(t))
    );
    assert!(
        unconfirmed.iter().filter(|t| pending(t)).count() <= 1,
        "one vehicle: one test cut"
    );
    assert!(
        unconfirmed
            .iter()
            .all(|t| t["failure_rate_low"].as_f64() <= t["failure_rate"].as_f64())
    );
}

#[test]
fn a_test_failing_once_in_three_is_not_confirmed_and_re_flights_come_first() {
    for learn in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let flown = Arc::new(Mutex::new(Vec::new()));
        let cfg = {
            let mut c = if learn { adapted(14) } else { config(14) };
            c.flight.confirm = 3;
            c
        };
        let r = run_with(&cfg, dir.path(), flaky(&flown, false)).unwrap();
        check_confirmed(dir.path(), &r, 14);
        assert!(
            r.suite.failing > 0 && r.suite.failed_once > r.suite.failing,
            "learn {learn}"
        );
        assert_eq!(
            r.suite.confirmation_rate.unwrap(),
            r.suite.failed_again as f64 / r.suite.flown_again as f64
        );
        if learn {
            // The rounds learnt each test at its flights' mean: the even tests their repeats refuted are no
            // failures to learn from (and no parents of children).
            let learnt: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(dir.path().join("learnt.json")).unwrap()).unwrap();
            let journal = Journal::read(&dir.path().join("journal.jsonl")).unwrap();
            let mut means: BTreeMap<u64, (f64, f64)> = BTreeMap::new();
            for rec in &journal {
                let e = means.entry(rec.candidate.0).or_default();
                *e = (e.0 + rec.flown.min_distance.unwrap(), e.1 + 1.0);
            }
            let failing = means.values().filter(|(sum, n)| sum / n < 1.5).count();
            assert_eq!(
                learnt["failure_counts"]["total"]["failures"].as_u64(),
                Some(failing as u64)
            );
            assert!(failing < r.suite.failed_once, "some failures were refuted");
        }
        // One vehicle: a failing first flight is followed by the same test's next flight.
        let flown = flown.lock().unwrap().clone();
        let journal = Journal::read(&dir.path().join("journal.jsonl")).unwrap();
        for w in journal.windows(2) {
            if w[0].flown.min_distance.unwrap() < 1.5 && w[0].attempt == 0 {
                assert_eq!(
                    (w[1].candidate, w[1].attempt),
                    (w[0].candidate, 1),
                    "learn {learn}: {flown:?}"
                );
            }
        }
    }
}

#[test]
fn a_resumed_campaign_flies_the_pending_confirmation_first() {
    for learn in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let flown = Arc::new(Mutex::new(Vec::new()));
        let cfg = {
            let mut c = if learn { adapted(12) } else { config(12) };
            c.flight.confirm = 3;
            c
        };
        let cancel = AtomicBool::new(false);
        run_campaign_with(&cfg, dir.path(), &ScriptedLfs, flaky(&flown, true), &Quiet, &cancel).unwrap();
        let cut = Journal::read(&dir.path().join("journal.jsonl")).unwrap();
        let last = cut.last().unwrap();
        assert!(
            last.flown.min_distance.unwrap() < 1.5 && last.attempt == 0,
            "killed after a first failure"
        );
        let before = flown.lock().unwrap().len();
        let r = run_with(&cfg, dir.path(), flaky(&flown, false)).unwrap();
        let flown = flown.lock().unwrap().clone();
        assert_eq!(flown[before], (last.candidate.0, 1), "learn {learn}: {flown:?}");
        check_confirmed(dir.path(), &r, 12);
    }
}

#[test]
fn one_flight_per_test_writes_no_unconfirmed_list() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let r = run_with(&config(8), dir.path(), flaky(&flown, false)).unwrap();
    // Every test failed once; the fake vehicle flies them all the same way, so all but one are near-duplicates.
    let near_duplicates = r.tests.iter().filter(|t| t.near_duplicate_of.is_some()).count();
    assert_eq!(
        (r.suite.reflights, r.suite.failed_once),
        (0, r.suite.failing + near_duplicates)
    );
    assert_eq!(
        dir.path().join("unconfirmed.json").exists(),
        near_duplicates > 0,
        "listed only when a test was not written"
    );
    assert!(flown.lock().unwrap().iter().all(|f| f.1 == 0));
}

/// Every flight of a campaign's journal, sorted: (candidate, flight, distance in mm, status).
fn flights_in(dir: &Path) -> Vec<(u64, u32, i64, FlightStatus)> {
    let mut all: Vec<_> = Journal::read(&dir.join("journal.jsonl"))
        .unwrap()
        .into_iter()
        .map(|r| {
            let mm = (r.flown.min_distance.unwrap() * 1000.0).round() as i64;
            (r.candidate.0, r.attempt, mm, r.flown.status)
        })
        .collect();
    all.sort();
    all
}

/// A campaign folder as a `kill -9` after `records` leaves it: their journal lines and trajectories (copied
/// from the folder `whole`), nothing else.
fn killed_after(whole: &Path, records: &[FlightRecord]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("flights")).unwrap();
    let mut journal = Journal::open(&dir.path().join("journal.jsonl")).unwrap();
    for r in records {
        journal.append(r).unwrap();
        std::fs::copy(whole.join(&r.trajectory), dir.path().join(&r.trajectory)).unwrap();
    }
    dir
}

#[test]
fn a_learning_campaign_killed_after_any_flight_resumes_to_the_uninterrupted_end() {
    let cfg = {
        let mut c = adapted(16);
        c.flight.confirm = 3;
        c
    };
    let whole = tempfile::tempdir().unwrap();
    run_with(&cfg, whole.path(), flaky(&Arc::default(), false)).unwrap();
    let lines = Journal::read(&whole.path().join("journal.jsonl")).unwrap();
    let expected = flights_in(whole.path());
    assert!(expected.iter().any(|f| f.1 > 0), "the campaign confirms: {expected:?}");
    let learnt = std::fs::read_to_string(whole.path().join("learnt.json")).unwrap();
    for kept in 1..lines.len() {
        let dir = killed_after(whole.path(), &lines[..kept]);
        let flown = Arc::new(Mutex::new(Vec::new()));
        run_with(&cfg, dir.path(), flaky(&flown, false)).unwrap();
        assert_eq!(flights_in(dir.path()), expected, "killed after {kept} flights");
        assert_eq!(
            flown.lock().unwrap().len(),
            lines.len() - kept,
            "killed after {kept}: flew again"
        );
        let resumed = std::fs::read_to_string(dir.path().join("learnt.json")).unwrap();
        assert_eq!(resumed, learnt, "killed after {kept} flights: learnt otherwise");
    }
}

#[test]
fn a_resumed_campaign_that_plans_while_flying_keeps_every_journaled_flight_within_the_budget() {
    // Planning a round while the last one flies depends on timing, so the replayed plan may not ask for every
    // journaled flight: those are kept and counted, and the budget still holds.
    let cfg = {
        let mut c = adapted(16);
        c.flight.confirm = 3;
        c.flight.overlap = true;
        c
    };
    let whole = tempfile::tempdir().unwrap();
    run_with(&cfg, whole.path(), flaky(&Arc::default(), false)).unwrap();
    let lines = Journal::read(&whole.path().join("journal.jsonl")).unwrap();
    for kept in [1, 4, 9, 13] {
        let dir = killed_after(whole.path(), &lines[..kept]);
        let flown = Arc::new(Mutex::new(Vec::new()));
        let r = run_with(&cfg, dir.path(), flaky(&flown, false)).unwrap();
        let all = Journal::read(&dir.path().join("journal.jsonl")).unwrap();
        assert_eq!((all.len(), r.suite.flown), (16, 16), "killed after {kept}");
        assert_eq!(
            flown.lock().unwrap().len(),
            16 - kept,
            "killed after {kept}: flew again"
        );
        check_confirmed(dir.path(), &r, 16);
    }
}

#[test]
fn a_resume_whose_rounds_come_out_otherwise_keeps_the_journaled_flights_and_flies_no_index_twice() {
    let cfg = {
        let mut c = adapted(16);
        c.flight.confirm = 3;
        c
    };
    let whole = tempfile::tempdir().unwrap();
    run_with(&cfg, whole.path(), flaky(&Arc::default(), false)).unwrap();
    let journal = Journal::read(&whole.path().join("journal.jsonl")).unwrap();
    // The first flight journaled 5 m off what this vehicle flies: the replayed rounds learn otherwise and draw
    // other children, so later journaled candidates no longer match their draws.
    let kept = 12;
    let mut cut = journal[..kept].to_vec();
    cut[0].flown.min_distance = cut[0].flown.min_distance.map(|d| d + 5.0);
    let dir = killed_after(whole.path(), &cut);
    let flown = Arc::new(Mutex::new(Vec::new()));
    let r = run_with(&cfg, dir.path(), flaky(&flown, false)).unwrap();
    let all = Journal::read(&dir.path().join("journal.jsonl")).unwrap();
    assert_eq!((all.len(), r.suite.flown), (16, 16));
    assert_eq!(flown.lock().unwrap().len(), 16 - kept);
    let mut ids: Vec<(u64, u32)> = all.iter().map(|f| (f.candidate.0, f.attempt)).collect();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), 16, "a flight journaled twice");
}
