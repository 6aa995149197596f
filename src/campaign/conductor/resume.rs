//! What a resumed campaign does with journaled flights its replayed plan cannot take
//! ([`crate::campaign::fly::fleet::replay`]): another campaign's lines are refused; those of a learning round that
//! came out otherwise are kept and counted, never flown again.

use std::sync::atomic::Ordering;

use super::Round;
use super::Rounds;
use crate::campaign::fly::confirm::as_learnt;
use crate::campaign::fly::fleet::Fleet;
use crate::campaign::ground::candidate::{CandidateId, drawn_as};
use crate::campaign::ground::error::CampaignError;

impl Rounds<'_> {
    /// Checks a resumed campaign's journaled flights of `round`'s candidates against what it drew for them. A
    /// draw that no flight shapes (the first round's, or any round of a campaign that does not learn, whose
    /// one round also owns every candidate index) must give the journaled obstacles: otherwise the lines come
    /// from another campaign, an error. A later learning round's draw follows the flights (on vehicles that do
    /// not repeat it comes out otherwise), so there a mismatch is set aside: kept and counted, never flown again.
    pub(in crate::campaign) fn check_drawn(&self, round: &Round, fleet: &Fleet) -> Result<(), CampaignError> {
        let range = if self.learning {
            round.first..round.first + round.drawn as u64
        } else {
            0..u64::MAX
        };
        let drawn = &self.candidates;
        let diverged = fleet.set_aside_diverged(range, |r| {
            drawn
                .get(r.candidate.index())
                .is_some_and(|c| drawn_as(c, &r.obstacles))
        });
        if diverged.is_empty() {
            return Ok(());
        }
        let journal = self.input.folder.join("journal.jsonl");
        let ids = diverged
            .iter()
            .map(CandidateId::to_string)
            .collect::<Vec<_>>()
            .join(", ");
        if round.index == 0 || !self.learning {
            return Err(CampaignError::Config(format!(
                "{}: the journaled flights of candidate(s) {ids} are not what this campaign draws for them \
                 (other obstacles, or an index it never draws): the lines come from another campaign (seed, case or \
                 settings); remove them or restore the journal, then resume",
                journal.display()
            )));
        }
        self.input.progress.warn(&format!(
            "{}: the journaled flights of candidate(s) {ids} have other obstacles than the resumed campaign drew for \
             them (the rounds before came out otherwise, or the lines come from another campaign); they are kept \
             and counted, and those candidates are not flown again",
            journal.display()
        ));
        Ok(())
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
