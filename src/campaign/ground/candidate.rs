//! The record every stage of a campaign works on: one drawn candidate test, where in draw space it came from,
//! and what the low-fidelity simulator predicted for it.

use serde::{Deserialize, Serialize};

use crate::generator::adaptive::DIMS;
use crate::model::Obstacle;

pub use super::candidate_id::CandidateId;

/// Where a round's children come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lineage {
    /// The failing flights so far.
    Failures,
    /// No flight has failed yet: the closest flights within [`crate::campaign::plan::neighbours::NEAR_MISS_M`] of failing.
    NearMisses,
}

/// One drawn candidate; its index in the campaign's list is its generator index.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Its obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Its draw in the unit cube (where it lies in draw space).
    pub unit: [f64; DIMS],
    /// The parents' lineage of a child drawn around earlier flights; `None` for a draw of the histogram.
    pub parents: Option<Lineage>,
    /// A child admitted closer to a flown test than `max_iou` by the diversity guard.
    pub close: bool,
    /// The LFS's prediction, once screened: carried whole into its job and flight record.
    pub prediction: Option<LfsPrediction>,
}

impl Candidate {
    /// A candidate drawn from the histogram distribution (or the static campaign's generator).
    pub fn drawn(obstacles: Vec<Obstacle>, unit: [f64; DIMS]) -> Self {
        Self {
            obstacles,
            unit,
            parents: None,
            close: false,
            prediction: None,
        }
    }

    /// Whether it is a child of `lineage`'s parents.
    pub fn is_child_of(&self, lineage: Lineage) -> bool {
        self.parents == Some(lineage)
    }
}

/// Whether candidate `c` of `candidates` is a child of `lineage` (flights of candidates this run did not draw
/// are not).
pub fn is_child(candidates: &[Candidate], c: CandidateId, lineage: Lineage) -> bool {
    candidates.get(c.index()).is_some_and(|x| x.is_child_of(lineage))
}

/// The draw of candidate `c`, if this run drew it.
pub fn unit_of(candidates: &[Candidate], c: CandidateId) -> Option<[f64; DIMS]> {
    candidates.get(c.index()).map(|x| x.unit)
}

/// The screened candidates of `candidates` not among `flown` (flown, queued or set aside), in draw order.
pub fn unflown<'a>(candidates: &'a [Candidate], flown: &'a [CandidateId]) -> impl Iterator<Item = &'a LfsPrediction> {
    (candidates.iter())
        .filter_map(|c| c.prediction.as_ref())
        .filter(|s| !flown.contains(&s.candidate))
}

/// A candidate chosen to fly, with its prediction (`None`: the campaign flies unscreened).
#[derive(Debug, Clone, PartialEq)]
pub struct Pick {
    /// The candidate.
    pub candidate: CandidateId,
    /// What the LFS predicted for it.
    pub prediction: Option<LfsPrediction>,
}

impl From<LfsPrediction> for Pick {
    fn from(p: LfsPrediction) -> Self {
        Self {
            candidate: p.candidate,
            prediction: Some(p),
        }
    }
}

/// What the low-fidelity simulator predicted for one candidate: one value from its screening to its flight
/// records (`screening.json` keeps it in this shape).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LfsPrediction {
    /// The candidate.
    pub candidate: CandidateId,
    /// Predicted minimum distance (competition definition), metres.
    pub min_distance: f64,
    /// Predicted flight time, seconds.
    pub flight_time_s: f64,
    /// How the simulated flight ended.
    pub status: String,
    /// The ensemble's probability of a flight below 1.5 m (`None`: no ensemble ran for it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub p_fail: Option<f64>,
    /// The ensemble's expected competition points of one flight.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expected_points: Option<f64>,
    /// The LFS's own prediction when `min_distance` is a calibrated one (a learning campaign).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw_min_distance: Option<f64>,
}

impl LfsPrediction {
    /// A point prediction without an ensemble.
    pub fn point(candidate: CandidateId, min_distance: f64, flight_time_s: f64, status: String) -> Self {
        LfsPrediction {
            candidate,
            min_distance,
            flight_time_s,
            status,
            p_fail: None,
            expected_points: None,
            raw_min_distance: None,
        }
    }

    /// Expected points per minute of predicted flight: what a flight adds to the competition's test score
    /// (points x 10 / (obstacles^2 x minutes), the obstacle count being the same for every candidate).
    pub fn points_per_minute(&self) -> Option<f64> {
        self.expected_points.map(|p| p / (self.flight_time_s.max(1.0) / 60.0))
    }
}

/// How far a journaled obstacle may lie from the one drawn (metres or degrees): a JSON round trip, not a change.
const SAME_OBSTACLE_TOLERANCE: f64 = 1e-6;

/// Whether `obstacles` (a journaled flight's) are `candidate`'s as drawn, up to a JSON round trip.
pub fn drawn_as(candidate: &Candidate, obstacles: &[Obstacle]) -> bool {
    let values = |o: &Obstacle| {
        let (s, p) = (&o.size, &o.position);
        [s.l, s.w, s.h, p.x, p.y, p.z, p.r]
    };
    let same = |a: &Obstacle, b: &Obstacle| {
        let (a, b) = (values(a), values(b));
        a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= SAME_OBSTACLE_TOLERANCE)
    };
    let (c, r) = (&candidate.obstacles, obstacles);
    c.len() == r.len() && c.iter().zip(r).all(|(a, b)| same(a, b))
}
