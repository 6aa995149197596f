//! What defines a campaign (saved as `campaign.json`).

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::ground::error::CampaignError;
use super::settings::{Flight, Learning, Mock, Screening};
use crate::generator::GeneratorConfig;
use crate::judge::Judge;

/// Everything that defines a campaign; saved as `campaign.json` so `--resume` continues the same one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignConfig {
    /// The case study YAML.
    pub case: PathBuf,
    /// Seed of the generator.
    pub seed: u64,
    /// High-fidelity flights allowed.
    pub budget: usize,
    /// Candidates to draw and screen.
    pub candidates: usize,
    /// Only candidates predicted below this distance (metres) are flown.
    pub threshold_m: f64,
    /// Candidates overlapping an already chosen one by more than this IoU are skipped.
    pub max_iou: f64,
    /// Generator parameters.
    pub generator: GeneratorConfig,
    /// Whether tests are written with the old key spelling (`drone`/`test`).
    pub old_spelling: bool,
    /// The high-fidelity side as given (`mock` or MAVLink URLs).
    pub hfs: Vec<String>,
    /// Obstacle mode of the flights (`avoidance`, `offboard`, `mission`).
    #[serde(default = "default_mode")]
    pub mode: String,
    /// LFS motion model used for screening (`px4`, `paper`).
    #[serde(default = "default_motion")]
    pub motion: String,
    /// Clock speed of the embedded mock autopilots. 20 when the key is absent: the speed such campaigns flew at
    /// (a new campaign's default is `mock.speed`'s, in [`super::settings`]).
    #[serde(default = "mock_speed_before_key")]
    pub mock_speed: f64,
    /// The embedded mocks hold their clock for each avoidance answer (`mock_speed` is then an upper bound).
    /// Off when the key is absent: such campaign files' flights were free-running, and a resume must match.
    #[serde(default)]
    pub mock_lockstep: bool,
    /// In lockstep, the companion plans on the pose this old (vehicle milliseconds), as a real companion's
    /// camera and planner lag behind the vehicle.
    #[serde(default = "default_mock_latency_ms")]
    pub mock_latency_ms: f64,
    /// The embedded mocks' profile (`campaign::settings::mock_profile`). `competition` when the key is absent: the only
    /// mock there was before profiles, and a resume must match.
    #[serde(default = "profile_before_profiles")]
    pub mock_profile: String,
    /// RMS of the embedded mocks' gusts, m/s² per horizontal axis (`mock_autopilot::dynamics::Tuning`), as the
    /// profile had them when the campaign began. 0 when the key is absent: the mocks had no gusts before, and
    /// a resume must fly as the campaign began.
    #[serde(default)]
    pub mock_gust_acc_m_s2: f64,
    /// Screen with the LFS (off: fly candidates in the order drawn, the paper's baseline without the LFS).
    #[serde(default = "default_screen")]
    pub screen: bool,
    /// The judge edition of the flights (2025's when the key is absent: the edition those files were judged by).
    #[serde(default = "judge_before_editions")]
    pub judge: Judge,
    /// Re-anchor each test at the vehicle's home (`--anchor-at-vehicle-home`).
    #[serde(default)]
    pub anchor_at_vehicle_home: bool,
    /// Clock rate of the MAVLink vehicles (`--hfs-time-scale`); `None`: measured on each vehicle at connection.
    #[serde(default)]
    pub hfs_time_scale: Option<f64>,
    /// Give a flight up (LAND) after this many vehicle seconds.
    #[serde(default = "default_flight_timeout_s")]
    pub flight_timeout_s: f64,
    /// Members of the LFS ensemble run on the shortlisted candidates to rank them by expected points per
    /// minute; 0 (also when the key is absent) ranks by the point prediction.
    #[serde(default)]
    pub ensemble: usize,
    /// Learn the vehicle as the campaign flies (online calibration of the LFS, flights in rounds).
    #[serde(default)]
    pub learn: bool,
    /// With `learn`, also adapt the generator's draw distribution towards failures.
    #[serde(default)]
    pub adapt: bool,
    /// A previous campaign's folder whose `learnt.json` seeds this one.
    #[serde(default)]
    pub prior: Option<PathBuf>,
    /// The adapted generator backs off when the failing tests' diversity falls below this.
    #[serde(default = "default_min_diversity")]
    pub min_diversity: f64,
    /// With `adapt`, a child of a failing flight may overlap a flown test up to this IoU (above `max_iou`)
    /// while the failing tests would keep `min_diversity` ([`super::plan::diversity_guard`]); `None` (also when the
    /// key is absent): children obey `max_iou` like every candidate.
    #[serde(default)]
    pub child_max_iou: Option<f64>,
    /// Flights a failing test gets at most (`--confirm`): it is flown again until the majority of this many
    /// flights is settled ([`super::fly::confirm`]); its flights feed its expected 2026 points. 1 (also
    /// when the key is absent: such campaigns flew every test once) is one flight per test.
    #[serde(default = "one_flight")]
    pub confirm: usize,
    /// Plan each learning round while the previous one flies ([`super::conductor`]); `false` (also when the key is
    /// absent: such campaigns planned after each round landed) plans after.
    #[serde(default)]
    pub overlap: bool,
    /// `--runner`: each flight is a job, this shell command template run per flight (`hfs` is then
    /// `["runner"]`); `None` (also when the key is absent) flies on `hfs`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub runner: Option<String>,
    /// `--jobs`: runner jobs at once, kept so a resumed campaign runs as many unless told otherwise; `None`
    /// (also when the key is absent): one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jobs: Option<usize>,
    /// PX4 SITL instances the campaign starts itself (`--px4`), each flight on a fresh one; `None` (also when
    /// the key is absent): the vehicles of `hfs`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub px4: Option<Px4Backend>,
}

fn one_flight() -> usize {
    1
}

/// How a `--px4` campaign starts its instances (their number is not stored: a resumed campaign may change it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Px4Backend {
    /// The user's `px4_sitl_default` build folder.
    pub build: PathBuf,
    /// `PX4_SIM_SPEED_FACTOR`.
    pub speed_factor: f64,
    /// Copy each flight's ULog beside its trajectory.
    #[serde(default)]
    pub keep_ulog: bool,
}

// A key absent from campaign.json means the setting's default where the default has never changed: the
// declaration's ([`super::settings`]), so it is written once.
fn default_min_diversity() -> f64 {
    Learning::default().min_diversity()
}

fn judge_before_editions() -> Judge {
    Judge::E2025
}

fn default_flight_timeout_s() -> f64 {
    Flight::default().timeout_s()
}

fn default_screen() -> bool {
    Screening::default().screen()
}

fn default_mode() -> String {
    "avoidance".into()
}

fn default_motion() -> String {
    Screening::default().motion()
}

pub use super::settings::keys::{DEFAULT_MOCK_LATENCY_MS, MAX_BUDGET, MAX_CANDIDATES};

fn default_mock_latency_ms() -> f64 {
    Mock::default().latency_ms()
}

fn profile_before_profiles() -> String {
    "competition".into()
}

fn mock_speed_before_key() -> f64 {
    20.0
}

impl CampaignConfig {
    /// The vehicles fly a test the same way for the same seed (the embedded mock in lockstep), so the fleet
    /// flies in waves and the campaign repeats bit for bit ([`super::fly::fleet::FleetSetup::waves`]).
    pub fn repeatable_vehicles(&self) -> bool {
        self.hfs == ["mock"] && self.mock_lockstep
    }

    /// The campaign learns between rounds: it screens, and learning is on.
    pub fn learns(&self) -> bool {
        self.learn && self.screen
    }

    /// A round is planned while the previous one flies: only when there are rounds to learn between, so a
    /// campaign without learning flies its one round as a single stage.
    pub fn overlaps_rounds(&self) -> bool {
        self.overlap && self.learns()
    }
}

/// Checks the campaign's counts before anything is drawn: a count out of range is refused, naming the limit.
pub fn check_counts(budget: usize, candidates: usize) -> Result<(), CampaignError> {
    if !(1..=MAX_BUDGET).contains(&budget) {
        return Err(CampaignError::Config(format!(
            "the budget {budget} is out of range: 1 to {MAX_BUDGET} flights"
        )));
    }
    if !(1..=MAX_CANDIDATES).contains(&candidates) {
        return Err(CampaignError::Config(format!(
            "--candidates (screening.candidates) {candidates} is out of range: 1 to {MAX_CANDIDATES}"
        )));
    }
    Ok(())
}
