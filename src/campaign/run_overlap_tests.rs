//! The learning campaign with `overlap`: each round planned while the previous one flies.

use super::*;

/// The scripted LFS, counting the candidates it screened.
struct CountingLfs(Arc<AtomicUsize>);

impl Screener for CountingLfs {
    fn screen(&self, test: &TestCase) -> Screened {
        self.0.fetch_add(1, Ordering::SeqCst);
        ScriptedLfs.screen(test)
    }
}

/// The scripted vehicle; its first flight lasts until the LFS has screened more than `first_round` candidates
/// (at most 10 s), and says whether that happened while it flew.
struct OverlapProbe {
    inner: ScriptedVehicle,
    screened: Arc<AtomicUsize>,
    first_round: usize,
    overlapped: Arc<Mutex<Option<bool>>>,
}

impl Vehicle for OverlapProbe {
    fn name(&self) -> String {
        self.inner.name()
    }
    fn fly(&mut self, test: &TestCase, csv: &Path, cancel: &AtomicBool) -> Result<Flown, VehicleError> {
        let mut seen = self.overlapped.lock().unwrap();
        if seen.is_none() {
            let t0 = std::time::Instant::now();
            while self.screened.load(Ordering::SeqCst) <= self.first_round && t0.elapsed().as_secs() < 10 {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            *seen = Some(self.screened.load(Ordering::SeqCst) > self.first_round);
        }
        drop(seen);
        self.inner.fly(test, csv, cancel)
    }
}

#[test]
fn with_overlap_the_next_round_is_screened_while_a_round_flies_and_the_budget_is_flown_once() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = {
        let mut c = adapted(16);
        c.flight.overlap = true;
        c
    };
    let screened = Arc::new(AtomicUsize::new(0));
    let overlapped = Arc::new(Mutex::new(None));
    let flown = Arc::new(Mutex::new(Vec::new()));
    let probe = OverlapProbe {
        inner: ScriptedVehicle {
            flown: flown.clone(),
            stop_after: None,
            count: Arc::new(AtomicUsize::new(0)),
            extra_m: 0.2,
        },
        screened: screened.clone(),
        first_round: cfg.screening.candidates / crate::campaign::conductor::ROUNDS,
        overlapped: overlapped.clone(),
    };
    let lfs = CountingLfs(screened);
    let r = run_campaign_with(
        &cfg,
        dir.path(),
        &lfs,
        vec![Box::new(probe)],
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(
        *overlapped.lock().unwrap(),
        Some(true),
        "round 2 was screened while round 1 flew"
    );
    assert_eq!(r.suite.flown, 16);
    let journal = Journal::read(&dir.path().join("journal.jsonl")).unwrap();
    let mut seen: Vec<u64> = journal.iter().map(|j| j.candidate.0).collect();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen.len(), 16, "no candidate flown twice");
    let learnt = r.learning.expect("a learning campaign");
    // One round of lag: the second round was planned before the first one's flights were learnt from.
    assert_eq!(learnt.rounds[1].bias_m, 0.0, "{:?}", learnt.rounds[1]);
    assert!(learnt.rounds[2].bias_m > 0.0, "{:?}", learnt.rounds[2]);
    assert!(r.stages.vehicle_span_s >= r.stages.vehicle_busy_s && r.stages.vehicle_busy_s > 0.0);
}

#[test]
fn without_overlap_each_round_is_planned_after_the_previous_one_landed() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let r = run_scripted(&adapted(16), dir.path(), &flown);
    let learnt = r.learning.expect("a learning campaign");
    assert!(learnt.rounds[1].bias_m > 0.0, "{:?}", learnt.rounds[1]);
    assert_eq!(r.suite.flown, 16);
}
