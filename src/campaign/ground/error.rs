//! Why a campaign stops early, whichever stage stops it.

use crate::generator::GenerateError;
use crate::model::ModelError;

/// Why a campaign stopped early.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// A file could not be read or written.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The generator could not place obstacles.
    #[error(transparent)]
    Generate(#[from] GenerateError),
    /// Bad settings.
    #[error("{0}")]
    Config(String),
    /// No vehicle could be reached.
    #[error("no reachable vehicle: {0}")]
    NoVehicle(String),
}
