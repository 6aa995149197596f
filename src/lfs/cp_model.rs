//! The LFS of a Collision Prevention flight, for screening: the same pilot ([`super::cp_pilot`]) and lidar
//! ([`super::range_sensor`]) as the bridge, PX4's acceleration-based Position mode (`MPC_POS_MODE` 4:
//! the stick sets an acceleration, a linear drag brings the velocity to `stick x MPC_VEL_MANUAL`), the
//! Collision Prevention constraint of [`super::cp_constraint`], and a first-order lag from the velocity
//! setpoint to the vehicle. It predicts the judged minimum distance and how the flight ends.
//!
//! Frames: local NED about the test's home (`x` North, `y` East, metres); the heading stays where it starts
//! (the pilot gives no yaw), North. The trajectory it returns is the judge's (z up).

use super::cp_constraint::{ObstacleMap, Px4Limits, constrain};
use super::cp_params::CpParams;
use super::cp_pilot::{CpPilot, PilotParams, PilotStep, Sticks};
use super::range_sensor::{RangeSensor, SensorScene};
use crate::judge::{Judge, judge_in_frame};
use crate::model::{CMD_LAND, Mission, Sample, TestCase, Trajectory};

/// The model's settings (PX4 v1.16 defaults where PX4 has the number).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CpSimConfig {
    /// Step, seconds.
    pub dt_s: f64,
    /// The lidar.
    pub sensor: RangeSensor,
    /// The pilot.
    pub pilot: PilotParams,
    /// PX4's limits Collision Prevention and Position mode read.
    pub limits: Px4Limits,
    /// MPC_XY_MAN_EXPO.
    pub xy_expo: f64,
    /// Lag from the velocity setpoint to the vehicle's velocity, seconds: lumps PX4's tilt and velocity
    /// control, and is what carries the vehicle past `CP_DIST` when Collision Prevention brakes. Chosen by
    /// cross-validation on PX4 v1.16.2 flights (docs/collision-prevention.md, `examples/cp_fidelity.rs`).
    pub vel_tau_s: f64,
    /// MPC_Z_VEL_MAX_UP, MPC_Z_VEL_MAX_DN, MPC_LAND_SPEED, m/s.
    pub z_up_m_s: f64,
    /// See `z_up_m_s`.
    pub z_down_m_s: f64,
    /// See `z_up_m_s`.
    pub land_m_s: f64,
    /// Give up after this long, seconds.
    pub timeout_s: f64,
    /// The judge edition of the predicted distance.
    pub judge: Judge,
}

impl Default for CpSimConfig {
    fn default() -> Self {
        Self {
            dt_s: 0.02,
            sensor: RangeSensor::default(),
            pilot: PilotParams::default(),
            limits: Px4Limits::default(),
            xy_expo: 0.6,
            vel_tau_s: 0.8,
            z_up_m_s: 3.0,
            z_down_m_s: 1.5,
            land_m_s: 0.7,
            timeout_s: 500.0,
            judge: Judge::default(),
        }
    }
}

/// How the predicted flight ended.
#[derive(Debug, Clone, PartialEq)]
pub enum CpEnd {
    /// Every waypoint reached, landed.
    Landed,
    /// The pilot gave up on a waypoint (why).
    Stuck(String),
    /// Still flying at the time limit.
    Timeout,
}

/// The prediction.
#[derive(Debug, Clone)]
pub struct CpPrediction {
    /// The judged minimum distance, metres (`None` without boxes).
    pub min_distance: Option<f64>,
    /// The flown path (10 Hz, z up).
    pub trajectory: Trajectory,
    /// How it ended.
    pub end: CpEnd,
}

/// The mission's waypoints as the pilot flies them: takeoff point, waypoints, the land point at altitude.
pub fn waypoints(mission: &Mission) -> Vec<[f64; 3]> {
    let mut out: Vec<[f64; 3]> = Vec::new();
    for item in &mission.items {
        let Some(p) = item.local else { continue };
        let down = match item.command {
            CMD_LAND => out.last().map_or(-p.alt_m, |g| g[2]),
            _ => -p.alt_m,
        };
        out.push([p.north_m, p.east_m, down]);
        if item.command == CMD_LAND {
            break;
        }
    }
    out
}

/// The vehicle's state: position (NED), velocity and its setpoint (North, East), climb rate (up).
#[derive(Debug, Clone, Copy, Default)]
struct State {
    pos: [f64; 3],
    vel: [f64; 2],
    vel_sp: [f64; 2],
    vz_up: f64,
}

/// Predicts `test` flown in Position mode with Collision Prevention `cp`.
pub fn simulate_cp(test: &TestCase, cp: &CpParams, cfg: &CpSimConfig) -> CpPrediction {
    let scene = SensorScene::new(&test.obstacles);
    let mut pilot = CpPilot::new(waypoints(&test.mission), cfg.pilot);
    let mut st = State::default();
    let (yaw, dt) = (0.0, cfg.dt_s);
    let mut map: Option<ObstacleMap> = None;
    let mut samples = Vec::new();
    let (mut t, mut next_scan, mut next_sample) = (0.0, 0.0, 0.0);
    let end = loop {
        if t >= next_scan {
            next_scan += cfg.sensor.period_s();
            map = Some(scan(&cfg.sensor, &scene, st.pos, yaw));
        }
        if let Some(m) = map.as_mut() {
            m.age_s = t - (next_scan - cfg.sensor.period_s());
        }
        if t >= next_sample {
            next_sample += 0.1;
            samples.push(sample(t, &st));
        }
        let sticks = match pilot.step(t, st.pos, yaw) {
            PilotStep::Fly(s) => s,
            PilotStep::Finished => break land(&mut st, &mut samples, t, cfg),
            PilotStep::Stuck(why) => break CpEnd::Stuck(why),
        };
        step(&mut st, &sticks, map.as_ref(), cp, cfg, dt);
        t += dt;
        if t > cfg.timeout_s {
            break CpEnd::Timeout;
        }
    };
    let trajectory = Trajectory::new(samples);
    let min_distance = judge_in_frame(&trajectory, &test.obstacles, cfg.judge).map(|j| j.min_distance);
    CpPrediction {
        min_distance,
        trajectory,
        end,
    }
}

fn scan(sensor: &RangeSensor, scene: &SensorScene, pos: [f64; 3], yaw: f64) -> ObstacleMap {
    ObstacleMap {
        bins: sensor.scan(scene, pos, yaw),
        min_cm: sensor.min_cm,
        max_cm: sensor.max_cm,
        age_s: 0.0,
    }
}

fn sample(t: f64, st: &State) -> Sample {
    Sample {
        t_s: t,
        x: st.pos[0],
        y: st.pos[1],
        z: -st.pos[2],
        r: Some(0.0),
    }
}

/// One step of Position mode: the stick's acceleration (after expo, in the heading frame; heading North),
/// constrained by Collision Prevention, less the drag; the vehicle follows the velocity setpoint.
fn step(st: &mut State, sticks: &Sticks, map: Option<&ObstacleMap>, cp: &CpParams, cfg: &CpSimConfig, dt: f64) {
    let expo = |x: f64| (1.0 - cfg.xy_expo) * x + cfg.xy_expo * x.powi(3);
    let mut s = [expo(sticks.pitch), expo(sticks.roll)];
    let len = s[0].hypot(s[1]);
    if len > 1.0 {
        s = [s[0] / len, s[1] / len];
    }
    let lim = &cfg.limits;
    let acc_scale = 2.0 * lim.acc_hor;
    let mut acc = [s[0] * acc_scale, s[1] * acc_scale];
    if let Some(m) = map {
        acc = constrain(acc, st.vel_sp, 0.0, m, cp, lim);
    }
    // Releasing the stick brakes harder (PX4's brake boost).
    let boost = if len < 1e-6 { 2.0 } else { 1.0 };
    let drag = boost * acc_scale / lim.vel_manual;
    for (k, a) in acc.iter().enumerate() {
        st.vel_sp[k] += (a - drag * st.vel_sp[k]) * dt;
        st.vel[k] += (st.vel_sp[k] - st.vel[k]) * (dt / cfg.vel_tau_s).min(1.0);
        st.pos[k] += st.vel[k] * dt;
    }
    let vz_sp = climb_rate(sticks.throttle, cfg);
    st.vz_up += (vz_sp - st.vz_up) * (dt / cfg.vel_tau_s).min(1.0);
    st.pos[2] = (st.pos[2] - st.vz_up * dt).min(0.0);
}

/// PX4's throttle to climb rate: a 10 % dead zone about the centre, expo, the climb and descent limits.
fn climb_rate(throttle: f64, cfg: &CpSimConfig) -> f64 {
    let t = (2.0 * throttle - 1.0).clamp(-1.0, 1.0);
    if t.abs() <= 0.1 {
        return 0.0;
    }
    let x = (t.abs() - 0.1) / 0.9 * t.signum();
    let e = (1.0 - cfg.xy_expo) * x + cfg.xy_expo * x.powi(3);
    if e > 0.0 { e * cfg.z_up_m_s } else { e * cfg.z_down_m_s }
}

/// AUTO.LAND from where the pilot finished: straight down at MPC_LAND_SPEED, recorded.
fn land(st: &mut State, samples: &mut Vec<Sample>, mut t: f64, cfg: &CpSimConfig) -> CpEnd {
    st.vel = [0.0, 0.0];
    while st.pos[2] < 0.0 {
        t += 0.1;
        st.pos[2] = (st.pos[2] + cfg.land_m_s * 0.1).min(0.0);
        samples.push(sample(t, st));
    }
    CpEnd::Landed
}

#[cfg(test)]
#[path = "cp_model_tests.rs"]
mod tests;
