//! One parameter struct for the 3DVFH* port, holding the effective defaults of PX4-Avoidance HEAD
//! (docs/planner.md §14).

use super::PlannerError;
use super::fov::Fov;
use super::fov_estimate::FovEstimate;

/// Weights of the per-direction cost function (docs/planner.md §5.2). Defaults are the dynamic-reconfigure (cfg)
/// values, which overwrite the C++ struct defaults at start-up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostParams {
    /// k_yaw, cost per squared degree of azimuth away from the goal (or line).
    pub yaw_cost: f32,
    /// k_pitch, cost per squared degree of elevation away from the goal.
    pub pitch_cost: f32,
    /// k_v, cost per m/s of velocity not along the candidate direction.
    pub velocity_cost: f32,
    /// k_obs in metres: the centre of the distance-cost sigmoid.
    pub obstacle_cost_m: f32,
}

impl Default for CostParams {
    fn default() -> Self {
        Self {
            yaw_cost: 3.0,
            pitch_cost: 25.0,
            velocity_cost: 6000.0,
            obstacle_cost_m: 8.5,
        }
    }
}

impl CostParams {
    /// The C++ `costParameters` struct defaults (0.5, 3, 1.5, 5), used by AV's own star-planner unit test.
    pub fn struct_defaults() -> Self {
        Self {
            yaw_cost: 0.5,
            pitch_cost: 3.0,
            velocity_cost: 1.5,
            obstacle_cost_m: 5.0,
        }
    }
}

/// All planner parameters (ranges in metres, angles in degrees, times in seconds, speeds in m/s).
#[derive(Debug, Clone, PartialEq)]
pub struct PlannerParams {
    /// Cost-function weights.
    pub cost: CostParams,
    /// New points closer than this are dropped; also the lower bound of the goal-facing test (0.2 m).
    pub min_sensor_range_m: f32,
    /// Points farther than this are dropped; also the tree's expansion radius (15 m).
    pub max_sensor_range_m: f32,
    /// Remembered points older than this are forgotten (20 s).
    pub max_point_age_s: f32,
    /// The N-th point of each 2-degree cell is kept (1 in SITL).
    pub min_num_points_per_cell: u32,
    /// Smoothing margin of the distance cost (40 deg, i.e. 7 cells).
    pub smoothing_margin_deg: f32,
    /// Candidates per expanded node (8).
    pub children_per_node: usize,
    /// Maximum number of expansions (40).
    pub n_expanded_nodes: usize,
    /// Edge length of the tree (2 m).
    pub tree_node_distance_m: f32,
    /// Heuristic weight per metre to the goal (35).
    pub tree_heuristic_weight: f32,
    /// Camera FOVs in the body frame (one per camera); with [`FovEstimate::FromMaxima`] the planner starts them
    /// at zero and widens the first from each frame.
    pub fovs: Vec<Fov>,
    /// Whether `fovs` stay fixed or are estimated from the clouds as the original does.
    pub fov_estimate: FovEstimate,
    /// PX4 MPC_XY_CRUISE in m/s (5 in PX4 and the competition's `iris_obs_avoid` airframe).
    pub mpc_xy_cruise_m_s: f32,
    /// PX4 MPC_ACC_HOR in m/s^2 (PX4 default 3), for the sensor-range speed limit.
    pub mpc_acc_hor_m_s2: f32,
    /// PX4 MPC_JERK_MAX in m/s^3 (PX4 default 8), for the sensor-range speed limit.
    pub mpc_jerk_max_m_s3: f32,
    /// Mission item speed (a DO_CHANGE_SPEED before the current item), if any; replaces MPC_XY_CRUISE.
    pub mission_item_speed_m_s: Option<f32>,
}

impl Default for PlannerParams {
    fn default() -> Self {
        Self {
            cost: CostParams::default(),
            min_sensor_range_m: 0.2,
            max_sensor_range_m: 15.0,
            max_point_age_s: 20.0,
            min_num_points_per_cell: 1,
            smoothing_margin_deg: 40.0,
            children_per_node: 8,
            n_expanded_nodes: 40,
            tree_node_distance_m: 2.0,
            tree_heuristic_weight: 35.0,
            // The competition's HFS camera: 640 x 480 at 59 deg (1.02974 rad) horizontal FOV.
            fovs: vec![Fov::from_pinhole(640, 480, 59.0)],
            fov_estimate: FovEstimate::default(),
            mpc_xy_cruise_m_s: 5.0,
            mpc_acc_hor_m_s2: 3.0,
            mpc_jerk_max_m_s3: 8.0,
            mission_item_speed_m_s: None,
        }
    }
}

impl PlannerParams {
    /// Checks that every parameter is finite and in a range the algorithm can work with.
    pub fn validate(&self) -> Result<(), PlannerError> {
        let bad = |name: &'static str, value: f32| {
            Err(PlannerError::InvalidParam {
                name,
                value: value as f64,
            })
        };
        let finite_pos = [
            ("min_sensor_range_m", self.min_sensor_range_m, true),
            ("max_sensor_range_m", self.max_sensor_range_m, false),
            ("max_point_age_s", self.max_point_age_s, true),
            ("smoothing_margin_deg", self.smoothing_margin_deg, true),
            ("tree_node_distance_m", self.tree_node_distance_m, false),
            ("tree_heuristic_weight", self.tree_heuristic_weight, true),
            ("mpc_xy_cruise_m_s", self.mpc_xy_cruise_m_s, false),
            ("mpc_acc_hor_m_s2", self.mpc_acc_hor_m_s2, false),
            ("mpc_jerk_max_m_s3", self.mpc_jerk_max_m_s3, false),
            ("cost.yaw_cost", self.cost.yaw_cost, true),
            ("cost.pitch_cost", self.cost.pitch_cost, true),
            ("cost.velocity_cost", self.cost.velocity_cost, true),
            ("cost.obstacle_cost_m", self.cost.obstacle_cost_m, true),
        ];
        for (name, v, zero_ok) in finite_pos {
            if !v.is_finite() || v < 0.0 || (!zero_ok && v == 0.0) {
                return bad(name, v);
            }
        }
        if self.min_sensor_range_m >= self.max_sensor_range_m {
            return bad("min_sensor_range_m", self.min_sensor_range_m);
        }
        if self.smoothing_margin_deg > 90.0 {
            return bad("smoothing_margin_deg", self.smoothing_margin_deg);
        }
        if self.min_num_points_per_cell == 0 {
            return bad("min_num_points_per_cell", 0.0);
        }
        if self.children_per_node == 0 {
            return bad("children_per_node", 0.0);
        }
        if let Some(s) = self.mission_item_speed_m_s
            && (!s.is_finite() || s <= 0.0)
        {
            return bad("mission_item_speed_m_s", s);
        }
        for f in &self.fovs {
            for (name, v) in [("fov.h_fov_deg", f.h_fov_deg), ("fov.v_fov_deg", f.v_fov_deg)] {
                if !v.is_finite() || !(0.0..=360.0).contains(&v) {
                    return bad(name, v);
                }
            }
        }
        Ok(())
    }

    /// Smoothing radius in cells: `ceil(margin / ALPHA_RES)` (7 for 40 deg).
    pub fn smoothing_radius(&self) -> usize {
        (self.smoothing_margin_deg / super::polar::ALPHA_RES as f32).ceil() as usize
    }

    /// Cruise speed handed to the waypoint generator (docs/planner.md §7.6): the mission speed or MPC_XY_CRUISE, capped
    /// by the speed from which the vehicle can stop within the sensor range.
    pub fn cruise_speed_m_s(&self) -> f32 {
        let a = self.mpc_acc_hor_m_s2;
        let ramp = a / self.mpc_jerk_max_m_s3;
        let b = 2.0 * a * ramp;
        let c = 2.0 * -a * self.max_sensor_range_m;
        let limited = (-b + (b * b - 4.0 * c).sqrt()) / 2.0;
        self.mission_item_speed_m_s
            .unwrap_or(self.mpc_xy_cruise_m_s)
            .min(limited)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_match_spec() {
        let p = PlannerParams::default();
        p.validate().unwrap();
        assert_eq!(p.smoothing_radius(), 7);
        assert_eq!(p.cruise_speed_m_s(), 5.0);
    }

    #[test]
    fn sensor_range_speed_limit_known_answers() {
        // docs/planner.md §7.6: A = 5, J = 20, R = 15 -> ~11.1 m/s; A = 3, J = 8 -> ~8.4 m/s.
        let mut p = PlannerParams {
            mpc_xy_cruise_m_s: 100.0,
            mpc_acc_hor_m_s2: 5.0,
            mpc_jerk_max_m_s3: 20.0,
            ..Default::default()
        };
        assert!((p.cruise_speed_m_s() - 11.1).abs() < 0.05, "{}", p.cruise_speed_m_s());
        p.mpc_acc_hor_m_s2 = 3.0;
        p.mpc_jerk_max_m_s3 = 8.0;
        assert!((p.cruise_speed_m_s() - 8.4).abs() < 0.05, "{}", p.cruise_speed_m_s());
        p.mission_item_speed_m_s = Some(3.0);
        assert_eq!(p.cruise_speed_m_s(), 3.0);
    }

    #[test]
    fn bad_params_are_errors() {
        let p = PlannerParams {
            max_sensor_range_m: f32::NAN,
            ..Default::default()
        };
        assert!(p.validate().is_err());
        let p = PlannerParams {
            min_sensor_range_m: 20.0,
            ..Default::default()
        };
        assert!(p.validate().is_err());
        let p = PlannerParams {
            children_per_node: 0,
            ..Default::default()
        };
        assert!(p.validate().is_err());
        let p = PlannerParams {
            mission_item_speed_m_s: Some(-1.0),
            ..Default::default()
        };
        let err = p.validate().unwrap_err().to_string();
        assert!(err.contains("mission_item_speed_m_s"), "{err}");
    }
}
