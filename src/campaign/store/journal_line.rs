//! A flight record's journal line: the one place its on-disk shape is spelled.
//!
//! The record holds the candidate's prediction and the vehicle's outcome as they are; the line keeps the
//! shape journals have always had (prediction fields prefixed `predicted_`, the vehicle, trajectory and wall
//! time between the outcome and its Collision Prevention fields, in this order), so `serde(flatten)` cannot
//! write it and the mapping is by hand, here. A flight flown without a prediction is spelled, as journals
//! always spelled it, as a zero distance predicted over zero seconds: no simulated flight takes 0 s, so the
//! reader tells it apart; the records themselves hold `None`.

use std::borrow::Cow;
use std::path::Path;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::campaign::ground::candidate::LfsPrediction;
use crate::campaign::ground::candidate_id::CandidateId;
use crate::campaign::ground::flight_status::{FlightStatus, Flown};
use crate::campaign::store::journal::{FlightRecord, is_first};
use crate::model::Obstacle;

/// One journal line, borrowed from a record when written, owned when read. Optional fields are left out when
/// absent and read as absent, so older journals load.
#[derive(Serialize, Deserialize)]
struct Line<'a> {
    candidate: CandidateId,
    #[serde(default, skip_serializing_if = "is_first")]
    attempt: u32,
    obstacles: Cow<'a, [Obstacle]>,
    predicted_min_distance: f64,
    predicted_flight_time_s: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    predicted_p_fail: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    predicted_raw_min_distance: Option<f64>,
    min_distance: Option<f64>,
    min_distance_raw: Option<f64>,
    status: FlightStatus,
    flight_time_s: f64,
    #[serde(default, skip_serializing_if = "<[String]>::is_empty")]
    warnings: Cow<'a, [String]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reason: Option<Cow<'a, str>>,
    vehicle: Cow<'a, str>,
    trajectory: Cow<'a, Path>,
    wall_s: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    closest_centre_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    inside_cp_dist: Option<bool>,
}

impl Serialize for FlightRecord {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let (p, f) = (self.prediction.as_ref(), &self.flown);
        Line {
            candidate: self.candidate,
            attempt: self.attempt,
            obstacles: Cow::Borrowed(&self.obstacles),
            predicted_min_distance: p.map_or(0.0, |p| p.min_distance),
            predicted_flight_time_s: p.map_or(0.0, |p| p.flight_time_s),
            predicted_p_fail: p.and_then(|p| p.p_fail),
            predicted_raw_min_distance: p.and_then(|p| p.raw_min_distance),
            min_distance: f.min_distance,
            min_distance_raw: f.min_distance_raw,
            status: f.status,
            flight_time_s: f.flight_time_s,
            warnings: Cow::Borrowed(&f.warnings),
            reason: f.reason.as_deref().map(Cow::Borrowed),
            vehicle: Cow::Borrowed(&self.vehicle),
            trajectory: Cow::Borrowed(&self.trajectory),
            wall_s: self.wall_s,
            closest_centre_m: f.closest_centre_m,
            inside_cp_dist: f.inside_cp_dist,
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for FlightRecord {
    /// The prediction read back has the journaled fields only: no LFS status (empty) nor expected points.
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let l = Line::deserialize(deserializer)?;
        let predicted = l.predicted_flight_time_s > 0.0 || l.predicted_min_distance != 0.0;
        let prediction = predicted.then(|| LfsPrediction {
            p_fail: l.predicted_p_fail,
            raw_min_distance: l.predicted_raw_min_distance,
            ..LfsPrediction::point(
                l.candidate,
                l.predicted_min_distance,
                l.predicted_flight_time_s,
                String::new(),
            )
        });
        let flown = Flown {
            status: l.status,
            min_distance: l.min_distance,
            min_distance_raw: l.min_distance_raw,
            flight_time_s: l.flight_time_s,
            warnings: l.warnings.into_owned(),
            reason: l.reason.map(Cow::into_owned),
            closest_centre_m: l.closest_centre_m,
            inside_cp_dist: l.inside_cp_dist,
        };
        Ok(FlightRecord {
            candidate: l.candidate,
            attempt: l.attempt,
            obstacles: l.obstacles.into_owned(),
            prediction,
            flown,
            vehicle: l.vehicle.into_owned(),
            trajectory: l.trajectory.into_owned(),
            wall_s: l.wall_s,
        })
    }
}
