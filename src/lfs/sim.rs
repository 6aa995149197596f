//! The low-fidelity simulation loop: every simulated tick runs the named stages `sense` (render + cloud
//! processing), `plan` (mission logic + 3DVFH* tree), `control` (motion model command), `integrate` and
//! `record`, with time as a parameter (nothing reads a clock). A flight ends when landed, stuck (no progress for
//! `stuck_s` simulated seconds), at the timeout, or on collision; its trajectory is judged as the competition
//! judges a real one.
//!
//! Frames: the world is planner ENU (x East, y North, z Up, metres); the trajectory is Aerialist's (x North,
//! y East, z height up, heading clockwise from North in radians).

use nalgebra::Vector3;

use super::attitude::TiltState;
use super::camera::Camera;
use super::delay::DelayQueue;
use super::mission::{MissionParams, MissionRunner, Phase};
use super::motion::{KinematicState, PaperParams, Px4Params, vertical_step};
use super::render::{CameraPose, Scene};
use super::render_fast::{FastRenderScratch, KeepRange, render_cloud};
use crate::judge::judge_in_frame;
use crate::model::{Mission, Obstacle, Param, Sample, TestCase, Trajectory};
use geodesy::frames::yaw_enu_to_ned_rad;
use prgenuav_planner::planner::{PlanInput, Planner, VehicleState};
use prgenuav_planner::waypoint::{NavState, WaypointGenerator, WaypointInput};

pub use super::sim_config::{Motion, MotionModel, SimConfig, SimError, SimResult, SimStatus, cruise_param};

/// The stages of one tick, in order.
pub const STAGES: [&str; 5] = ["sense", "plan", "control", "integrate", "record"];

/// Motion-model state carried between ticks.
#[derive(Debug, Clone)]
enum MotionState {
    Paper(PaperParams),
    Px4(Px4Params, Box<WaypointGenerator>),
}

/// Everything one simulated flight holds.
#[derive(Debug, Clone)]
pub struct World {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// Ticks run.
    pub cycles: u64,
    /// The vehicle.
    pub vehicle: KinematicState,
    /// Set once the flight is over.
    pub status: Option<SimStatus>,
    tilt: TiltState,
    scene: Scene,
    obstacles: Vec<Obstacle>,
    camera: Camera,
    keep: KeepRange,
    scratch: FastRenderScratch,
    frame: Vec<Vector3<f32>>,
    planner: Planner,
    mission: MissionRunner,
    motion: MotionState,
    command: Command,
    pending: DelayQueue<Command>,
    samples: Vec<Sample>,
    config: SimConfig,
    best_goal_dist_m: f64,
    last_progress_s: f64,
}

/// What the control stage asks the integrate stage to do.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Command {
    Hold,
    Vertical { alt_m: f64, speed_m_s: f64 },
    Toward(Vector3<f64>),
    Track { setpoint: Vector3<f64>, yaw_enu_rad: f64 },
}

fn f32v(v: &Vector3<f64>) -> Vector3<f32> {
    Vector3::new(v.x as f32, v.y as f32, v.z as f32)
}

impl World {
    /// A vehicle on the ground at home, facing North, ready to fly `test`'s mission among its obstacles.
    pub fn new(test: &TestCase, config: SimConfig) -> Result<Self, SimError> {
        Self::from_parts(&test.mission, &test.obstacles, &test.params, config)
    }

    /// As [`World::new`], from a mission, obstacles and PX4 parameters.
    pub fn from_parts(
        mission: &Mission,
        obstacles: &[Obstacle],
        px4_params: &[Param],
        config: SimConfig,
    ) -> Result<Self, SimError> {
        let params = config.planner_params(px4_params)?;
        let planner = Planner::new(params.clone())?;
        let mission_params = config.mission.unwrap_or_else(|| MissionParams::from_params(px4_params));
        let mission = MissionRunner::new(mission, mission_params).ok_or(SimError::EmptyMission)?;
        // PX4 starts facing North (yaw 0) in Gazebo's default spawn; ENU yaw pi/2.
        let vehicle = KinematicState {
            position_enu: Vector3::zeros(),
            velocity_enu: Vector3::zeros(),
            acceleration_enu: Vector3::zeros(),
            yaw_enu_rad: std::f64::consts::FRAC_PI_2,
        };
        let motion = match config.motion {
            MotionModel::Paper(p) => MotionState::Paper(p),
            MotionModel::Px4(p) => MotionState::Px4(p, Box::new(WaypointGenerator::with_fovs(params.fovs.clone()))),
        };
        let mut w = Self {
            time_s: 0.0,
            cycles: 0,
            vehicle,
            status: None,
            tilt: TiltState::default(),
            scene: Scene::new(obstacles),
            obstacles: obstacles.to_vec(),
            camera: config.camera.clone(),
            keep: KeepRange {
                min_m: params.min_sensor_range_m,
                max_m: params.max_sensor_range_m,
            },
            scratch: FastRenderScratch::default(),
            frame: Vec::new(),
            planner,
            mission,
            motion,
            command: Command::Hold,
            pending: DelayQueue::default(),
            samples: Vec::new(),
            config,
            best_goal_dist_m: f64::INFINITY,
            last_progress_s: 0.0,
        };
        w.record();
        Ok(w)
    }

    /// The mission state.
    pub fn mission(&self) -> &MissionRunner {
        &self.mission
    }

    /// The planner.
    pub fn planner(&self) -> &Planner {
        &self.planner
    }

    fn vehicle_state(&self) -> VehicleState {
        VehicleState {
            position_enu: f32v(&self.vehicle.position_enu),
            velocity_enu: f32v(&self.vehicle.velocity_enu),
            yaw_enu_rad: self.vehicle.yaw_enu_rad as f32,
            pitch_rad: self.tilt.pitch_rad as f32,
        }
    }

    /// Stage `sense`: render the camera frame and feed it to the point memory.
    fn sense(&mut self, dt: f64) {
        if self.mission.phase() == Phase::Ground {
            return;
        }
        // The body pitch tilts the view through the camera's principal point (the fast renderer needs a level
        // pose); the planner gets the pitch itself with the vehicle state.
        let pose = CameraPose::level(self.vehicle.position_enu, self.vehicle.yaw_enu_rad);
        if self.config.tilt.is_some() {
            self.camera.view_pitch_rad = self.tilt.pitch_rad;
        }
        self.frame.clear();
        if self.vehicle.position_enu.z > 0.05 {
            let r = render_cloud(
                &self.scene,
                &self.camera,
                &pose,
                self.keep,
                &mut self.scratch,
                &mut self.frame,
            );
            if r.is_err() {
                // Only a pose inside a box fails here (the height was checked).
                self.status = Some(SimStatus::Collision);
                return;
            }
        }
        let state = self.vehicle_state();
        if self.planner.update_cloud(&self.frame, &state, dt as f32).is_err() {
            self.status = Some(SimStatus::Stuck);
        }
    }

    /// Stage `plan`: mission acceptance, then one planner iteration while cruising.
    fn plan(&mut self) {
        let pos = self.vehicle.position_enu;
        if self.mission.update(&pos) {
            self.best_goal_dist_m = f64::INFINITY;
            self.last_progress_s = self.time_s;
        }
        if self.mission.phase() != Phase::Cruise {
            return;
        }
        let input = PlanInput {
            state: self.vehicle_state(),
            goal_enu: f32v(&self.mission.goal_enu(&pos)),
            prev_goal_enu: f32v(&self.mission.prev_goal_enu()),
            now_s: self.time_s,
        };
        if self.planner.plan(&input).is_err() {
            self.status = Some(SimStatus::Stuck);
        }
    }

    /// Stage `control`: the motion model's command for this tick.
    fn control(&mut self) {
        let pos = self.vehicle.position_enu;
        let goal = self.mission.goal_enu(&pos);
        let mp = *self.mission.params();
        self.command = match self.mission.phase() {
            Phase::Ground | Phase::Landed => Command::Hold,
            Phase::Takeoff => Command::Vertical {
                alt_m: goal.z,
                speed_m_s: mp.takeoff_speed_m_s,
            },
            Phase::Descend => Command::Vertical {
                alt_m: 0.0,
                speed_m_s: mp.land_speed_m_s,
            },
            Phase::Cruise | Phase::Hold => {
                let state = self.vehicle_state();
                let plan = self.planner.last_plan();
                match &mut self.motion {
                    MotionState::Paper(_) => {
                        // Without a fresh tree (nothing within sensor range: the planner keeps its old path) the
                        // drone flies straight at the goal, as the waypoint generator's DIRECT state does.
                        let path = &plan.path_enu;
                        if plan.replanned && path.len() >= 2 {
                            let n = path[path.len() - 2];
                            Command::Toward(Vector3::new(f64::from(n.x), f64::from(n.y), f64::from(n.z)))
                        } else {
                            Command::Toward(goal)
                        }
                    }
                    MotionState::Px4(_, wg) => {
                        wg.set_fovs(self.planner.fovs());
                        let input = WaypointInput {
                            state,
                            goal_enu: f32v(&goal),
                            prev_goal_enu: f32v(&self.mission.prev_goal_enu()),
                            stay: false,
                            is_airborne: true,
                            nav_state: NavState::Mission,
                            is_land_waypoint: false,
                            is_takeoff_waypoint: false,
                            desired_vel_enu: None,
                            plan,
                        };
                        let out = wg.step(&input, self.time_s);
                        let sp = out.position_enu;
                        Command::Track {
                            setpoint: Vector3::new(f64::from(sp.x), f64::from(sp.y), f64::from(sp.z)),
                            yaw_enu_rad: f64::from(out.yaw_enu_rad),
                        }
                    }
                }
            }
        };
    }

    /// Stage `integrate`: move the vehicle for `dt` seconds.
    fn integrate(&mut self, dt: f64) {
        // The motion model's control delay: act on the command of `delay` ticks ago (hold until there is one).
        let delay = self.config.motion.delay_ticks();
        self.command = self.pending.act_on(self.command, delay, Command::Hold);
        self.move_vehicle(self.command, dt);
        if let Some(p) = &self.config.tilt {
            self.tilt
                .update(p, &self.vehicle.velocity_enu, self.vehicle.yaw_enu_rad, dt);
        }
        self.cycles += 1;
        // From the tick count (not summed), so no rounding drift over thousands of ticks.
        self.time_s = self.cycles as f64 * dt;
    }

    /// Moves the vehicle by `command` for `dt` seconds with the motion model.
    fn move_vehicle(&mut self, command: Command, dt: f64) {
        let v = &mut self.vehicle;
        match (command, &self.motion) {
            (Command::Hold, _) => {
                v.velocity_enu = Vector3::zeros();
                v.acceleration_enu = Vector3::zeros();
            }
            (Command::Vertical { alt_m, speed_m_s }, _) => vertical_step(v, alt_m, speed_m_s, dt),
            (Command::Toward(t), MotionState::Paper(p)) => p.step(v, &t, dt),
            (Command::Toward(t), MotionState::Px4(p, _)) => p.track(v, &t, v.yaw_enu_rad, dt),
            (Command::Track { setpoint, yaw_enu_rad }, MotionState::Px4(p, _)) => {
                p.track(v, &setpoint, yaw_enu_rad, dt)
            }
            (Command::Track { setpoint, .. }, MotionState::Paper(p)) => p.step(v, &setpoint, dt),
        }
        v.position_enu.z = v.position_enu.z.max(0.0);
    }

    /// Stage `record`: sample the trajectory and decide whether the flight is over.
    fn record(&mut self) {
        let p = self.vehicle.position_enu;
        self.samples.push(Sample {
            // Whole microseconds, as the CSV stores them, so the 0.5 s bins of the judge see the same samples.
            t_s: (self.time_s * 1e6).round() / 1e6,
            x: p.y,
            y: p.x,
            z: p.z,
            r: Some(yaw_enu_to_ned_rad(self.vehicle.yaw_enu_rad)),
        });
        if self.status.is_some() {
            return;
        }
        let inside = self.obstacles.iter().any(|o| {
            p.z < o.top_m() && p.z >= o.position.z && o.footprint().contains(crate::geometry::P2::new(p.y, p.x))
        });
        if inside {
            self.status = Some(SimStatus::Collision);
        } else if self.mission.phase() == Phase::Landed {
            self.status = Some(SimStatus::Landed);
        } else if self.time_s >= self.config.timeout_s - 1e-9 {
            self.status = Some(SimStatus::Timeout);
        } else {
            let d = (self.mission.goal_enu(&p) - p).norm();
            if d <= self.best_goal_dist_m - self.config.progress_m || !self.best_goal_dist_m.is_finite() {
                self.best_goal_dist_m = d;
                self.last_progress_s = self.time_s;
            } else if self.time_s - self.last_progress_s > self.config.stuck_s {
                self.status = Some(SimStatus::Stuck);
            }
        }
    }

    /// The obstacles the flight is among.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The settings the flight runs with.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Replaces the obstacles from the next tick on (an ensemble member's jittered set; the point memory keeps
    /// what it saw, so call it before any box is within sensor range).
    pub fn set_obstacles(&mut self, obstacles: &[Obstacle]) {
        self.scene = Scene::new(obstacles);
        self.obstacles = obstacles.to_vec();
    }

    /// Replaces the motion model's constants from the next tick on (same kind, or the call is refused). A
    /// longer delay repeats the oldest queued command and a shorter one drops the oldest, so the vehicle never
    /// holds still for the change.
    pub fn set_motion(&mut self, motion: MotionModel) -> Result<(), SimError> {
        match (&mut self.motion, motion) {
            (MotionState::Paper(p), MotionModel::Paper(q)) => *p = q,
            (MotionState::Px4(p, _), MotionModel::Px4(q)) => *p = q,
            _ => return Err(SimError::Setting("motion model kind cannot change in flight")),
        }
        let (old, new) = (self.config.motion.delay_ticks(), motion.delay_ticks());
        self.config.motion = motion;
        self.pending.resize(old, new, self.command);
        Ok(())
    }

    /// Moves the vehicle `fraction` of a tick further with the command it acted on last, without sensing,
    /// planning or counting a tick: shifts every later camera frame and planner tick along the path.
    pub fn shift_phase(&mut self, fraction: f64) {
        if fraction > 0.0 && fraction.is_finite() {
            self.move_vehicle(self.command, fraction * self.config.dt_s);
        }
    }

    /// The trajectory so far.
    pub fn trajectory(&self) -> Trajectory {
        Trajectory::new(self.samples.clone())
    }

    /// The frames the renderer had to draw in full so far.
    pub fn full_renders(&self) -> u64 {
        self.scratch.fallbacks
    }
}

/// Runs one tick of `dt` seconds through [`STAGES`]; returns the status once the flight is over (then further
/// calls do nothing).
pub fn step(world: &mut World, dt: f64) -> Option<SimStatus> {
    if world.status.is_some() {
        return world.status;
    }
    world.sense(dt);
    if world.status.is_none() {
        world.plan();
    }
    if world.status.is_none() {
        world.control();
        world.integrate(dt);
    }
    world.record();
    world.status
}

/// Simulates `test`'s mission with its obstacles until the flight ends, and judges the trajectory.
pub fn simulate(test: &TestCase, config: &SimConfig) -> Result<SimResult, SimError> {
    simulate_parts(&test.mission, &test.obstacles, &test.params, config)
}

/// As [`simulate`], from a mission, obstacles and PX4 parameters.
pub fn simulate_parts(
    mission: &Mission,
    obstacles: &[Obstacle],
    px4_params: &[Param],
    config: &SimConfig,
) -> Result<SimResult, SimError> {
    let mut world = World::from_parts(mission, obstacles, px4_params, config.clone())?;
    let dt = config.dt_s;
    let status = loop {
        if let Some(s) = step(&mut world, dt) {
            break s;
        }
    };
    let trajectory = world.trajectory();
    // The simulated flight starts at the test's home, in the obstacles' frame.
    let distance = judge_in_frame(&trajectory, obstacles, config.judge);
    Ok(SimResult {
        status,
        flight_time_s: world.time_s,
        cycles: world.cycles,
        distance,
        full_renders: world.full_renders(),
        trajectory,
    })
}

#[cfg(test)]
#[path = "sim_tests.rs"]
mod tests;
