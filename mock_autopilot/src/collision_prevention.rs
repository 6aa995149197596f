//! PX4's Collision Prevention (v1.16 `CollisionPrevention.cpp`), our own model of it: in Position mode it
//! bends and scales the stick acceleration so the vehicle stops `CP_DIST` before what the range messages
//! report. It acts on the sensor messages only, never on the mock's own obstacles.
//!
//! Frames: vectors are local NED horizontal (x North, y East); map bins are body-frame (see
//! [`crate::obstacle_map`]). Distances in the map are centimetres, everything else metres and seconds.

use std::time::Duration;

use mavlink::dialects::common::OBSTACLE_DISTANCE_DATA;
use nalgebra::Vector2;

use crate::dynamics::max_speed_from_distance;
use crate::obstacle_map::{BIN_COUNT, BIN_DEG, ObstacleMap, RANGE_TIMEOUT, UNKNOWN, bin_at, wrap_360};
use crate::params::ParamTable;
use crate::release::Px4Release;

/// A horizontal NED vector (x North, y East).
pub type Xy = Vector2<f64>;

/// Without fresh data for this long (and that long after activation) the vehicle switches to Hold
/// (PX4's `TIMEOUT_HOLD_US`).
pub const NO_DATA_HOLD: Duration = Duration::from_secs(5);

/// The parameters Collision Prevention reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CpParams {
    /// CP_DIST, m: distance to keep; not positive disables Collision Prevention.
    pub dist_m: f64,
    /// CP_DELAY, s: sensor plus tracking delay.
    pub delay_s: f64,
    /// CP_GUIDE_ANG, degrees: how far the setpoint may be turned towards free space.
    pub guide_deg: f64,
    /// CP_GO_NO_DATA: moving where no sensor ever looked is allowed.
    pub go_no_data: bool,
    /// MPC_XY_P, 1/s.
    pub xy_p: f64,
    /// MPC_JERK_MAX, m/s³.
    pub jerk_max: f64,
    /// MPC_ACC_HOR, m/s².
    pub acc_hor: f64,
    /// MPC_XY_VEL_P_ACC, 1/s.
    pub xy_vel_p_acc: f64,
    /// MPC_VEL_MANUAL, m/s.
    pub vel_manual: f64,
    /// Whether the release calls Collision Prevention in the Position mode `MPC_POS_MODE` selects.
    pub in_position_mode: bool,
}

impl CpParams {
    /// From the parameter table (gains and limits kept positive).
    pub fn from_params(p: &ParamTable) -> Self {
        let pos = |n: &str| p.f64(n).max(0.01);
        Self {
            dist_m: p.f64("CP_DIST"),
            delay_s: p.f64("CP_DELAY").max(0.0),
            guide_deg: p.f64("CP_GUIDE_ANG").max(0.0),
            go_no_data: p.f64("CP_GO_NO_DATA") != 0.0,
            xy_p: pos("MPC_XY_P"),
            jerk_max: pos("MPC_JERK_MAX"),
            acc_hor: pos("MPC_ACC_HOR"),
            xy_vel_p_acc: pos("MPC_XY_VEL_P_ACC"),
            vel_manual: pos("MPC_VEL_MANUAL"),
            in_position_mode: true,
        }
    }

    /// As [`Self::from_params`], for `release`, whose Collision Prevention may ignore the Position mode set.
    pub fn for_release(p: &ParamTable, release: Px4Release) -> Self {
        Self {
            in_position_mode: release.cp_acts_in_position_mode(p.f64("MPC_POS_MODE")),
            ..Self::from_params(p)
        }
    }

    /// Collision Prevention acts when CP_DIST is positive, in a Position mode that calls it.
    pub fn active(&self) -> bool {
        self.dist_m > 0.0 && self.in_position_mode
    }
}

/// What Collision Prevention asks of the vehicle beside the setpoint.
#[derive(Debug, Clone, PartialEq)]
pub enum CpEvent {
    /// A message for the operator (critical).
    Text(String),
    /// No data for too long: switch to Hold (AUTO.LOITER).
    Hold,
}

/// The newest OBSTACLE_DISTANCE received, as PX4's uORB topic holds it across mode changes.
#[derive(Debug, Clone, Default)]
pub struct RangeInbox {
    latest: Option<(OBSTACLE_DISTANCE_DATA, Duration)>,
    generation: u64,
}

impl RangeInbox {
    /// Keeps a message received at `now`.
    pub fn put(&mut self, m: &OBSTACLE_DISTANCE_DATA, now: Duration) {
        self.latest = Some((m.clone(), now));
        self.generation += 1;
    }
}

/// One activation of Collision Prevention (PX4 builds it anew each time Position mode starts).
#[derive(Debug, Clone, Default)]
pub struct CollisionPrevention {
    map: ObstacleMap,
    seen: u64,
    was_active: bool,
    activated_at: Duration,
    warned_at: Option<Duration>,
    data_present: bool,
    closest_m: f64,
    closest_dir: Xy,
}

/// World direction of body bin `i` at heading `yaw`.
fn bin_dir(i: usize, yaw: f64) -> Xy {
    let a = yaw + (i as f64 * f64::from(BIN_DEG)).to_radians();
    Xy::new(a.cos(), a.sin())
}

impl CollisionPrevention {
    /// The body-frame obstacle map.
    pub fn map(&self) -> &ObstacleMap {
        &self.map
    }

    /// Whether it acts now; notes the activation time when it starts acting.
    pub fn active(&mut self, p: &CpParams, now: Duration) -> bool {
        let active = p.active();
        if active && !self.was_active {
            self.activated_at = now;
        }
        self.was_active = active;
        active
    }

    /// The stick acceleration `acc` (NED xy, m/s²) constrained for obstacles, given the mode's current velocity
    /// setpoint `vel_sp` and heading `yaw` (rad).
    pub fn modify(
        &mut self,
        acc: Xy,
        vel_sp: Xy,
        yaw: f64,
        (inbox, now): (&RangeInbox, Duration),
        p: &CpParams,
        events: &mut Vec<CpEvent>,
    ) -> Xy {
        if inbox.generation != self.seen {
            self.seen = inbox.generation;
            if let Some((m, at)) = &inbox.latest
                && let Err(text) = self.map.ingest(m, *at, yaw, now)
            {
                events.push(CpEvent::Text(text));
            }
        }
        self.update_data(yaw, now);
        let min_keep = (f64::from(self.map.min_distance) / 100.0).max(p.dist_m);
        let length = acc.norm();
        if self.data_present && length > 0.001 {
            let (index, dir) = self.setpoint_bin(acc, yaw, p);
            let (comp, comp_dir) = self.velocity_compensation(vel_sp, yaw, now, min_keep, p);
            let feasible = !(self.map.distances[index] == UNKNOWN && (!p.go_no_data || self.map.covered[index]));
            let constrained = if feasible {
                self.constrain(dir, length, yaw, min_keep, p)
            } else {
                Xy::zeros()
            };
            constrained + comp_dir * comp
        } else if !self.data_present {
            self.no_data(now, events);
            Xy::zeros()
        } else {
            acc
        }
    }

    fn update_data(&mut self, yaw: f64, now: Duration) {
        self.map.drop_stale(now);
        let fresh = now.saturating_sub(self.map.stamp) < RANGE_TIMEOUT;
        self.data_present = fresh && self.map.distances.iter().any(|&d| d < UNKNOWN);
        self.closest_m = f64::from(UNKNOWN);
        self.closest_dir = Xy::zeros();
        for (i, &d) in self.map.distances.iter().enumerate() {
            if f64::from(d) * 0.01 < self.closest_m {
                self.closest_m = f64::from(d) * 0.01;
                self.closest_dir = bin_dir(i, yaw);
            }
        }
    }

    fn no_data(&mut self, now: Duration, events: &mut Vec<CpEvent>) {
        let since = |t: Duration| now.saturating_sub(t);
        let quiet = self.warned_at.is_none_or(|t| since(t) > Duration::from_secs(1));
        if quiet && since(self.activated_at) > Duration::from_secs(1) {
            if since(self.map.stamp) > NO_DATA_HOLD && since(self.activated_at) > NO_DATA_HOLD {
                events.push(CpEvent::Hold);
            }
            self.warned_at = Some(now);
        }
    }

    /// The bin the setpoint points into and its direction, turned by up to CP_GUIDE_ANG towards the bin
    /// with the most room (PX4's `_transformSetpoint` and `_adaptSetpointDirection`).
    fn setpoint_bin(&self, acc: Xy, yaw: f64, p: &CpParams) -> (usize, Xy) {
        let body_deg = (acc.y.atan2(acc.x) - yaw).to_degrees() as f32;
        let index = ((wrap_360(body_deg) / BIN_DEG).floor() as usize).min(BIN_COUNT - 1);
        let dist = |i: i64| self.map.distances[i.rem_euclid(BIN_COUNT as i64) as usize];
        let guidance = (p.guide_deg / f64::from(BIN_DEG)).floor() as i64;
        let (mut best, mut best_cost) = (index, 9999.0);
        for i in index as i64 - guidance..=index as i64 + guidance {
            let room = |j: i64| match dist(j) {
                UNKNOWN => p.dist_m * 100.0,
                d => f64::from(d),
            };
            let mean = (room(i - 1) + room(i) + room(i + 1)) / 3.0;
            let cost = p.dist_m * 50.0 * (i - index as i64).abs() as f64 - mean - f64::from(dist(i));
            if cost < best_cost && dist(i) != UNKNOWN {
                best_cost = cost;
                best = i.rem_euclid(BIN_COUNT as i64) as usize;
            }
        }
        if best == index {
            (index, acc / acc.norm())
        } else {
            (best, bin_dir(best, yaw))
        }
    }

    /// PX4's `_getScale`: 1 far away, falling quadratically to 0 at the distance to keep, negative inside it.
    fn scale(reference_m: f64, min_keep: f64, p: &CpParams) -> f64 {
        let s = reference_m - min_keep;
        let scale_distance = min_keep.max(p.vel_manual / p.xy_p);
        let s = if s > 0.0 { (s / scale_distance).powi(2) } else { s };
        s.min(1.0)
    }

    fn distance_towards(&self, dir: Xy, yaw: f64) -> f64 {
        if dir.norm() <= f64::from(f32::EPSILON) {
            return 0.0;
        }
        let body_deg = (dir.y.atan2(dir.x) - yaw).to_degrees() as f32;
        f64::from(self.map.distances[bin_at(body_deg)]) * 0.01
    }

    /// The acceleration along `dir` of `length`, its part towards the closest obstacle scaled down.
    fn constrain(&self, dir: Xy, length: f64, yaw: f64, min_keep: f64, p: &CpParams) -> Xy {
        if self.closest_dir.dot(&dir) <= 0.0 {
            return dir * length;
        }
        let normal = self.closest_dir * dir.dot(&self.closest_dir);
        let tangential = dir - normal;
        let normal_scale = Self::scale(self.closest_m, min_keep, p);
        let tangential_scale = Self::scale(self.distance_towards(tangential, yaw), min_keep, p);
        (tangential * tangential_scale + normal * normal_scale) * length
    }

    /// The strongest braking any bin asks for, so the velocity setpoint can still stop `min_keep` before it
    /// after the delay (CP_DELAY plus the data's age); (0, zero) when no bin asks.
    fn velocity_compensation(&self, vel_sp: Xy, yaw: f64, now: Duration, min_keep: f64, p: &CpParams) -> (f64, Xy) {
        let (mut comp, mut comp_dir) = (f64::INFINITY, Xy::zeros());
        for i in 0..BIN_COUNT {
            let d_cm = self.map.distances[i];
            if d_cm <= self.map.min_distance || d_cm == UNKNOWN {
                continue;
            }
            let dir = bin_dir(i, yaw);
            let distance = f64::from(d_cm) * 0.01;
            let v_par = vel_sp.dot(&dir).max(0.0);
            let mut delay = v_par * p.delay_s;
            if distance < f64::from(self.map.max_ranges[i]) * 0.01 {
                delay += v_par * now.saturating_sub(self.map.stamps[i]).as_secs_f64();
            }
            let stop = distance - min_keep - delay;
            let c = if stop >= 0.0 {
                let v_max = max_speed_from_distance(p.jerk_max, p.acc_hor, stop, 0.0);
                p.xy_vel_p_acc * (v_max - v_par).min(0.0)
            } else {
                -p.xy_vel_p_acc * v_par
            };
            if c < comp {
                comp = c;
                comp_dir = dir;
            }
        }
        // PX4 multiplies an infinite "no constraint" by a zero direction here (NaN); the mock adds nothing.
        if comp.is_finite() {
            (comp, comp_dir)
        } else {
            (0.0, Xy::zeros())
        }
    }
}

#[cfg(test)]
#[path = "collision_prevention_tests.rs"]
mod tests;
