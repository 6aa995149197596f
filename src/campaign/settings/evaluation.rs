//! The settings an evaluation flies a suite with: the mode, the judge, the seed, the vehicles and every
//! flight's settings, by section as a campaign holds them. A suite that is a campaign's folder is flown as the
//! campaign was (its mode, its mock, its judge), unless a flag asks otherwise; a backend asked for replaces the
//! suite's. An evaluation keeps its settings, and a later run of it is refused a fixed setting asked otherwise
//! ([`super::resume`]), so one test's runs never mix two modes or two vehicles.

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::keys::Vehicles;
use super::keys_draw::Output;
use super::keys_run::{Flight, Mock};
use super::request::Request;
use super::resolve::setup_of;
use super::rules::Setup;
use super::stored::{CampaignSettings, FleetSettings};
use super::{Resume, Setting, all};
use crate::bridge::FlyMode;
use crate::judge::Judge;

/// The `[campaign]` settings an evaluation has a use for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Flying {
    /// How the flights avoid the boxes.
    pub mode: FlyMode,
    /// The judge edition.
    pub judge: Judge,
    /// Seed of the embedded mocks' gusts.
    pub seed: u64,
}

/// What an evaluation's flights fly with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvaluationSettings {
    /// The mode, the judge, the seed.
    pub campaign: Flying,
    /// What flies them.
    pub vehicles: Vehicles,
    /// The embedded mocks.
    pub mock: Mock,
    /// Every flight.
    pub flight: Flight,
    /// The spelling of the tests runner jobs get.
    pub output: Output,
}

/// Whether an evaluation keeps setting `s` (the others are a campaign's alone).
pub fn kept(s: &Setting) -> bool {
    matches!(s.section, "vehicles" | "mock" | "flight" | "output")
        || (s.section == "campaign" && matches!(s.key, "mode" | "judge" | "seed"))
}

impl EvaluationSettings {
    /// What `request` asks, laid over `suite`'s campaign settings when the suite is a campaign's folder (else
    /// over the defaults).
    pub fn resolve(request: &Request, suite: Option<&CampaignSettings>) -> Result<Self, String> {
        let a = &request.asked;
        let setup = setup_of(request);
        let Some(suite) = suite else {
            return Ok(Self {
                campaign: Flying {
                    mode: a.campaign.mode(),
                    judge: a.campaign.judge(),
                    seed: a.campaign.seed(),
                },
                vehicles: a.vehicles.resolve(&setup)?,
                mock: a.mock.resolve(&setup)?,
                flight: a.flight.resolve(&setup)?,
                output: a.output.resolve(&setup)?,
            });
        };
        let backend_asked = ["connect", "runner", "px4"]
            .iter()
            .any(|k| request.gives("vehicles", k));
        let vehicles = if backend_asked {
            // A suite flown on a named bench is evaluated on it when --px4 comes without --bench.
            let mut asked = a.vehicles.clone();
            if asked.px4.is_some() && suite.vehicles.px4.is_some() {
                asked.bench = asked.bench.or(Some(suite.vehicles.bench));
            }
            let setup = Setup {
                bench: asked.bench(),
                ..setup
            };
            asked.resolve(&setup)?
        } else {
            suite.vehicles.overridden(&a.vehicles)
        };
        let c = &suite.campaign;
        Ok(Self {
            campaign: Flying {
                mode: a.campaign.mode.unwrap_or(c.mode),
                judge: a.campaign.judge.unwrap_or(c.judge),
                seed: a.campaign.seed.unwrap_or(c.seed),
            },
            vehicles: as_asked_again(&vehicles, &a.vehicles.resolve(&setup)?, "vehicles")?,
            mock: as_asked_again(&suite.mock.overridden(&a.mock), &a.mock.resolve(&setup)?, "mock")?,
            flight: as_asked_again(
                &suite.flight.overridden(&a.flight),
                &a.flight.resolve(&setup)?,
                "flight",
            )?,
            output: suite.output.overridden(&a.output),
        })
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
}

/// `kept` with the keys of `section` a resumed run takes as asked again ([`Resume::Asked`]) from `fresh`.
fn as_asked_again<T: Serialize + DeserializeOwned>(kept: &T, fresh: &T, section: &str) -> Result<T, String> {
    let mut k = serde_json::to_value(kept).map_err(|e| e.to_string())?;
    let f = serde_json::to_value(fresh).map_err(|e| e.to_string())?;
    for s in all().filter(|s| s.section == section && s.resume == Resume::Asked) {
        if let (Some(o), Some(v)) = (k.as_object_mut(), f.get(s.key)) {
            o.insert(s.key.to_string(), v.clone());
        }
    }
    serde_json::from_value(k).map_err(|e| e.to_string())
}
