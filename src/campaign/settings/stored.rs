//! The settings a campaign runs with, every one typed and resolved (`campaign.json` is this type as JSON:
//! [`super::json`]), and the views the stages take of them: what flies the campaign ([`Backend`]) and what a
//! fleet needs ([`FleetSettings`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::keys::{Campaign, Vehicles};
use super::keys_draw::{Output, Screening};
use super::keys_run::{Flight, Learning, Mock};
use crate::bridge::FlyMode;
use crate::generator::GeneratorConfig;
use crate::judge::Judge;
use crate::model::Spelling;

/// Everything that defines a campaign, by section, each setting as its declaration types it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignSettings {
    /// What the campaign is: case, budget, seed, mode, judge, prior.
    pub campaign: Campaign,
    /// What flies it.
    pub vehicles: Vehicles,
    /// The obstacle construction.
    pub generator: GeneratorConfig,
    /// The written files.
    pub output: Output,
    /// The low-fidelity screening.
    pub screening: Screening,
    /// The embedded mocks.
    pub mock: Mock,
    /// Every flight.
    pub flight: Flight,
    /// Learning between rounds.
    pub learning: Learning,
}

/// What a fleet of vehicles needs to fly and judge flights: a campaign's, or an evaluation's.
#[derive(Debug, Clone, Copy)]
pub struct FleetSettings<'a> {
    /// How the flights avoid the boxes.
    pub mode: FlyMode,
    /// The judge edition.
    pub judge: Judge,
    /// Seed of the embedded mocks' gusts.
    pub seed: u64,
    /// What flies them.
    pub vehicles: &'a Vehicles,
    /// The embedded mocks.
    pub mock: &'a Mock,
    /// Every flight.
    pub flight: &'a Flight,
    /// The spelling of the tests a runner job gets.
    pub spelling: Spelling,
}

impl<'a> FleetSettings<'a> {
    /// What flies them.
    pub fn backend(&self) -> Backend<'a> {
        backend_of(self.vehicles)
    }
}

/// What `v` names.
fn backend_of(v: &Vehicles) -> Backend<'_> {
    match (&v.runner, &v.px4, &v.hitl) {
        (Some(t), ..) => Backend::Runner(t),
        (None, Some(b), _) => Backend::Px4(b),
        (None, None, Some(boards)) => Backend::Hitl(boards),
        (None, None, None) if v.connect == ["mock"] => Backend::Mock,
        (None, None, None) => Backend::Links(&v.connect),
    }
}

/// What flies a campaign, as its `[vehicles]` settings name it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend<'a> {
    /// The embedded mock autopilots.
    Mock,
    /// The vehicles at these MAVLink URLs, one flight each at a time.
    Links(&'a [String]),
    /// PX4 SITL instances started here from this build folder.
    Px4(&'a Path),
    /// A job per flight, this shell command template.
    Runner(&'a str),
    /// Boards in the loop on these serial ports, fed by prgenuav's simulator.
    Hitl(&'a [String]),
}

impl CampaignSettings {
    /// What flies the campaign (a runner's command may itself start PX4, so a runner wins over `px4`; the
    /// check refuses both given together).
    pub fn backend(&self) -> Backend<'_> {
        backend_of(&self.vehicles)
    }

    /// What the fleet needs of these settings.
    pub fn flights(&self) -> FleetSettings<'_> {
        FleetSettings {
            mode: self.campaign.mode,
            judge: self.campaign.judge,
            seed: self.campaign.seed,
            vehicles: &self.vehicles,
            mock: &self.mock,
            flight: &self.flight,
            spelling: self.output.spelling,
        }
    }

    /// The embedded mocks fly it.
    pub fn on_mock(&self) -> bool {
        self.backend() == Backend::Mock
    }

    /// The vehicles fly a test the same way for the same seed (the embedded mock in lockstep), so the fleet
    /// flies in waves and the campaign repeats bit for bit ([`crate::campaign::fly::fleet::FleetSetup::waves`]).
    pub fn repeatable_vehicles(&self) -> bool {
        self.on_mock() && self.mock.lockstep
    }

    /// The campaign learns between rounds: it screens, and learning is on.
    pub fn learns(&self) -> bool {
        self.learning.learn && self.screening.screen
    }

    /// The adapted generator draws towards failures (a learning campaign with `adapt`).
    pub fn adapts(&self) -> bool {
        self.learns() && self.learning.adapt
    }

    /// A round is planned while the previous one flies: only when there are rounds to learn between, so a
    /// campaign without learning flies its one round as a single stage.
    pub fn overlaps_rounds(&self) -> bool {
        self.flight.overlap && self.learns()
    }

    /// The paths the settings hold, named as errors name them.
    pub fn paths(&self) -> [(&'static str, Option<&PathBuf>); 3] {
        [
            ("the case", Some(&self.campaign.case)),
            ("--prior", self.campaign.prior.as_ref()),
            ("--px4", self.vehicles.px4.as_ref()),
        ]
    }
}
