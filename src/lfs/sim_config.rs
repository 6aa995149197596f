//! What a simulated flight is run with and what comes out of it: the motion model, the settings, the
//! errors, the outcome (re-exported by [`super::sim`], whose loop uses them).

use serde::Serialize;

use super::attitude::TiltParams;
use super::camera::Camera;
use super::mission::MissionParams;
use super::motion::{PaperParams, Px4Params};
use crate::judge::{FlightDistance, Judge};
use crate::model::{Param, Trajectory};
use prgenuav_planner::params::PlannerParams;

/// The motion model by name, as a campaign's settings choose it (its constants are the fitted ones).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Motion {
    /// PX4's waypoint generator and a PX4-like position tracker.
    #[default]
    Px4,
    /// The paper's kinematic rule towards the planner's first tree node.
    Paper,
}

impl Motion {
    /// The model with its fitted constants.
    pub fn model(self) -> MotionModel {
        match self {
            Motion::Px4 => MotionModel::Px4(Px4Params::default()),
            Motion::Paper => MotionModel::Paper(PaperParams::default()),
        }
    }
}

/// Which motion model moves the vehicle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotionModel {
    /// The paper's rule towards the first tree node.
    Paper(PaperParams),
    /// The waypoint generator followed by a PX4-like tracker.
    Px4(Px4Params),
}

impl MotionModel {
    /// The model by CLI name (`paper` or `px4`) with its fitted defaults.
    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "paper" => Some(Self::Paper(PaperParams::default())),
            "px4" => Some(Self::Px4(Px4Params::default())),
            _ => None,
        }
    }

    /// Ticks between the planner's answer and the vehicle acting on it (0 = the same tick).
    pub fn delay_ticks(&self) -> usize {
        match self {
            Self::Paper(p) => p.delay_ticks,
            Self::Px4(p) => p.delay_ticks,
        }
    }

    /// CLI name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Paper(_) => "paper",
            Self::Px4(_) => "px4",
        }
    }
}

/// How a flight ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SimStatus {
    /// Touched down after the land item.
    Landed,
    /// No progress towards the current target for `stuck_s`.
    Stuck,
    /// Simulated time reached `timeout_s`.
    Timeout,
    /// The vehicle entered a box.
    Collision,
}

/// Simulation settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Motion model.
    pub motion: MotionModel,
    /// Depth camera.
    pub camera: Camera,
    /// Camera pitch from the vehicle's acceleration and drag ([`super::attitude`]); `None` = level camera.
    pub tilt: Option<TiltParams>,
    /// Planner parameters (its FOV is replaced by the camera's; with `fov_estimate` `FromMaxima` the planner then
    /// starts it at zero and widens it from the frames).
    pub planner: PlannerParams,
    /// Mission parameters; `None` = PX4 defaults overridden by the test's parameters.
    pub mission: Option<MissionParams>,
    /// Tick length, seconds (the planner period, 0.1 s).
    pub dt_s: f64,
    /// Simulated-time limit, seconds (the competition's 500 s).
    pub timeout_s: f64,
    /// A flight with no progress for this long (seconds) is stuck.
    pub stuck_s: f64,
    /// Progress means getting this much closer (metres) to the current target.
    pub progress_m: f64,
    /// The judge edition whose definition the prediction uses (the flights it predicts are judged alike).
    pub judge: Judge,
}

impl SimConfig {
    /// The planner's parameters for a vehicle with `px4_params`, after checking the loop's own settings.
    pub fn planner_params(&self, px4_params: &[Param]) -> Result<PlannerParams, SimError> {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !ok(self.dt_s) || !ok(self.timeout_s) || !ok(self.stuck_s) || !ok(self.progress_m) {
            return Err(SimError::Setting(
                "dt_s, timeout_s, stuck_s and progress_m must be positive",
            ));
        }
        let mut params = self.planner.clone();
        // With the data-driven FOV the planner starts it at zero and widens it from each rendered frame.
        params.fovs = vec![self.camera.fov()];
        // PX4-Avoidance reads MPC_XY_CRUISE from the vehicle; the case's parameters are what the vehicle has.
        if let Some(v) = cruise_param(px4_params) {
            params.mpc_xy_cruise_m_s = v;
        }
        Ok(params)
    }
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            motion: MotionModel::Paper(PaperParams::default()),
            camera: Camera::hfs(),
            tilt: None,
            planner: PlannerParams::default(),
            mission: None,
            dt_s: 0.1,
            timeout_s: crate::model::competition::SIMULATION_TIMEOUT_S,
            stuck_s: 20.0,
            progress_m: 1.0,
            judge: Judge::default(),
        }
    }
}

/// Why a simulation cannot start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The mission has no positional item.
    #[error("the mission has no item with a position")]
    EmptyMission,
    /// Planner parameters are invalid.
    #[error(transparent)]
    Planner(#[from] prgenuav_planner::PlannerError),
    /// A setting is out of range.
    #[error("invalid simulation setting {0}")]
    Setting(&'static str),
}

/// The outcome of one simulated flight.
#[derive(Debug, Clone)]
pub struct SimResult {
    /// Flown path, Aerialist frame, one sample per tick from t = 0 (on the ground at home).
    pub trajectory: Trajectory,
    /// How it ended.
    pub status: SimStatus,
    /// Simulated seconds until the end.
    pub flight_time_s: f64,
    /// Ticks simulated (one planner cycle each).
    pub cycles: u64,
    /// The competition's verdict on the trajectory (`None` without obstacles).
    pub distance: Option<FlightDistance>,
    /// Frames the fast renderer had to render in full (a box within the near clip).
    pub full_renders: u64,
}

/// MPC_XY_CRUISE among the case's PX4 parameters, if set to a usable speed (m/s).
pub fn cruise_param(px4_params: &[Param]) -> Option<f32> {
    px4_params
        .iter()
        .rev()
        .find(|p| p.name == "MPC_XY_CRUISE")
        .map(|p| p.value as f32)
        .filter(|v| v.is_finite() && *v > 0.0)
}
