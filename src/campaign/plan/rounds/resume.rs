//! What a resumed learning campaign does with journaled flights its replayed plan cannot take
//! ([`crate::campaign::store::replay`]): they are kept and counted, never flown again.

use std::sync::atomic::Ordering;

use super::Round;
use super::Rounds;
use crate::campaign::candidate::{CandidateId, drawn_as};
use crate::campaign::fly::confirm::as_learnt;
use crate::campaign::fly::fleet::Fleet;

impl Rounds<'_> {
    /// A resumed campaign's journaled flights of `round`'s candidates drawn with other obstacles this time (the
    /// rounds before came out otherwise, or the record is another campaign's) are not served to the plan; they
    /// are kept, and their candidate indices never flown again.
    pub(in crate::campaign) fn set_aside_diverged(&self, round: &Round, fleet: &Fleet) {
        let range = round.first..round.first + round.drawn as u64;
        let drawn = &self.candidates;
        let diverged = fleet.set_aside_diverged(range, |r| {
            drawn.get(r.candidate.index()).is_some_and(|c| drawn_as(c, r))
        });
        if diverged.is_empty() {
            return;
        }
        self.input.progress.warn(&format!(
            "{}: the journaled flights of candidate(s) {} have other obstacles than the resumed campaign drew for \
             them (the rounds before came out otherwise, or the lines come from another campaign); they are kept \
             and counted, and those candidates are not flown again",
            self.input.folder.join("journal.jsonl").display(),
            diverged
                .iter()
                .map(CandidateId::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }

    /// Journaled flights the replayed plan never asked for (the campaign flew on vehicles that do not repeat,
    /// so its rounds came out otherwise) are kept: they count, are reported and are learnt from.
    pub(in crate::campaign) fn keep_unreplayed(&mut self, fleet: &Fleet) {
        let left = fleet.unreplayed();
        if left.is_empty() || self.input.cancel.load(Ordering::Relaxed) {
            return;
        }
        self.input.progress.warn(&format!(
            "resumed: {} journaled flight(s) were not planned again (candidates {}); they are kept and counted",
            left.len(),
            left.iter()
                .map(|r| r.candidate.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
        self.flights.extend(left);
        self.journal = as_learnt(&self.flights);
    }
}
