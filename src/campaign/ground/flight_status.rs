//! How a campaign's flight ended, one type from the vehicle's report to the journal and back (the bridge's
//! own status, or the campaign's two endings), and the vehicle's whole outcome of a flight ([`Flown`]). The
//! journal's strings are the bridge's, so journals written before read as they were.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::bridge::session::report::Status;
use crate::judge::cp_verdict::CpVerdict;

/// How a flight ended: as the vehicle's side reported it (the bridge's [`Status`]), or by the campaign's own
/// hand (the user's stop, a failed backend).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FlightStatus {
    /// As the vehicle's side reported it.
    Vehicle(Status),
    /// Cut short by the user's stop: journaled so the trajectory is kept, not charged, flown again on resume.
    Interrupted,
    /// The backend failed around the flight after its retry: the vehicle, not the test, is at fault.
    BackendFailed,
}

impl FlightStatus {
    /// Flown to the end, landed and disarmed.
    pub const LANDED: Self = Self::Vehicle(Status::Landed);
    /// The vehicle entered an obstacle.
    pub const COLLISION: Self = Self::Vehicle(Status::Collision);
    /// Still flying at the timeout.
    pub const TIMEOUT: Self = Self::Vehicle(Status::Timeout);
    /// The vehicle went silent or rebooted.
    pub const LINK_LOST: Self = Self::Vehicle(Status::LinkLost);
    /// Cancelled mid-flight by the vehicle's side.
    pub const ABORTED: Self = Self::Vehicle(Status::Aborted);
    /// The vehicle refused the mission, a parameter, a mode or arming.
    pub const REJECTED: Self = Self::Vehicle(Status::Rejected);

    /// The journal's spelling (the vehicle's own statuses as the bridge spells them).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Vehicle(s) => s.as_str(),
            Self::Interrupted => "interrupted",
            Self::BackendFailed => "backend_failed",
        }
    }

    /// The status spelled `text` in a journal.
    pub fn parse(text: &str) -> Option<Self> {
        match text {
            "interrupted" => Some(Self::Interrupted),
            "backend_failed" => Some(Self::BackendFailed),
            other => Status::ALL.into_iter().find(|s| s.as_str() == other).map(Self::Vehicle),
        }
    }

    /// Whether the flight counts against the budget: an interrupted flight or a failed backend says nothing
    /// about the test.
    pub fn charged(self) -> bool {
        matches!(self, Self::Vehicle(_))
    }

    /// Whether the flight ran to its end (a measurement exists).
    pub fn completed(self) -> bool {
        matches!(self, Self::Vehicle(s) if s.completed())
    }

    /// Whether a vehicle's own report can say it (`prgenuav fly`'s statuses); the others are the campaign's.
    pub fn from_vehicle(self) -> bool {
        matches!(self, Self::Vehicle(_))
    }
}

impl Serialize for FlightStatus {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for FlightStatus {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let text = String::deserialize(deserializer)?;
        Self::parse(&text).ok_or_else(|| serde::de::Error::custom(format!("unknown flight status {text:?}")))
    }
}

impl fmt::Display for FlightStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl From<Status> for FlightStatus {
    fn from(s: Status) -> Self {
        Self::Vehicle(s)
    }
}

/// How one flight ended, as the vehicle's side reports it; its flight record keeps it as it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Flown {
    /// How it ended.
    pub status: FlightStatus,
    /// The competition's minimum distance, metres, if anything was recorded.
    pub min_distance: Option<f64>,
    /// The un-binned minimum distance, metres.
    pub min_distance_raw: Option<f64>,
    /// Flight time, seconds.
    pub flight_time_s: f64,
    /// What the flight side warned about (e.g. the avoidance planner falling behind).
    pub warnings: Vec<String>,
    /// Why the flight stopped, in words, when it did not land.
    pub reason: Option<String>,
    /// A Collision Prevention flight: the closest the vehicle's centre came to a box, metres (absent in other
    /// modes, and in journals written before it was kept).
    pub closest_centre_m: Option<f64>,
    /// A Collision Prevention flight: whether the vehicle came inside `CP_DIST`.
    pub inside_cp_dist: Option<bool>,
}

impl Flown {
    /// A flight that ended `status` with nothing measured: no distance, no time, no reason given.
    pub fn ended(status: FlightStatus) -> Self {
        Flown {
            status,
            min_distance: None,
            min_distance_raw: None,
            flight_time_s: 0.0,
            warnings: Vec::new(),
            reason: None,
            closest_centre_m: None,
            inside_cp_dist: None,
        }
    }

    /// A flight that never flew (stopped before take-off, or its backend failed): `status` and why.
    pub fn unflown(status: FlightStatus, reason: String) -> Self {
        Flown {
            reason: Some(reason),
            ..Flown::ended(status)
        }
    }

    /// This outcome with the Collision Prevention verdict `cp` of a flight in that mode (its `CP_DIST` is
    /// not kept: the journal never held it).
    pub fn with_cp(self, cp: Option<CpVerdict>) -> Self {
        Flown {
            closest_centre_m: cp.and_then(|v| v.closest_centre_m),
            inside_cp_dist: cp.and_then(|v| v.inside_cp_dist),
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [FlightStatus; 8] = [
        FlightStatus::LANDED,
        FlightStatus::COLLISION,
        FlightStatus::TIMEOUT,
        FlightStatus::LINK_LOST,
        FlightStatus::ABORTED,
        FlightStatus::REJECTED,
        FlightStatus::Interrupted,
        FlightStatus::BackendFailed,
    ];

    #[test]
    fn the_journal_strings_read_and_write_as_before() {
        let names = [
            "landed",
            "collision",
            "timeout",
            "link_lost",
            "aborted",
            "rejected",
            "interrupted",
            "backend_failed",
        ];
        for (s, name) in ALL.into_iter().zip(names) {
            let json = serde_json::to_string(&s).unwrap();
            assert_eq!(json, format!("\"{name}\""));
            assert_eq!(serde_json::from_str::<FlightStatus>(&json).unwrap(), s);
        }
        for bridge in Status::ALL {
            assert_eq!(FlightStatus::from(bridge).as_str(), bridge.as_str());
        }
        assert!(serde_json::from_str::<FlightStatus>("\"queued\"").is_err());
        assert!(serde_json::from_str::<FlightStatus>("\"crashed\"").is_err());
    }

    #[test]
    fn only_the_campaigns_own_endings_go_uncharged() {
        let uncharged: Vec<_> = ALL.into_iter().filter(|s| !s.charged()).collect();
        assert_eq!(uncharged, [FlightStatus::Interrupted, FlightStatus::BackendFailed]);
        assert!(ALL.iter().filter(|s| s.from_vehicle()).all(|s| s.charged()));
    }
}
