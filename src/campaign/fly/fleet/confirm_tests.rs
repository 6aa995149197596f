//! Confirmation in the fleet: a failing test flown again before the next candidate, within the budget.

use crate::campaign::ground::flight_status::FlightStatus;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

use super::tests::jobs;
use super::*;
use crate::campaign::fly::vehicle::*;
use crate::campaign::store::journal::Journal;
use crate::model::TestCase;

/// Flies candidate `i`'s `n`th flight to `script[i][n]` metres (repeating the last), logging (candidate,
/// csv file name).
struct Scripted {
    script: Vec<Vec<f64>>,
    flown: Arc<Mutex<Vec<(u64, String)>>>,
}

impl Vehicle for Scripted {
    fn name(&self) -> String {
        "scripted".into()
    }
    fn fly(&mut self, test: &TestCase, csv: &Path, _c: &AtomicBool) -> Result<Flown, VehicleError> {
        let id = test.obstacles[0].position.x as u64;
        let mut flown = self.flown.lock().unwrap();
        let n = flown.iter().filter(|f| f.0 == id).count();
        let file = csv.file_name().unwrap().to_string_lossy().into_owned();
        flown.push((id, file));
        let script = &self.script[id as usize];
        let d = script[n.min(script.len() - 1)];
        Ok(Flown {
            status: FlightStatus::LANDED,
            min_distance: Some(d),
            min_distance_raw: Some(d),
            flight_time_s: 40.0,
            warnings: Vec::new(),
            reason: None,
            closest_centre_m: None,
            inside_cp_dist: None,
        })
    }
}

/// The journal's (candidate, attempt, failed) and the flights made as (candidate, csv file name).
type Run = (Vec<(u64, u32, bool)>, Vec<(u64, String)>);

/// `jobs` confirmed over `k` flights on one scripted vehicle within `budget`.
fn confirm_run(script: Vec<Vec<f64>>, k: usize, budget: usize) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let mut fleet: Vec<Box<dyn Vehicle>> = vec![Box::new(Scripted {
        script: script.clone(),
        flown: flown.clone(),
    })];
    let jobs = jobs(script.len() as u64)
        .into_iter()
        .map(|j| Job { confirm: k, ..j })
        .collect();
    let path = dir.path().join("journal.jsonl");
    let out = fly_all(
        &mut fleet,
        jobs,
        budget,
        dir.path(),
        &mut Journal::load(&path).unwrap().0,
        &AtomicBool::new(false),
        &|_| {},
    );
    let records = Journal::read(&path).unwrap();
    assert_eq!(out.records, records);
    let got = (records.iter())
        .map(|r| (r.candidate.0, r.attempt, r.flown.min_distance.unwrap() < 1.5))
        .collect();
    let flown = flown.lock().unwrap().clone();
    (got, flown)
}

#[test]
fn a_failing_test_is_flown_again_before_the_next_candidate_until_its_majority_is_settled() {
    // Candidate 0 fails then passes twice (1 of 3), 1 fails twice (settled at 2), 2 passes, 3 alternates.
    let script = vec![vec![1.0, 2.0, 2.0], vec![1.0, 1.2], vec![2.0], vec![1.0, 2.0, 1.0]];
    let (journal, flown) = confirm_run(script.clone(), 3, 20);
    let (f, p) = (true, false);
    assert_eq!(
        journal,
        [
            (0, 0, f),
            (0, 1, p),
            (0, 2, p),
            (1, 0, f),
            (1, 1, f),
            (2, 0, p),
            (3, 0, f),
            (3, 1, p),
            (3, 2, f),
        ]
    );
    let files: Vec<&str> = flown.iter().take(3).map(|f| f.1.as_str()).collect();
    assert_eq!(files, ["candidate_0.csv", "candidate_0_2.csv", "candidate_0_3.csv"]);
    // The re-flights are charged to the budget: 5 flights reach candidate 2 only by skipping nothing.
    let (journal, _) = confirm_run(script.clone(), 3, 5);
    assert_eq!(journal.len(), 5);
    assert_eq!(
        journal.last(),
        Some(&(1, 1, f)),
        "candidate 1 confirmed before 2 is drawn"
    );
    // K = 1: every candidate once, as without confirmation.
    let (journal, _) = confirm_run(script, 1, 20);
    assert_eq!(
        journal.iter().map(|j| (j.0, j.1)).collect::<Vec<_>>(),
        [(0, 0), (1, 0), (2, 0), (3, 0)]
    );
}

/// As [`Scripted`], each flight taking a random few milliseconds from `rng`: which vehicle lands first varies.
struct Jittery {
    inner: Scripted,
    rng: rand_chacha::ChaCha8Rng,
}

impl Vehicle for Jittery {
    fn name(&self) -> String {
        "jittery".into()
    }
    fn fly(&mut self, test: &TestCase, csv: &Path, c: &AtomicBool) -> Result<Flown, VehicleError> {
        use rand::Rng;
        std::thread::sleep(std::time::Duration::from_millis(self.rng.random_range(0..15)));
        self.inner.fly(test, csv, c)
    }
}

/// Two jittery vehicles flying in waves: the round's records as `wait_round` hands them back.
fn waves_run(script: &[Vec<f64>], jitter_seed: u64, budget: usize) -> Vec<(u64, u32, f64)> {
    use rand::SeedableRng;
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let mut fleet: Vec<Box<dyn Vehicle>> = (0..2)
        .map(|i| {
            Box::new(Jittery {
                inner: Scripted {
                    script: script.to_vec(),
                    flown: flown.clone(),
                },
                rng: rand_chacha::ChaCha8Rng::seed_from_u64(jitter_seed * 2 + i),
            }) as Box<dyn Vehicle>
        })
        .collect();
    let jobs: Vec<Job> = (jobs(script.len() as u64).into_iter())
        .map(|j| Job { confirm: 3, ..j })
        .collect();
    let setup = crate::campaign::fly::fleet::FleetSetup {
        folder: dir.path(),
        journal: &mut Journal::load(&dir.path().join("journal.jsonl")).unwrap().0,
        cancel: &AtomicBool::new(false),
        on_flight: &|_| {},
        waves: true,
        replay: crate::campaign::fly::fleet::replay::Replay::none(),
    };
    let (records, _) = crate::campaign::fly::fleet::run_fleet(&mut fleet, setup, |fleet| {
        fleet.push(0, jobs, budget);
        fleet.wait_round(0)
    });
    (records.iter())
        .map(|r| (r.candidate.0, r.attempt, r.flown.min_distance.unwrap()))
        .collect()
}

#[test]
fn in_waves_the_same_jobs_fly_the_same_flights_whoever_lands_first() {
    // Failures to confirm, refuted ones and passes, with a budget that cuts the last confirmations short.
    let script: Vec<Vec<f64>> = (0..12)
        .map(|i| match i % 4 {
            0 => vec![1.0, 2.0, 1.1],
            1 => vec![1.2, 1.3],
            2 => vec![2.0],
            _ => vec![1.4, 2.2, 2.3],
        })
        .collect();
    let first = waves_run(&script, 0, 20);
    assert_eq!(first.len(), 20);
    assert!(first.iter().any(|f| f.1 == 2), "some tests were flown a third time");
    for jitter in 1..6 {
        assert_eq!(waves_run(&script, jitter, 20), first, "jitter seed {jitter}");
    }
}
