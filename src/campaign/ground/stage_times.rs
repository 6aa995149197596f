//! How long each stage of a campaign took, and how busy its vehicles were while they flew.

use serde::Serialize;

/// Wall time of each stage, seconds.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Drawing the candidates.
    pub sample_s: f64,
    /// Low-fidelity screening.
    pub screen_s: f64,
    /// The LFS ensemble on the shortlisted candidates.
    pub ensemble_s: f64,
    /// Online learning: calibrating the LFS on the flights, re-ranking, adapting the generator.
    pub learn_s: f64,
    /// High-fidelity flights.
    pub fly_s: f64,
    /// Writing the outputs.
    pub report_s: f64,
    /// Vehicle-seconds the vehicles spent flying, summed over the flight stages.
    pub vehicle_busy_s: f64,
    /// Vehicle-seconds available from each stage's first take-off to its last landing (vehicles x span).
    pub vehicle_span_s: f64,
}

impl StageTimes {
    /// Counts a fleet's use of its vehicles.
    pub fn add_fleet(&mut self, fleet: FleetUse) {
        self.vehicle_busy_s += fleet.busy_s;
        self.vehicle_span_s += fleet.vehicles as f64 * fleet.span_s;
    }

    /// Share of the vehicle time from take-off to last landing the vehicles waited (on screening, learning, or
    /// the last flights of a round); `None` before any flight.
    pub fn vehicles_idle(&self) -> Option<f64> {
        (self.vehicle_span_s > 0.0).then(|| (1.0 - self.vehicle_busy_s / self.vehicle_span_s).clamp(0.0, 1.0))
    }
}

/// How busy a fleet's vehicles were, wall time.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FleetUse {
    /// Vehicles at the start.
    pub vehicles: usize,
    /// Seconds the vehicles spent flying (setting up, in the air, landing), summed over the vehicles.
    pub busy_s: f64,
    /// Seconds from the first take-off to the last landing.
    pub span_s: f64,
}
