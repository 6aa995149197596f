//! The flight stage: the tests waiting for confirmation, then a ranking, as jobs for the fleet; the flights'
//! progress lines.

use std::collections::HashSet;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use crate::campaign::fly::confirm::pending;
use crate::campaign::fly::vehicle::Job;
use crate::campaign::ground::candidate::{Candidate, CandidateId, Pick};
use crate::campaign::ground::error::CampaignError;
use crate::campaign::ground::input::CampaignInput;
use crate::campaign::ground::screener::Progress;
use crate::campaign::store::journal::{FlightRecord, flights_charged};
use crate::model::TestCase;

/// What the flight stage reads.
pub struct FlightStage<'a> {
    /// The case study.
    pub case: &'a TestCase,
    /// Every candidate drawn so far, by index.
    pub candidates: &'a [Candidate],
    /// The campaign folder (journal, trajectories).
    pub folder: &'a Path,
    /// Progress output.
    pub progress: &'a dyn Progress,
    /// Stops the flights (vehicles in the air land).
    pub cancel: &'a AtomicBool,
    /// Every flight journaled before this stage: the tests among them whose confirmation is not settled are
    /// flown first.
    pub done: &'a [FlightRecord],
    /// Flights a failing test gets at most (`--confirm`).
    pub confirm: usize,
    /// Fly in waves, so repeatable vehicles repeat the campaign ([`crate::campaign::fly::fleet::FleetSetup::waves`]).
    pub waves: bool,
}

/// A fleet with no vehicle left stops the campaign in `folder`, keeping the flights journaled so far for
/// `--resume`: a campaign that lost every vehicle must not end as a clean run that found no failing test.
/// `dropped`: why each vehicle was dropped in this stage (none: in an earlier one).
pub fn no_vehicle_left(folder: &Path, dropped: &[String]) -> CampaignError {
    CampaignError::NoVehicle(format!(
        "{}; the flights so far are journaled: resume with  prgenuav generate --resume {}",
        if dropped.is_empty() {
            "every vehicle was dropped in an earlier stage".to_string()
        } else {
            dropped.join("; ")
        },
        folder.display()
    ))
}

/// Tells the user that the campaign resumes from the charged flights `done` of its `budget`, and `how` it
/// goes on with them.
pub fn note_resuming(progress: &dyn Progress, done: &[FlightRecord], budget: usize, how: &str) {
    if done.is_empty() {
        return;
    }
    let charged = flights_charged(done);
    progress.note(&format!(
        "resuming: {charged} flights already journaled, {} left in the budget{how}",
        budget.saturating_sub(charged)
    ));
}

impl<'a> FlightStage<'a> {
    /// The flight stage of the campaign `input` over `candidates`, after the journaled flights `done`.
    pub fn new(input: &CampaignInput<'a>, candidates: &'a [Candidate], done: &'a [FlightRecord]) -> Self {
        Self {
            case: input.case,
            candidates,
            folder: input.folder,
            progress: input.progress,
            cancel: input.cancel,
            done,
            confirm: input.cfg.flight.confirm,
            waves: input.cfg.repeatable_vehicles(),
        }
    }
}

/// The jobs of a flight stage: the tests waiting for confirmation (longest waiting first; those in `busy`, queued
/// or in the air already, left out), then `ranked` in order.
pub fn stage_jobs(ctx: &FlightStage, ranked: Vec<Pick>, busy: &[CandidateId]) -> Vec<Job> {
    let again = pending(ctx.done, ctx.confirm)
        .into_iter()
        .filter(|(_, first)| !busy.contains(&first.candidate))
        .map(|(tally, first)| Job {
            tally,
            confirm: ctx.confirm,
            ..Job::new(
                first.candidate,
                first.prediction.clone(),
                ctx.case.with_obstacles(first.obstacles.clone()),
            )
        });
    let fresh = ranked.into_iter().map(|pick| {
        let test = (ctx.case).with_obstacles(ctx.candidates[pick.candidate.index()].obstacles.clone());
        Job {
            confirm: ctx.confirm,
            ..Job::new(pick.candidate, pick.prediction, test)
        }
    });
    again.chain(fresh).collect()
}

/// Counts a campaign's flights for its progress lines: each flight's number in the campaign, and in the flight
/// stage under way (what the stage's progress counts to); and the flights' warnings said so far.
#[derive(Debug, Default)]
pub(in crate::campaign) struct FlightCount {
    total: AtomicUsize,
    stage_start: AtomicUsize,
    said: Mutex<HashSet<String>>,
}

/// A flight's numbers ([`FlightCount::next`]), with the count it came from.
pub(in crate::campaign) struct Numbered<'a> {
    n: usize,
    in_stage: usize,
    count: &'a FlightCount,
}

impl FlightCount {
    /// A flight stage starts after the flights counted so far.
    pub(in crate::campaign) fn new_stage(&self) {
        self.stage_start
            .store(self.total.load(Ordering::Relaxed), Ordering::Relaxed);
    }

    /// Counts one flight: its number in the campaign and in the stage, both from 1.
    pub(in crate::campaign) fn next(&self) -> Numbered<'_> {
        let n = self.total.fetch_add(1, Ordering::Relaxed) + 1;
        Numbered {
            n,
            in_stage: n.saturating_sub(self.stage_start.load(Ordering::Relaxed)),
            count: self,
        }
    }

    /// Whether `warning` is said for the first time in the campaign.
    fn first_time(&self, warning: &str) -> bool {
        self.said
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .insert(warning.to_string())
    }
}

/// Tells the user of a flight; a warning already said for an earlier flight (the same setting changed on
/// every flight, say) is not said again.
pub(in crate::campaign) fn announce(progress: &dyn Progress, numbered: Numbered<'_>, r: &FlightRecord, tick: bool) {
    let Numbered { n, in_stage, count } = numbered;
    if tick {
        progress.tick(in_stage);
    }
    let predicted = r
        .predicted_m()
        .map_or("not screened".into(), |d| format!("predicted {d:.2} m"));
    progress.note(&format!(
        "flight {n}: candidate {}{} {predicted}, flew {} ({})",
        r.candidate,
        match r.attempt {
            0 => String::new(),
            a => format!(" (its flight {})", a + 1),
        },
        r.flown.min_distance.map_or("-".into(), |d| format!("{d:.2} m")),
        r.flown.status
    ));
    for w in r.flown.warnings.iter().filter(|w| count.first_time(w)) {
        progress.note(&format!("  warning: {w} (said once: not repeated for later flights)"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::store::journal::test_record;

    struct Notes(Mutex<Vec<String>>);

    impl Progress for Notes {
        fn stage(&self, _: &str, _: usize) {}
        fn tick(&self, _: usize) {}
        fn note(&self, message: &str) {
            self.0.lock().unwrap().push(message.to_string());
        }
    }

    #[test]
    fn a_warning_every_flight_gives_is_said_once() {
        let (count, notes) = (FlightCount::default(), Notes(Mutex::new(Vec::new())));
        let mut r = test_record(1, 1.0, Some(2.0));
        r.flown.warnings = vec!["MPC_POS_MODE set to 3 for this flight".into()];
        for _ in 0..3 {
            announce(&notes, count.next(), &r, false);
        }
        let said = notes.0.into_inner().unwrap();
        assert_eq!(
            said.iter().filter(|n| n.contains("MPC_POS_MODE")).count(),
            1,
            "{said:#?}"
        );
        assert_eq!(said.iter().filter(|n| n.starts_with("flight ")).count(), 3);
    }
}
