//! The rules of the defaults that depend on a campaign's setup (the budget, the mode, the vehicles), each named
//! in its setting's declaration, and the setup they read.

use super::mock_profile::{MockProfile, ProfileName};
use crate::bridge::{Bench, FlyMode, VehicleSim};

/// What the setup-dependent defaults depend on, read from the request before any section is resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// The budget (0 when none was given: only a resumed campaign lacks one, and it keeps its stored rules).
    pub budget: usize,
    /// The flight mode.
    pub mode: FlyMode,
    /// The embedded mocks fly the campaign.
    pub mock: bool,
    /// The mocks' profile.
    pub profile: ProfileName,
    /// The mocks' gusts, m/s² RMS per horizontal axis.
    pub gusts_m_s2: f64,
    /// Flights at once, as `--jobs` asks.
    pub jobs: Option<usize>,
    /// The cores this process may run on.
    pub cores: usize,
    /// The bench the --px4 instances reproduce.
    pub bench: Bench,
}

/// The gusts of the mocks' profile `p`, m/s² RMS per horizontal axis.
pub fn profile_gusts(p: ProfileName) -> f64 {
    MockProfile::of(p).tuning.gust_acc_m_s2
}

/// Ensemble members ranking the shortlist when the vehicles are MAVLink ones (an ensemble costs more CPU
/// than a mock flight, far less than a PX4 or hardware flight).
pub const LINK_ENSEMBLE: usize = 8;
/// Flights a failing test gets at most on a vehicle whose flights scatter: on PX4 a test that failed once
/// often passes when flown again, and so on the default mock profile, whose gusts are fitted to that.
pub const SCATTERING_CONFIRM: usize = 3;
/// The embedded mocks' speed in `collision-prevention` mode: the pilot's 20 Hz sticks keep up with a mock
/// holding its clock for them at this speed, and at 100 the vehicle was seen never to take off
/// (docs/collision-prevention.md#campaigns).
pub const CP_MOCK_SPEED: f64 = 20.0;
/// The embedded mocks' speed otherwise, times real time (in lockstep an upper bound).
pub const MOCK_SPEED: f64 = 100.0;

/// `vehicles.sim`: the bench's simulator.
pub fn sim(s: &Setup) -> VehicleSim {
    s.bench.sim()
}

/// `screening.candidates`: 3 x the budget, at least 20.
pub fn candidates(s: &Setup) -> usize {
    s.budget.saturating_mul(3).max(20)
}

/// `screening.ensemble`: none on the mock, [`LINK_ENSEMBLE`] on MAVLink vehicles.
pub fn ensemble(s: &Setup) -> usize {
    if s.mock { 0 } else { LINK_ENSEMBLE }
}

/// `mock.speed`.
pub fn mock_speed(s: &Setup) -> f64 {
    if s.mode == FlyMode::CollisionPrevention {
        CP_MOCK_SPEED
    } else {
        MOCK_SPEED
    }
}

/// `mock.vehicles`: as many as `--jobs` asks, else one per core.
pub fn mock_vehicles(s: &Setup) -> usize {
    s.jobs.unwrap_or(s.cores)
}

/// `mock.gust_acc_m_s2`: the profile's.
pub fn gusts(s: &Setup) -> f64 {
    profile_gusts(s.profile)
}

/// `flight.confirm`: [`SCATTERING_CONFIRM`] where flights scatter (any vehicle but a gust-free mock; the
/// mock's gusts fly only in avoidance mode), else 1.
pub fn confirm(s: &Setup) -> usize {
    let scatters = !s.mock || (s.mode == FlyMode::Avoidance && s.gusts_m_s2 > 0.0);
    if scatters { SCATTERING_CONFIRM } else { 1 }
}

/// `flight.overlap`: on every backend but the embedded mock, which flies on the screening's cores.
pub fn overlap(s: &Setup) -> bool {
    !s.mock
}
