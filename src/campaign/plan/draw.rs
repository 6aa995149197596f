//! The draw stage of a learning round: the round's candidates from the histogram distribution, and its last
//! ones as children in the boxes around the parents ([`crate::campaign::plan::neighbours`]), each child admitted by the
//! diversity guard.

use crate::campaign::ground::candidate::{Candidate, Lineage};
use crate::campaign::plan::diversity_guard::DiversityGuard;
use crate::campaign::plan::neighbours::{CHILD_TRIES, child_box};
use crate::generator::adaptive::{DrawDistribution, Neighbourhood, Proposal};
use crate::generator::{GenerateError, Generator};

/// What one round draws.
pub struct DrawPlan<'a> {
    /// Generator index of the round's first candidate.
    pub first: u64,
    /// Candidates to draw, children included.
    pub count: usize,
    /// Of them, the last ones drawn as children.
    pub children: usize,
    /// The parents' boxes.
    pub around: &'a [Neighbourhood],
    /// Whose children they are.
    pub lineage: Lineage,
    /// The children's failure rate so far, for the guard's expectation.
    pub child_rate: f64,
}

/// Draws `plan`'s candidates with `base` (from `distribution`, children from the parents' boxes).
pub fn draw(
    base: &Generator,
    distribution: &DrawDistribution,
    plan: &DrawPlan,
    guard: &mut DiversityGuard,
) -> Result<Vec<Candidate>, GenerateError> {
    let histogram = base.clone().with_distribution(distribution.clone());
    // Every parent's wide box, then every narrow one (`neighbours::child_box`'s order).
    let close = guard.close_children_may_fly();
    let near: Vec<Generator> = (0..2 * plan.around.len())
        .filter_map(|j| child_box(plan.around, j, close))
        .map(|n| base.clone().with_proposal(Proposal::Around(n)))
        .collect();
    let mut drawn = Vec::with_capacity(plan.count);
    for (k, i) in (plan.first..plan.first + plan.count as u64).enumerate() {
        // The parents' boxes take turns (wide, then narrow); a box with no room left (or no admissible child)
        // gives way to the histogram.
        let child = k
            .checked_sub(plan.count - plan.children)
            .map(|j| near[j % near.len()].sample_where(i, CHILD_TRIES, |o| guard.admit(o, plan.child_rate)));
        let (p, from_box) = match child {
            Some(Ok(p)) => (p, true),
            _ => (histogram.sample(i)?, false),
        };
        drawn.push(Candidate {
            obstacles: p.obstacles.to_vec(),
            unit: p.draw.unit,
            parents: from_box.then_some(plan.lineage),
            close: from_box && guard.last_was_close(),
            prediction: None,
        });
    }
    Ok(drawn)
}
