//! One planner iteration (docs/planner.md §7, AV `LocalPlanner::runPlanner` / `determineStrategy` /
//! `getAvoidanceOutput`) behind a pure API: points and poses in, path out; time is always a parameter.

use nalgebra::{Vector2, Vector3};

use super::PlannerError;
use super::cloud::{CloudPose, PointMemory};
use super::fov::Fov;
use super::fov_estimate::{BodyPose, FovEstimate, update_from_cloud};
use super::histogram::{Histogram, HistogramScratch};
use super::params::PlannerParams;
use super::polar::RAD_TO_DEG;
use super::tree::{StarPlanner, TreeInputs, TreeNode};

/// The vehicle's state in the planner frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleState {
    /// Position, ENU metres (x East, y North, z Up).
    pub position_enu: Vector3<f32>,
    /// Velocity, ENU m/s.
    pub velocity_enu: Vector3<f32>,
    /// ENU yaw in radians, counter-clockwise from East (PX4 yaw `psi` gives `pi/2 - psi`, see `frames`).
    pub yaw_enu_rad: f32,
    /// Pitch in radians, positive nose-down (so the body-fixed camera looks down); 0 for a level vehicle.
    pub pitch_rad: f32,
}

impl VehicleState {
    fn check(&self) -> Result<(), PlannerError> {
        let finite = self
            .position_enu
            .iter()
            .chain(self.velocity_enu.iter())
            .all(|v| v.is_finite())
            && self.yaw_enu_rad.is_finite()
            && self.pitch_rad.is_finite();
        if finite {
            Ok(())
        } else {
            Err(PlannerError::InvalidInput {
                name: "vehicle state",
                detail: format!("not finite: {self:?}"),
            })
        }
    }
}

/// Inputs of one planning iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanInput {
    /// Vehicle state at planning time.
    pub state: VehicleState,
    /// Current target waypoint, ENU metres (the goal itself, however far; nothing clamps it).
    pub goal_enu: Vector3<f32>,
    /// Previous target waypoint, ENU metres (use the start position or the goal if there is none).
    pub prev_goal_enu: Vector3<f32>,
    /// Simulation time in seconds.
    pub now_s: f64,
}

/// The planner output handed to the waypoint generator (`avoidanceOutput`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Plan {
    /// Tree path, ENU metres: **index 0 = deepest node, last = root** (the vehicle at `path_time_s`).
    /// Empty until a tree was first built.
    pub path_enu: Vec<Vector3<f32>>,
    /// Simulation time at which `path_enu` was built; `None` before the first tree.
    pub path_time_s: Option<f64>,
    /// Cruise speed for following the path, m/s.
    pub cruise_speed_m_s: f32,
    /// True if this iteration built a new tree; false if the histogram at the vehicle was empty and the previous
    /// path was kept.
    pub replanned: bool,
}

/// The 3DVFH* planner: point memory plus star planner. Construct once per flight.
#[derive(Debug, Clone)]
pub struct Planner {
    params: PlannerParams,
    memory: PointMemory,
    star: StarPlanner,
    vehicle_hist: Histogram,
    hist_scratch: HistogramScratch,
    plan: Plan,
    closest_pt: Option<Vector3<f32>>,
    optical_scratch: Vec<Vector3<f32>>,
}

impl Planner {
    /// A planner with validated parameters.
    pub fn new(mut params: PlannerParams) -> Result<Self, PlannerError> {
        params.validate()?;
        if params.fov_estimate == FovEstimate::FromMaxima {
            // The original's FOV() before the first cloud: nothing is inside it.
            params.fovs.iter_mut().for_each(|f| *f = Fov::default());
        }
        let cruise = params.cruise_speed_m_s();
        Ok(Self {
            params,
            memory: PointMemory::new(),
            star: StarPlanner::new(),
            vehicle_hist: Histogram::new(),
            hist_scratch: HistogramScratch::default(),
            plan: Plan {
                cruise_speed_m_s: cruise,
                ..Plan::default()
            },
            closest_pt: None,
            optical_scratch: Vec::new(),
        })
    }

    /// The camera FOVs in use (the current estimate with [`FovEstimate::FromMaxima`]).
    pub fn fovs(&self) -> &[Fov] {
        &self.params.fovs
    }

    /// The parameters in use.
    pub fn params(&self) -> &PlannerParams {
        &self.params
    }

    /// Feeds one camera frame (`processPointcloud`): `points_enu` are world-frame ENU points (NaNs allowed and
    /// ignored) seen at `state`, `elapsed_s` seconds after the previous frame (ages grow by it).
    pub fn update_cloud(
        &mut self,
        points_enu: &[Vector3<f32>],
        state: &VehicleState,
        elapsed_s: f32,
    ) -> Result<(), PlannerError> {
        state.check()?;
        if !elapsed_s.is_finite() || elapsed_s < 0.0 {
            return Err(PlannerError::InvalidInput {
                name: "elapsed_s",
                detail: format!("{elapsed_s} is not >= 0"),
            });
        }
        // The original widens the FOV in the cloud's transform thread, before the planner processes that cloud.
        // One merged cloud comes in, so only a single camera's FOV can be estimated.
        if self.params.fov_estimate == FovEstimate::FromMaxima
            && let [fov] = self.params.fovs.as_mut_slice()
        {
            let body = BodyPose {
                position_enu: state.position_enu,
                yaw_enu_rad: state.yaw_enu_rad,
                pitch_rad: state.pitch_rad,
            };
            update_from_cloud(fov, points_enu, &body, &mut self.optical_scratch);
        }
        let pose = CloudPose {
            position_enu: state.position_enu,
            yaw_enu_deg: state.yaw_enu_rad * RAD_TO_DEG,
            pitch_deg: state.pitch_rad * RAD_TO_DEG,
        };
        self.memory.process(points_enu, &pose, &self.params, elapsed_s);
        Ok(())
    }

    /// Runs one planning iteration on the current memory. If the histogram at the vehicle is empty, no tree is
    /// built and the previous path (with its old time) is returned, as the original does.
    pub fn plan(&mut self, input: &PlanInput) -> Result<&Plan, PlannerError> {
        input.state.check()?;
        let finite = input
            .goal_enu
            .iter()
            .chain(input.prev_goal_enu.iter())
            .all(|v| v.is_finite());
        if !finite || !input.now_s.is_finite() {
            return Err(PlannerError::InvalidInput {
                name: "plan input",
                detail: format!("not finite: {input:?}"),
            });
        }
        let pos = input.state.position_enu;
        let (xs, ys, zs) = self.memory.soa();
        self.vehicle_hist
            .build_from_soa(xs, ys, zs, &pos, &mut self.hist_scratch);
        let closest = closest_point_on_line(
            &pos,
            &input.goal_enu,
            &input.prev_goal_enu,
            self.params.mpc_xy_cruise_m_s,
        );
        self.closest_pt = Some(closest);
        self.plan.cruise_speed_m_s = self.params.cruise_speed_m_s();
        self.plan.replanned = false;
        if !self.vehicle_hist.is_empty() {
            let inputs = TreeInputs {
                position: pos,
                velocity: input.state.velocity_enu,
                goal: input.goal_enu,
                closest_pt: closest,
            };
            let path =
                self.star
                    .build_with_root_histogram(&self.memory, &inputs, &self.params, Some(&self.vehicle_hist));
            self.plan.path_enu.clear();
            self.plan.path_enu.extend_from_slice(path);
            self.plan.path_time_s = Some(input.now_s);
            self.plan.replanned = true;
        }
        Ok(&self.plan)
    }

    /// The latest plan.
    pub fn last_plan(&self) -> &Plan {
        &self.plan
    }

    /// The processed point cloud (memory).
    pub fn memory(&self) -> &PointMemory {
        &self.memory
    }

    /// The histogram at the vehicle from the last [`Planner::plan`].
    pub fn vehicle_histogram(&self) -> &Histogram {
        &self.vehicle_hist
    }

    /// The nodes of the last tree (index 0 = root).
    pub fn tree(&self) -> &[TreeNode] {
        self.star.nodes()
    }

    /// The line-pull point used by the last [`Planner::plan`], if any.
    pub fn closest_point(&self) -> Option<Vector3<f32>> {
        self.closest_pt
    }
}

/// The vehicle's xy projection onto the line prev_goal -> goal with z = goal.z (docs/planner.md §7.3); the goal itself
/// when the vehicle is nearer the line than `mpc_xy_cruise` (a speed used as a distance, as in the original) or
/// the two goals coincide in xy.
pub fn closest_point_on_line(
    pos: &Vector3<f32>,
    goal: &Vector3<f32>,
    prev_goal: &Vector3<f32>,
    mpc_xy_cruise: f32,
) -> Vector3<f32> {
    let d = Vector2::new(goal.x - prev_goal.x, goal.y - prev_goal.y);
    // Eigen's normalized() leaves a zero vector unchanged.
    let u = if d.norm_squared() > 0.0 { d / d.norm() } else { d };
    let prev_to_pos = Vector2::new(pos.x - prev_goal.x, pos.y - prev_goal.y);
    let xy = Vector2::new(prev_goal.x, prev_goal.y) + u * u.dot(&prev_to_pos);
    let c = Vector3::new(xy.x, xy.y, goal.z);
    let off_line = Vector2::new(pos.x - c.x, pos.y - c.y).norm();
    if off_line < mpc_xy_cruise || d.norm() < 0.001 {
        *goal
    } else {
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(p: Vector3<f32>) -> VehicleState {
        VehicleState {
            position_enu: p,
            velocity_enu: Vector3::zeros(),
            yaw_enu_rad: std::f32::consts::FRAC_PI_2,
            pitch_rad: 0.0,
        }
    }

    #[test]
    fn closest_point_rules() {
        let prev = Vector3::new(0.0, 0.0, 2.0);
        let goal = Vector3::new(0.0, 20.0, 4.0);
        // 10 m off the line: projection with the goal's height.
        let c = closest_point_on_line(&Vector3::new(10.0, 5.0, 3.0), &goal, &prev, 5.0);
        assert_eq!(c, Vector3::new(0.0, 5.0, 4.0));
        // Within MPC_XY_CRUISE of the line: the goal.
        assert_eq!(
            closest_point_on_line(&Vector3::new(3.0, 5.0, 3.0), &goal, &prev, 5.0),
            goal
        );
        // Coinciding goals: the goal.
        assert_eq!(
            closest_point_on_line(&Vector3::new(30.0, 5.0, 3.0), &goal, &goal, 5.0),
            goal
        );
    }

    #[test]
    fn empty_memory_keeps_the_previous_path() {
        // The fixed camera FOV: an estimate from the wall alone would be 0 deg tall, and the wall remembered.
        let mut p = Planner::new(PlannerParams {
            fov_estimate: FovEstimate::Fixed,
            ..Default::default()
        })
        .unwrap();
        let goal = Vector3::new(0.0, 30.0, 5.0);
        let input = PlanInput {
            state: state(Vector3::new(0.0, 0.0, 5.0)),
            goal_enu: goal,
            prev_goal_enu: goal,
            now_s: 1.0,
        };
        let plan = p.plan(&input).unwrap();
        assert!(!plan.replanned && plan.path_enu.is_empty() && plan.path_time_s.is_none());
        // Something seen: a tree is built.
        let wall: Vec<_> = (-20..=20).map(|i| Vector3::new(i as f32 * 0.1, 6.0, 5.0)).collect();
        p.update_cloud(&wall, &input.state, 0.1).unwrap();
        let plan = p.plan(&PlanInput { now_s: 1.1, ..input }).unwrap().clone();
        assert!(plan.replanned && plan.path_enu.len() >= 2);
        assert_eq!(plan.path_time_s, Some(1.1));
        assert_eq!(
            *plan.path_enu.last().unwrap_or(&Vector3::zeros()),
            input.state.position_enu
        );
        // The wall is in view (yaw North) and no longer seen: forgotten; the old path and time remain.
        p.update_cloud(&[], &input.state, 0.1).unwrap();
        let again = p.plan(&PlanInput { now_s: 1.2, ..input }).unwrap();
        assert!(!again.replanned);
        assert_eq!(again.path_enu, plan.path_enu);
        assert_eq!(again.path_time_s, Some(1.1));
    }

    #[test]
    fn estimated_fov_starts_at_zero_and_grows_from_frames() {
        let fixed = Planner::new(PlannerParams {
            fov_estimate: FovEstimate::Fixed,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(fixed.fovs(), PlannerParams::default().fovs.as_slice());
        let mut p = Planner::new(PlannerParams {
            fov_estimate: FovEstimate::FromMaxima,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(p.fovs(), &[Fov::default()]);
        // Facing North at 5 m: a point 10 m ahead level, one 10 m ahead and 10 m East (45 deg right), one on
        // the ground straight ahead (26.6 deg below).
        let s = state(Vector3::new(0.0, 0.0, 5.0));
        let pts = [
            Vector3::new(0.0, 10.0, 5.0),
            Vector3::new(10.0, 10.0, 5.0),
            Vector3::new(0.0, 10.0, 0.0),
        ];
        p.update_cloud(&pts, &s, 0.1).unwrap();
        let f = p.fovs()[0];
        assert!(
            (f.h_fov_deg - 45.0).abs() < 1e-3 && (f.yaw_deg + 22.5).abs() < 1e-3,
            "{f:?}"
        );
        let below = 0.5f32.atan().to_degrees();
        assert!(
            (f.v_fov_deg - below).abs() < 1e-3 && (f.pitch_deg - below / 2.0).abs() < 1e-3,
            "{f:?}"
        );
        // An empty frame leaves it as it is.
        p.update_cloud(&[], &s, 0.1).unwrap();
        assert_eq!(p.fovs()[0], f);
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(
            Planner::new(PlannerParams {
                tree_node_distance_m: -1.0,
                ..Default::default()
            })
            .is_err()
        );
        let mut p = Planner::new(PlannerParams::default()).unwrap();
        let s = state(Vector3::new(0.0, 0.0, f32::NAN));
        assert!(p.update_cloud(&[], &s, 0.1).is_err());
        assert!(p.update_cloud(&[], &state(Vector3::zeros()), -0.1).is_err());
        let input = PlanInput {
            state: state(Vector3::zeros()),
            goal_enu: Vector3::new(f32::INFINITY, 0.0, 0.0),
            prev_goal_enu: Vector3::zeros(),
            now_s: 0.0,
        };
        assert!(p.plan(&input).is_err());
    }
}
