//! The waypoint generator (docs/planner.md §8, AV `waypoint_generator.cpp`): turns the planner's path into one position
//! and yaw setpoint per tick, with a four-state machine, the FOV speed taper, a speed low-pass and critically
//! damped smoothing. Time is injected (`now_s`); nothing reads a clock.
//!
//! Frame: ENU (x East, y North, z Up, metres, m/s); yaw in radians counter-clockwise from East.

use nalgebra::Vector3;

use super::fov::{Fov, scale_to_fov};
use super::planner::{Plan, VehicleState};
use super::polar::{RAD_TO_DEG, cartesian_to_polar_fcu, wrap_pi, wrap_polar};

/// States of the generator (initial: `Loiter`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WaypointState {
    /// Follow the planner's path.
    TryPath,
    /// Reach the goal altitude first (takeoff, land, offboard start).
    AltitudeChange,
    /// Hold the position stored on entry.
    Loiter,
    /// Fly straight at the goal, ignoring obstacles (no valid path).
    Direct,
}

/// Outcome of running one state (the original's `usm::Transition`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transition {
    /// Stay in the state.
    Repeat,
    /// First alternative of the state's table.
    Next1,
    /// Second alternative.
    Next2,
    /// Third alternative.
    Next3,
}

/// The transition table, a pure function. Unmapped pairs go to `Loiter` (the table's error state).
pub fn next_state(state: WaypointState, t: Transition) -> WaypointState {
    use Transition::*;
    use WaypointState::*;
    match (state, t) {
        (s, Repeat) => s,
        (TryPath, Next1) => AltitudeChange,
        (TryPath, Next2) => Direct,
        (TryPath, Next3) => Loiter,
        (Loiter, Next1) => TryPath,
        (Direct, Next1) => TryPath,
        (Direct, Next2) => AltitudeChange,
        (Direct, Next3) => Loiter,
        (AltitudeChange, Next1) => TryPath,
        (AltitudeChange, Next2) => Loiter,
        _ => Loiter,
    }
}

/// PX4 navigation state as the avoidance node sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NavState {
    /// Not in an autonomous mode.
    #[default]
    None,
    /// Mission mode.
    Mission,
    /// Auto takeoff.
    AutoTakeoff,
    /// Auto land.
    AutoLand,
    /// Return to launch.
    AutoRtl,
    /// Offboard.
    Offboard,
    /// Auto loiter.
    AutoLoiter,
}

/// Inputs of one tick.
#[derive(Debug, Clone, Copy)]
pub struct WaypointInput<'a> {
    /// Vehicle state (ENU).
    pub state: VehicleState,
    /// Current goal, ENU metres.
    pub goal_enu: Vector3<f32>,
    /// Previous goal, ENU metres.
    pub prev_goal_enu: Vector3<f32>,
    /// Failsafe hover request.
    pub stay: bool,
    /// Armed and in an autonomous mode.
    pub is_airborne: bool,
    /// PX4 navigation state.
    pub nav_state: NavState,
    /// The current mission item is a land item.
    pub is_land_waypoint: bool,
    /// The current mission item is a takeoff item.
    pub is_takeoff_waypoint: bool,
    /// PX4's desired velocity (trajectory point 0), ENU m/s, if it sent one.
    pub desired_vel_enu: Option<Vector3<f32>>,
    /// The latest planner output.
    pub plan: &'a Plan,
}

/// One tick's setpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaypointOutput {
    /// State that produced this output (the state after the tick's transition, as `waypoint_type`).
    pub state: WaypointState,
    /// Position setpoint, ENU metres (the smoothed goto point).
    pub position_enu: Vector3<f32>,
    /// Velocity setpoint per ENU axis in m/s; `None` = unset (only altitude-change branches set it).
    pub velocity_enu: [Option<f32>; 3],
    /// Yaw setpoint, ENU radians counter-clockwise from East.
    pub yaw_enu_rad: f32,
    /// Unit-step target before speed adaptation, ENU metres.
    pub goto_enu: Vector3<f32>,
    /// Speed-adapted target before smoothing, ENU metres.
    pub adapted_goto_enu: Vector3<f32>,
}

/// Setpoint on the path `elapsed * speed` past the depth-1 node (`getSetpointFromPath`). Returns the point (if
/// the path has at least 2 entries) and whether it is valid (not run off the path's end).
pub fn setpoint_from_path(
    path: &[Vector3<f32>],
    path_time_s: Option<f64>,
    speed: f32,
    now_s: f64,
) -> (Option<Vector3<f32>>, bool) {
    let n = path.len();
    if n < 2 {
        return (None, false);
    }
    if n == 2 {
        return (Some(path[0]), true);
    }
    let Some(t0) = path_time_s else {
        return (None, false);
    };
    let mut seg = path[n - 3] - path[n - 2];
    let mut left = ((now_s - t0) * speed as f64) as f32;
    let mut sp = path[n - 2] + seg * (left / seg.norm());
    let mut i = n - 3;
    while i > 0 && left > seg.norm() {
        left -= seg.norm();
        seg = path[i - 1] - path[i];
        sp = path[i] + seg * (left / seg.norm());
        i -= 1;
    }
    (Some(sp), left < seg.norm())
}

/// The generator's memory between ticks.
#[derive(Debug, Clone)]
pub struct WaypointGenerator {
    fovs: Vec<Fov>,
    smoothing_speed_xy: f32,
    smoothing_speed_z: f32,
    state: WaypointState,
    state_changed: bool,
    last_time_s: Option<f64>,
    smoothed: Option<(Vector3<f32>, Vector3<f32>)>,
    yaw_sp_rad: f32,
    yaw_rate: f32,
    heading_at_goal_rad: Option<f32>,
    yaw_reach_height_rad: Option<f32>,
    speed: f32,
    hover: Option<Vector3<f32>>,
    change_alt_pos: Vector3<f32>,
    reach_altitude_offboard: bool,
    auto_land: bool,
    // The last output position: while landing it is not recomputed outside the altitude-change branch.
    last_output_pos: Option<Vector3<f32>>,
}

/// Per-tick working values (the original's `output_` fields plus the inputs).
struct Tick<'a> {
    inp: &'a WaypointInput<'a>,
    pos: Vector3<f32>,
    goal: Vector3<f32>,
    yaw: f32,
    dt: f32,
    now_s: f64,
    goto: Vector3<f32>,
    adapted: Vector3<f32>,
    smoothed_out: Vector3<f32>,
    velocity: [Option<f32>; 3],
}

fn normalized_or_zero(v: Vector3<f32>) -> Vector3<f32> {
    let n = v.norm();
    if n > 0.0 { v / n } else { v }
}

impl WaypointGenerator {
    /// A generator in `Loiter` with the given camera FOVs and smoothing gains (defaults 10 and 3; 0 disables).
    pub fn new(fovs: Vec<Fov>, smoothing_speed_xy: f32, smoothing_speed_z: f32) -> Self {
        Self {
            fovs,
            smoothing_speed_xy,
            smoothing_speed_z,
            state: WaypointState::Loiter,
            state_changed: false,
            last_time_s: None,
            smoothed: None,
            yaw_sp_rad: 0.0,
            yaw_rate: 0.0,
            heading_at_goal_rad: None,
            yaw_reach_height_rad: None,
            speed: 0.0,
            hover: None,
            change_alt_pos: Vector3::zeros(),
            reach_altitude_offboard: false,
            auto_land: false,
            last_output_pos: None,
        }
    }

    /// A generator with the default smoothing gains (xy 10, z 3).
    pub fn with_fovs(fovs: Vec<Fov>) -> Self {
        Self::new(fovs, 10.0, 3.0)
    }

    /// Replaces the camera FOVs (the original hands the planner's estimate over every planner cycle).
    pub fn set_fovs(&mut self, fovs: &[Fov]) {
        self.fovs.clear();
        self.fovs.extend_from_slice(fovs);
    }

    /// Current state.
    pub fn state(&self) -> WaypointState {
        self.state
    }

    /// Runs one tick at simulation time `now_s` (seconds). `dt` is the time since the previous tick, or 1e-4 s if
    /// not positive; the first tick also uses 1e-4 s (the original would use the time since the epoch).
    pub fn step(&mut self, inp: &WaypointInput<'_>, now_s: f64) -> WaypointOutput {
        let pos = inp.state.position_enu;
        let yaw = inp.state.yaw_enu_rad;
        // updateState: (re)initialise the smoother when not flying; keep re-initialising while landing.
        let reinit = !inp.is_airborne
            || self
                .smoothed
                .is_none_or(|(p, v)| !(p.iter().chain(v.iter()).all(|x| x.is_finite())));
        if reinit {
            self.smoothed = Some((pos, Vector3::zeros()));
            self.yaw_sp_rad = yaw;
            self.yaw_rate = 0.0;
            self.reach_altitude_offboard = false;
        }
        if self.auto_land {
            self.smoothed = Some((pos, Vector3::zeros()));
        }
        let dt = match self.last_time_s {
            Some(t) if now_s - t > 0.0 => (now_s - t) as f32,
            _ => 0.0001,
        };
        self.last_time_s = Some(now_s);
        let mut t = Tick {
            inp,
            pos,
            goal: inp.goal_enu,
            yaw,
            dt,
            now_s,
            goto: pos,
            adapted: pos,
            smoothed_out: self.last_output_pos.unwrap_or(pos),
            velocity: [None; 3],
        };
        let transition = match self.state {
            WaypointState::TryPath => self.run_try_path(&mut t),
            WaypointState::AltitudeChange => self.run_altitude_change(&mut t),
            WaypointState::Loiter => self.run_loiter(&mut t),
            WaypointState::Direct => self.run_direct(&mut t),
        };
        self.state_changed = false;
        self.last_output_pos = Some(t.smoothed_out);
        if transition != Transition::Repeat {
            self.state = next_state(self.state, transition);
            self.state_changed = true;
        }
        WaypointOutput {
            state: self.state,
            position_enu: t.smoothed_out,
            velocity_enu: t.velocity,
            yaw_enu_rad: self.yaw_sp_rad,
            goto_enu: t.goto,
            adapted_goto_enu: t.adapted,
        }
    }

    fn path_setpoint(&self, t: &Tick<'_>) -> (Option<Vector3<f32>>, bool) {
        let plan = t.inp.plan;
        setpoint_from_path(&plan.path_enu, plan.path_time_s, plan.cruise_speed_m_s, t.now_s)
    }

    fn run_try_path(&mut self, t: &mut Tick<'_>) -> Transition {
        let (sp, valid) = self.path_setpoint(t);
        t.goto = t.pos + normalized_or_zero(sp.unwrap_or(t.pos) - t.pos);
        self.path_msg(t);
        if t.inp.stay {
            Transition::Next3
        } else if self.is_altitude_change(t) {
            Transition::Next1
        } else if valid {
            Transition::Repeat
        } else {
            Transition::Next2
        }
    }

    fn run_altitude_change(&mut self, t: &mut Tick<'_>) -> Transition {
        if self.state_changed {
            self.yaw_reach_height_rad = Some(t.yaw);
            self.change_alt_pos = t.pos;
        }
        if t.inp.nav_state == NavState::Offboard {
            t.goto = t.pos;
            t.goal.x = t.pos.x;
            t.goal.y = t.pos.y;
            if t.inp.is_airborne {
                t.goto.z += if t.pos.z <= t.goal.z { 1.0 } else { -1.0 };
            }
        } else if t.inp.state.velocity_enu.xy().norm() > 0.5 {
            // Brake first: horizontal velocity 0, hold the current height.
            t.velocity = [Some(0.0), Some(0.0), None];
            t.goto = t.pos;
            t.adapted = t.pos;
            t.smoothed_out = t.pos;
            self.change_alt_pos = t.pos;
        } else {
            t.goto = Vector3::new(self.change_alt_pos.x, self.change_alt_pos.y, t.goal.z);
            if self.auto_land {
                let target = Vector3::new(self.change_alt_pos.x, self.change_alt_pos.y, t.goal.z);
                t.adapted = target;
                t.smoothed_out = target;
            }
            t.velocity = match t.inp.desired_vel_enu {
                Some(v) => [Some(v.x), Some(v.y), Some(v.z)],
                None => [None; 3],
            };
        }
        self.path_msg(t);
        if t.inp.stay {
            Transition::Next2
        } else if self.is_altitude_change(t) {
            Transition::Repeat
        } else {
            Transition::Next1
        }
    }

    fn run_loiter(&mut self, t: &mut Tick<'_>) -> Transition {
        if self.state_changed || self.hover.is_none() {
            self.hover = Some(t.pos);
        }
        t.goto = self.hover.unwrap_or(t.pos);
        self.path_msg(t);
        if t.inp.stay {
            Transition::Repeat
        } else {
            Transition::Next1
        }
    }

    fn run_direct(&mut self, t: &mut Tick<'_>) -> Transition {
        t.goto = t.pos + normalized_or_zero(t.goal - t.pos);
        self.path_msg(t);
        if self.path_setpoint(t).1 {
            Transition::Next1
        } else if self.is_altitude_change(t) {
            Transition::Next2
        } else if t.inp.stay {
            Transition::Next3
        } else {
            Transition::Repeat
        }
    }

    /// `getPathMsg`: yaw smoothing, then (unless landing) speed adaptation and position smoothing.
    fn path_msg(&mut self, t: &mut Tick<'_>) {
        t.adapted = t.goto;
        self.next_smooth_yaw(t);
        if !self.auto_land {
            self.adapt_speed(t);
            self.smooth_waypoint(t);
        }
    }

    fn next_smooth_yaw(&mut self, t: &Tick<'_>) {
        let d = t.goto - t.pos;
        let mut desired = if d.xy().norm() > 0.1 {
            Some(d.y.atan2(d.x))
        } else {
            Some(t.yaw)
        };
        if self.state == WaypointState::AltitudeChange {
            desired = self.yaw_reach_height_rad;
        }
        if self.smoothing_speed_xy <= 0.01 {
            if let Some(y) = desired {
                self.yaw_sp_rad = y;
            }
            return;
        }
        let p_gain = self.smoothing_speed_xy;
        let d_gain = 2.0 * p_gain.sqrt();
        let diff = wrap_pi(desired.map_or(0.0, |y| y - self.yaw_sp_rad));
        self.yaw_rate += (diff * p_gain + (0.0 - self.yaw_rate) * d_gain) * t.dt;
        self.yaw_sp_rad = wrap_pi(self.yaw_sp_rad + self.yaw_rate * t.dt);
    }

    fn adapt_speed(&mut self, t: &mut Tick<'_>) {
        let alpha = t.dt / (0.9 + t.dt);
        let last = self.speed;
        let cruise = t.inp.plan.cruise_speed_m_s;
        self.speed = if cruise.is_finite() { cruise } else { 2.0 };
        let goal_dist = (t.goal - t.pos).norm();
        if goal_dist < 1.0 {
            t.goto = t.goal;
            self.speed = goal_dist;
            let heading = *self.heading_at_goal_rad.get_or_insert(t.yaw);
            self.yaw_sp_rad = heading;
        } else {
            if self.state != WaypointState::AltitudeChange {
                let mut p = cartesian_to_polar_fcu(&t.goto, &t.pos);
                p.e_deg -= t.inp.state.pitch_rad * RAD_TO_DEG;
                p.z_deg -= RAD_TO_DEG * t.yaw;
                self.speed *= scale_to_fov(&self.fovs, &wrap_polar(p));
            }
            self.heading_at_goal_rad = None;
        }
        self.speed = alpha * self.speed + (1.0 - alpha) * last;
        self.speed = self.speed.min(goal_dist);
        let mut to_wp = t.goto - t.pos;
        if to_wp.norm() > 0.1 {
            to_wp = normalized_or_zero(to_wp);
        }
        t.adapted = t.pos + to_wp * self.speed;
    }

    fn smooth_waypoint(&mut self, t: &mut Tick<'_>) {
        if self.smoothing_speed_xy < 0.01 || self.smoothing_speed_z < 0.01 {
            t.smoothed_out = t.adapted;
            return;
        }
        let p_gain = Vector3::new(self.smoothing_speed_xy, self.smoothing_speed_xy, self.smoothing_speed_z);
        let d_gain = p_gain.map(|p| 2.0 * p.sqrt());
        let target_vel = if (t.adapted - t.goal).norm() < 0.1 {
            Vector3::zeros()
        } else {
            t.inp.state.velocity_enu
        };
        let (mut s, mut v) = self.smoothed.unwrap_or((t.pos, Vector3::zeros()));
        let mut loc_diff = t.adapted - s;
        if !loc_diff.iter().all(|x| x.is_finite()) {
            loc_diff = Vector3::zeros();
        }
        let mut vel_diff = target_vel - v;
        if !vel_diff.iter().all(|x| x.is_finite()) {
            vel_diff = Vector3::zeros();
        }
        v += (loc_diff.component_mul(&p_gain) + vel_diff.component_mul(&d_gain)) * t.dt;
        s += v * t.dt;
        self.smoothed = Some((s, v));
        t.smoothed_out = s;
    }

    /// `isAltitudeChange`: also updates the landing flag, as the original does.
    fn is_altitude_change(&mut self, t: &Tick<'_>) -> bool {
        let (pos, goal, nav) = (t.pos, t.goal, t.inp.nav_state);
        // As written upstream the descend branch is unreachable: below goal.z - 0.8 the goal is always above.
        let below = pos.z <= goal.z - 0.8;
        let rtl_climb = below && goal.z > pos.z;
        let rtl_descend = below && goal.z <= pos.z;
        let offboard_not_reached = nav == NavState::Offboard && !self.reach_altitude_offboard;
        let takeoff = nav == NavState::AutoTakeoff
            || (nav == NavState::Mission && t.inp.is_takeoff_waypoint)
            || (nav == NavState::AutoRtl && rtl_climb);
        self.auto_land = nav == NavState::AutoLand
            || (nav == NavState::Mission && t.inp.is_land_waypoint)
            || (nav == NavState::AutoRtl && rtl_descend);
        if offboard_not_reached || takeoff || self.auto_land {
            if nav == NavState::Offboard && pos.z >= goal.z {
                self.reach_altitude_offboard = true;
                return false;
            }
            return true;
        }
        false
    }
}

#[cfg(test)]
#[path = "waypoint_tests.rs"]
mod tests;
