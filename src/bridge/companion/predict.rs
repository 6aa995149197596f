//! The low-fidelity simulator's prediction for a test, computed before the flight and reported beside it.

use crate::judge::Judge;
use crate::lfs::camera::Camera;
use crate::lfs::sim::{MotionModel, SimConfig, simulate};
use crate::model::{TestCase, Trajectory};

/// What the LFS predicts.
#[derive(Debug, Clone)]
pub struct Prediction {
    /// The minimum distance of the simulated flight by the judge edition asked for, metres (`None` without
    /// obstacles).
    pub min_distance: Option<f64>,
    /// The simulated trajectory (Aerialist frame).
    pub trajectory: Trajectory,
}

/// Simulates `test` with `motion` (the `px4` model follows the same waypoint generator the bridge flies with)
/// and the competition's camera, judged by `judge` as the flight will be; `Err` says why it could not.
pub fn predict(test: &TestCase, motion: MotionModel, judge: Judge) -> Result<Prediction, String> {
    let config = SimConfig {
        motion,
        camera: Camera::hfs(),
        judge,
        ..SimConfig::default()
    };
    let r = simulate(test, &config).map_err(|e| e.to_string())?;
    Ok(Prediction {
        min_distance: r.distance.map(|d| d.min_distance),
        trajectory: r.trajectory,
    })
}

/// The Collision Prevention model's prediction ([`crate::lfs::cp_model`]) for `test` with its CP parameters.
pub fn predict_cp(test: &TestCase, judge: Judge) -> Result<Prediction, String> {
    use crate::lfs::cp_model::{CpSimConfig, simulate_cp};
    let cp = crate::lfs::cp_params::CpParams::from_params(&test.params)?;
    let config = CpSimConfig {
        judge,
        ..CpSimConfig::default()
    };
    let p = simulate_cp(test, &cp, &config);
    Ok(Prediction {
        min_distance: p.min_distance,
        trajectory: p.trajectory,
    })
}
