//! Every section of a campaign's settings as asked: each key given by the campaign TOML or a flag, or not,
//! typed once by serde.

use serde::{Deserialize, Serialize};

use super::keys::{CampaignAsked, VehiclesAsked};
use super::keys_draw::{OutputAsked, ScreeningAsked};
use super::keys_run::{FlightAsked, LearningAsked, MockAsked};
use crate::generator::GeneratorConfig;

/// Every section as asked.
#[derive(Debug, Default, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Asked {
    /// `[campaign]` (flags only).
    #[serde(default)]
    pub campaign: CampaignAsked,
    /// `[vehicles]` (flags only).
    #[serde(default)]
    pub vehicles: VehiclesAsked,
    /// `[generator]`: the generator's own configuration, its defaults under the keys given.
    #[serde(default)]
    pub generator: Option<GeneratorConfig>,
    /// `[output]`.
    #[serde(default)]
    pub output: OutputAsked,
    /// `[screening]`.
    #[serde(default)]
    pub screening: ScreeningAsked,
    /// `[mock]`.
    #[serde(default)]
    pub mock: MockAsked,
    /// `[flight]`.
    #[serde(default)]
    pub flight: FlightAsked,
    /// `[learning]`.
    #[serde(default)]
    pub learning: LearningAsked,
}

impl Asked {
    /// The sections of `raw` as typed, the generator's checked.
    pub fn typed(raw: &toml::Table) -> Result<Self, String> {
        let asked: Self = toml::Value::Table(raw.clone())
            .try_into()
            .map_err(|e: toml::de::Error| e.to_string())?;
        if let Some(g) = &asked.generator {
            g.validate().map_err(|e| format!("[generator] {e}"))?;
        }
        Ok(asked)
    }
}
