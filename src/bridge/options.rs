//! What the caller asks of one flight, and why a flight could not even start.

use std::path::PathBuf;
use std::time::Duration;

use super::hil::gate::SimGate;
use super::wire::notices;
use super::wire::url::{DEFAULT_URL, LinkAddress, UrlError};

/// How the virtual obstacles are flown around.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FlyMode {
    /// PX4 <= 1.15 flies the mission with COM_OBS_AVOID = 1; the bridge is the avoidance companion.
    #[default]
    Avoidance,
    /// The bridge flies the mission's waypoints in OFFBOARD mode with setpoints from the planner (any PX4).
    Offboard,
    /// PX4 flies the plain mission, no avoidance (the baseline).
    Mission,
    /// PX4's Collision Prevention is the system under test: the bridge is the pilot in Position mode
    /// (`MANUAL_CONTROL` toward each waypoint) and a virtual lidar (`OBSTACLE_DISTANCE`).
    #[serde(rename = "collision-prevention")]
    CollisionPrevention,
}

/// What simulates the vehicle PX4 SITL flies (`--sim`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VehicleSim {
    /// PX4's own SIH quadrotor inside PX4 (v1.14 and later).
    #[default]
    Sih,
    /// prgenuav's iris simulator (the Gazebo Classic iris) in this process, feeding PX4 in external-simulator
    /// mode over the HIL protocol (v1.12 and later).
    Iris,
}

/// How the iris simulator's HIL link reaches PX4 SITL (`--sim-link`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SimLink {
    /// PX4's TCP connection, in lockstep: simulated time drives PX4's clock.
    #[default]
    Tcp,
    /// A serial pty bridged to PX4's TCP connection by `socat`, on the wall clock at 250 Hz (as a board).
    Serial,
}

/// Options of one flight. Times are in the vehicle's seconds (see [`FlyOptions::time_scale`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FlyOptions {
    /// Connection address ([`LinkAddress`] syntax).
    pub connect: String,
    /// Obstacle mode.
    pub mode: FlyMode,
    /// Give up (LAND, status `timeout`) after this long in flight, seconds.
    pub timeout_s: f64,
    /// Append the trajectory to this CSV as it arrives.
    pub trajectory_csv: Option<PathBuf>,
    /// Upload the obstacles as geofence exclusion polygons.
    pub fence: bool,
    /// The vehicle's time runs this many times faster than wall time (mock `--speed-factor`,
    /// `PX4_SIM_SPEED_FACTOR`); 1 for real vehicles.
    pub time_scale: f64,
    /// Wait this long for the first autopilot heartbeat, wall seconds: a vehicle's clock is unknown until it
    /// speaks, and a PX4 boots on the wall clock whatever its speed factor.
    pub heartbeat_wait_s: f64,
    /// Silence longer than this during the flight is a lost link, seconds.
    pub link_loss_s: f64,
    /// Only fly the vehicle with this system id (default: the first autopilot heard).
    pub target_system: Option<u8>,
    /// The LFS prediction to report beside the flown distance, if the caller computed it.
    pub lfs_min_distance: Option<f64>,
    /// `Some(latency)`: the vehicle holds its clock until each avoidance answer (the mock's `--lockstep`), so
    /// answer every request at once with a plan made from the pose `latency` (vehicle time) before it,
    /// measure the flight timeout in the vehicle's reported time, and do not count the vehicle's silence
    /// while it waits for us as a lost link. `time_scale` is then an upper bound.
    pub lockstep: Option<Duration>,
    /// The judge edition whose distance definition the report uses.
    pub judge: crate::judge::Judge,
    /// Re-anchor the test (mission, obstacles, fence) at the vehicle's home instead of refusing a vehicle
    /// farther than MIS_DIST_1WP from the test's home ([`super::session::placement`]).
    pub anchor_at_vehicle_home: bool,
    /// Wait at most this long (vehicle seconds) for the vehicle to become ready to arm (estimator, GPS fix,
    /// home, PX4's pre-arm checks); arming is retried within the same budget. The wait lasts at least
    /// [`MIN_READY_WALL_S`] of wall time however fast the vehicle's clock runs ([`Self::ready_budget_s`]).
    pub ready_timeout_s: f64,
    /// Measure the vehicle's clock rate at connection and use it as `time_scale` (a pool of simulators at
    /// unknown speed); `time_scale` is then only the assumption until measured.
    pub detect_time_scale: bool,
    /// Live notices (vehicle messages, readiness, clock warnings), e.g. printed by the CLI.
    pub notices: Option<notices::NoticeSink>,
    /// The gate of prgenuav's simulator in this process, feeding this PX4 in lockstep: the avoidance
    /// companion answers on simulated time, holding it until each answer is out (set `lockstep` too).
    pub sim_gate: Option<SimGate>,
    /// The vehicle is a board in HITL: refuse it, before anything is set or armed, unless `SYS_HITL` is 1.
    pub require_hitl: bool,
    /// How the avoidance companion plans and answers (its waypoint generator's path age, the yaw-rate field).
    pub companion: crate::bridge::companion::planner_steer::CompanionStyle,
}

impl Default for FlyOptions {
    fn default() -> Self {
        Self {
            connect: DEFAULT_URL.into(),
            mode: FlyMode::default(),
            timeout_s: 500.0,
            trajectory_csv: None,
            fence: true,
            time_scale: 1.0,
            heartbeat_wait_s: 30.0,
            link_loss_s: 5.0,
            target_system: None,
            lfs_min_distance: None,
            lockstep: None,
            judge: crate::judge::Judge::default(),
            anchor_at_vehicle_home: false,
            ready_timeout_s: 60.0,
            detect_time_scale: false,
            notices: None,
            sim_gate: None,
            require_hitl: false,
            companion: Default::default(),
        }
    }
}

/// Why a flight could not even start (no vehicle to report on). Vehicle refusals are reports, not errors.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// The address is malformed.
    #[error(transparent)]
    Url(#[from] UrlError),
    /// The link could not be opened.
    #[error("cannot open {url}: {source}")]
    Open {
        /// The address.
        url: String,
        /// The IO error.
        source: std::io::Error,
    },
    /// No autopilot heartbeat within the wait.
    #[error(
        "no autopilot heartbeat on {url} within {waited_s} s (is PX4 running and sending to this address? \
         PX4 SITL instance i sends its API link to udp port 14540+i)"
    )]
    NoHeartbeat {
        /// The address.
        url: String,
        /// Seconds waited (vehicle time).
        waited_s: f64,
    },
    /// The trajectory file cannot be created.
    #[error("cannot write the trajectory to {path}: {source}")]
    Trajectory {
        /// The file.
        path: PathBuf,
        /// The IO error.
        source: std::io::Error,
    },
    /// The test cannot be turned into a plan, or an option is out of range.
    #[error("{0}")]
    Invalid(String),
    /// Cancelled before a vehicle was found.
    #[error("cancelled before the vehicle was found")]
    Cancelled,
}

/// The readiness wait's floor in wall seconds: at 100x a 60 s budget is 0.6 s of wall time, which a busy
/// machine (four campaigns on 2 cores) can spend before the bridge runs at all.
pub const MIN_READY_WALL_S: f64 = 5.0;

impl FlyOptions {
    /// The readiness budget in vehicle seconds for a clock running `time_scale` times real time:
    /// `ready_timeout_s`, but at least [`MIN_READY_WALL_S`] of wall time.
    pub fn ready_budget_s(&self, time_scale: f64) -> f64 {
        self.ready_timeout_s.max(MIN_READY_WALL_S * time_scale)
    }

    /// Checks the numbers.
    pub fn validate(&self) -> Result<(), BridgeError> {
        for (name, v) in [
            ("timeout", self.timeout_s),
            ("time scale", self.time_scale),
            ("heartbeat wait", self.heartbeat_wait_s),
            ("link-loss time", self.link_loss_s),
            ("ready timeout", self.ready_timeout_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(BridgeError::Invalid(format!("{name} {v} is not a positive number")));
            }
        }
        LinkAddress::parse(&self.connect)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_readiness_budget_lasts_at_least_the_wall_floor() {
        let o = FlyOptions::default();
        // Real time and PX4 SITL at 5x: the vehicle-time budget rules.
        assert_eq!(o.ready_budget_s(1.0), o.ready_timeout_s);
        assert_eq!(o.ready_budget_s(5.0), o.ready_timeout_s.max(5.0 * MIN_READY_WALL_S));
        // A mock at 100x: 60 vehicle seconds would be 0.6 s of wall time.
        assert_eq!(o.ready_budget_s(100.0), 100.0 * MIN_READY_WALL_S);
    }
}
