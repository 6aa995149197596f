//! The LFS planner as the bridge's steering: render the test's virtual boxes from the vehicle's streamed pose
//! with the simulator's depth camera, feed the 3DVFH* planner, and turn its path into a setpoint with the
//! PX4-Avoidance waypoint generator, exactly as the companion computer would with a real camera.

use nalgebra::Vector3;

use super::steer::{Nav, Steer, SteerInput, SteerOutput};
use crate::lfs::LfsError;
use crate::lfs::camera::Camera;
use crate::lfs::params::PlannerParams;
use crate::lfs::planner::{PlanInput, Planner, VehicleState};
use crate::lfs::render::{CameraPose, Scene};
use crate::lfs::render_fast::{FastRenderScratch, KeepRange, render_cloud};
use crate::lfs::waypoint::{NavState, WaypointGenerator, WaypointInput, WaypointOutput};
use crate::model::Obstacle;
use geodesy::frames::{enu_to_ned, ned_to_enu, yaw_enu_to_ned_rad, yaw_ned_to_enu_rad};

/// Planner period assumed for the first step, seconds.
const FIRST_DT_S: f64 = 0.1;

/// How the companion plans and answers where PX4-Avoidance's behaviour is a matter of its timing or of a field
/// it leaves unset (both default to prgenuav's original companion).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct CompanionStyle {
    /// How old the path is that the waypoint generator follows.
    pub plan_age: PlanAge,
    /// What the answer's yaw-rate field carries.
    pub yaw_rate: YawRateField,
}

/// The answer's yaw-rate field (point 0's `vel_yaw`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum YawRateField {
    /// NaN: PX4 v1.12 then feeds the yaw setpoint's rate of change forward (`FlightTaskAuto::_limitYawRate`).
    #[default]
    Unset,
    /// 0 rad/s, so PX4 tracks the yaw setpoint on its attitude gain alone: PX4-Avoidance fills the field from a
    /// member its live code never sets (`angular_velocity_wp`, read as zero here: an inference).
    Zero,
}

/// How old the path is that the waypoint generator follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlanAge {
    /// The path planned in the same step, from the same pose (age 0).
    #[default]
    Fresh,
    /// The path of the previous step (one planner period old, planned from the pose of then): PX4-Avoidance's
    /// waypoint loop runs on its own 10 Hz timer after the planner, whose tree comes from a cloud and a pose
    /// already old, and advances the carrot by the path's age times the cruise speed.
    OnePeriod,
}

/// Planner + camera + waypoint generator over a fixed set of virtual boxes.
pub struct PlannerSteer {
    scene: Scene,
    camera: Camera,
    keep: KeepRange,
    scratch: FastRenderScratch,
    frame: Vec<Vector3<f32>>,
    planner: Planner,
    generator: WaypointGenerator,
    last_s: Option<f64>,
    style: CompanionStyle,
}

impl std::fmt::Debug for PlannerSteer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PlannerSteer")
            .field("boxes", &self.scene.box_count())
            .finish()
    }
}

fn v3(a: [f64; 3]) -> Vector3<f32> {
    Vector3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

impl PlannerSteer {
    /// A planner seeing `obstacles` through `camera`, with default planner parameters.
    pub fn new(obstacles: &[Obstacle], camera: Camera) -> Result<Self, LfsError> {
        Self::with_cruise(obstacles, camera, None)
    }

    /// As [`PlannerSteer::new`], planning with the vehicle's MPC_XY_CRUISE (m/s) where known, as PX4-Avoidance
    /// reads it from PX4: the waypoint generator's cruise speed and the line-pull distance.
    pub fn with_cruise(
        obstacles: &[Obstacle],
        camera: Camera,
        mpc_xy_cruise_m_s: Option<f64>,
    ) -> Result<Self, LfsError> {
        let defaults = PlannerParams::default();
        let params = PlannerParams {
            fovs: vec![camera.fov()],
            mpc_xy_cruise_m_s: mpc_xy_cruise_m_s.map_or(defaults.mpc_xy_cruise_m_s, |v| v as f32),
            ..defaults
        };
        Ok(Self {
            scene: Scene::new(obstacles),
            keep: KeepRange {
                min_m: params.min_sensor_range_m,
                max_m: params.max_sensor_range_m,
            },
            camera,
            scratch: FastRenderScratch::default(),
            frame: Vec::new(),
            generator: WaypointGenerator::with_fovs(params.fovs.clone()),
            planner: Planner::new(params)?,
            last_s: None,
            style: CompanionStyle::default(),
        })
    }

    /// The same steering in `style`.
    pub fn with_style(mut self, style: CompanionStyle) -> Self {
        self.style = style;
        self
    }
}

impl Steer for PlannerSteer {
    fn steer(&mut self, input: &SteerInput) -> Option<SteerOutput> {
        let pos = ned_to_enu(&Vector3::from(input.pos_ned));
        let state = VehicleState {
            position_enu: pos.map(|v| v as f32),
            velocity_enu: ned_to_enu(&v3(input.vel_ned)),
            yaw_enu_rad: yaw_ned_to_enu_rad(input.yaw_rad) as f32,
            pitch_rad: 0.0,
        };
        let dt = self.last_s.map_or(FIRST_DT_S, |t| input.now_s - t).max(0.0);
        self.last_s = Some(input.now_s);
        self.sense(pos, &state, dt)?;
        let goal = ned_to_enu(&v3(input.goal_ned));
        let prev_goal = ned_to_enu(&v3(input.prev_goal_ned));
        let cruising = input.airborne && matches!(input.nav, Nav::Mission | Nav::Offboard);
        let previous = (self.style.plan_age == PlanAge::OnePeriod).then(|| self.planner.last_plan().clone());
        if cruising {
            let plan_input = PlanInput {
                state,
                goal_enu: goal,
                prev_goal_enu: prev_goal,
                now_s: input.now_s,
            };
            self.planner.plan(&plan_input).ok()?;
        }
        self.generator.set_fovs(self.planner.fovs());
        let out = self.generator.step(
            &WaypointInput {
                state,
                goal_enu: goal,
                prev_goal_enu: prev_goal,
                stay: false,
                is_airborne: input.airborne,
                nav_state: nav_state(input.nav),
                is_land_waypoint: input.nav == Nav::Land,
                is_takeoff_waypoint: input.nav == Nav::Takeoff,
                desired_vel_enu: input.desired_vel_ned.map(|v| ned_to_enu(&v3(v))),
                plan: previous.as_ref().unwrap_or(self.planner.last_plan()),
            },
            input.now_s,
        );
        let yaw_rate = (self.style.yaw_rate == YawRateField::Zero).then_some(0.0);
        setpoint_ned(&out).map(|sp| SteerOutput {
            yaw_rate_rad_s: yaw_rate,
            ..sp
        })
    }
}

impl PlannerSteer {
    /// Renders what the camera sees from `pos` (ENU; nothing on the ground) into the planner's cloud. `None`
    /// only with the camera inside a box, where nothing sensible can be planned.
    fn sense(&mut self, pos: Vector3<f64>, state: &VehicleState, dt: f64) -> Option<()> {
        self.frame.clear();
        if pos.z > 0.05 {
            let pose = CameraPose::level(pos, f64::from(state.yaw_enu_rad));
            render_cloud(
                &self.scene,
                &self.camera,
                &pose,
                self.keep,
                &mut self.scratch,
                &mut self.frame,
            )
            .ok()?;
        }
        self.planner.update_cloud(&self.frame, state, dt as f32).ok()
    }
}

/// The waypoint generator's state for the vehicle's navigation state.
fn nav_state(nav: Nav) -> NavState {
    match nav {
        Nav::Mission => NavState::Mission,
        Nav::Takeoff => NavState::AutoTakeoff,
        Nav::Land => NavState::AutoLand,
        Nav::Offboard => NavState::Offboard,
        Nav::Other => NavState::AutoLoiter,
    }
}

/// The generator's ENU setpoint in NED, `None` unless complete. Velocity ENU (east, north, up) -> NED
/// (north, east, down) per axis, an unset axis staying unset.
fn setpoint_ned(out: &WaypointOutput) -> Option<SteerOutput> {
    let sp = enu_to_ned(&out.position_enu);
    let [ve, vn, vu] = out.velocity_enu;
    let vel = [vn, ve, vu.map(|v| -v)].map(|v| v.map(f64::from).filter(|v| v.is_finite()));
    let out = SteerOutput {
        pos_ned: [f64::from(sp.x), f64::from(sp.y), f64::from(sp.z)],
        vel_ned: vel,
        yaw_rad: Some(yaw_enu_to_ned_rad(f64::from(out.yaw_enu_rad))),
        yaw_rate_rad_s: None,
    };
    out.is_complete().then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(now_s: f64, pos_ned: [f64; 3], goal_ned: [f64; 3]) -> SteerInput {
        SteerInput {
            now_s,
            pos_ned,
            vel_ned: [0.0; 3],
            yaw_rad: 0.0,
            goal_ned,
            prev_goal_ned: [0.0, 0.0, pos_ned[2]],
            desired_vel_ned: None,
            nav: Nav::Mission,
            airborne: true,
        }
    }

    #[test]
    fn free_space_heads_for_the_goal_and_a_wall_deflects() {
        let mut free = PlannerSteer::new(&[], Camera::hfs()).unwrap();
        let mut last = None;
        for k in 0..20 {
            last = free.steer(&input(f64::from(k) * 0.1, [0.0, 0.0, -5.0], [30.0, 0.0, -5.0]));
        }
        let sp = last.unwrap();
        assert!(
            sp.pos_ned[0] > 1.0 && sp.pos_ned[1].abs() < 0.5,
            "about straight North: {sp:?}"
        );
        let free_sp = sp;
        // A wide wall 6 m ahead across the path: the setpoint leaves the straight line.
        let wall = Obstacle::new(2.0, 16.0, 20.0, 6.0, 0.0, 0.0);
        let mut blocked = PlannerSteer::new(&[wall], Camera::hfs()).unwrap();
        let mut sp = None;
        for k in 0..20 {
            sp = blocked.steer(&input(f64::from(k) * 0.1, [0.0, 0.0, -5.0], [30.0, 0.0, -5.0]));
        }
        let sp = sp.unwrap();
        let deflected = (sp.pos_ned[1] - free_sp.pos_ned[1]).abs() > 0.5;
        let braking = sp.pos_ned[0] < free_sp.pos_ned[0] - 0.5;
        assert!(deflected || braking, "blocked {sp:?} vs free {free_sp:?}");
    }

    fn wall_run(style: CompanionStyle, steps: u32) -> Vec<SteerOutput> {
        let wall = Obstacle::new(2.0, 16.0, 20.0, 6.0, 0.0, 0.0);
        let mut steer = PlannerSteer::new(&[wall], Camera::hfs()).unwrap().with_style(style);
        (0..steps)
            .map(|k| {
                steer
                    .steer(&input(f64::from(k) * 0.1, [0.0, 0.0, -5.0], [30.0, 0.0, -5.0]))
                    .unwrap()
            })
            .collect()
    }

    #[test]
    fn a_one_period_old_path_gives_other_setpoints() {
        let old = CompanionStyle {
            plan_age: PlanAge::OnePeriod,
            ..CompanionStyle::default()
        };
        let (fresh, late) = (wall_run(CompanionStyle::default(), 20), wall_run(old, 20));
        let mut free = PlannerSteer::new(&[], Camera::hfs()).unwrap();
        let straight = free.steer(&input(0.0, [0.0, 0.0, -5.0], [30.0, 0.0, -5.0])).unwrap();
        // Step 0 has no earlier path: straight for the goal, as with no wall.
        assert_eq!(late[0].pos_ned, straight.pos_ned);
        // Then the previous step's path, its carrot further along it by the path's age: another setpoint.
        let differs = fresh.iter().zip(&late).filter(|(a, b)| a.pos_ned != b.pos_ned).count();
        assert!(differs >= 10, "{differs} of 20 setpoints differ");
    }

    #[test]
    fn the_yaw_rate_field_is_nan_or_zero_by_style() {
        assert!(
            wall_run(CompanionStyle::default(), 3)
                .iter()
                .all(|o| o.yaw_rate_rad_s.is_none())
        );
        let zero = CompanionStyle {
            yaw_rate: YawRateField::Zero,
            ..CompanionStyle::default()
        };
        assert!(wall_run(zero, 3).iter().all(|o| o.yaw_rate_rad_s == Some(0.0)));
    }

    #[test]
    fn landing_descends_by_velocity_above_the_hold_point() {
        let mut steer = PlannerSteer::new(&[], Camera::hfs()).unwrap();
        let mut i = input(0.0, [50.0, 0.2, -8.0], [50.0, 0.0, f64::NAN]);
        i.nav = Nav::Land;
        i.desired_vel_ned = Some([f64::NAN, f64::NAN, 1.5]);
        let mut out = None;
        for k in 0..5 {
            i.now_s = f64::from(k) * 0.1;
            out = steer.steer(&i);
        }
        let sp = out.expect("a landing setpoint");
        assert!(sp.pos_ned[2].is_nan(), "z left to the velocity: {sp:?}");
        assert_eq!(sp.vel_ned[2], Some(1.5));
        assert!(
            (sp.pos_ned[0] - 50.0).abs() < 1e-3 && (sp.pos_ned[1] - 0.2).abs() < 1e-3,
            "holds x, y where the descent began"
        );
    }
}
