//! A model of PX4 Collision Prevention's acceleration constraint in Position mode (v1.16, as read from its
//! source for facts; our own code): the stick's acceleration is bent toward a freer sector (within
//! `CP_GUIDE_ANG`), scaled down toward the closest obstacle, and a braking term keeps the velocity below
//! what can still stop `CP_DIST` short of each sector's obstacle, allowing for `CP_DELAY` and the scan's age.
//!
//! Horizontal vectors are (North, East) in the local NED frame; the map's bins are the body FRD sectors of
//! [`super::range_sensor`] (bin `i` centred `i x 5` degrees clockwise from the nose), centimetres,
//! `u16::MAX` = no data.

use super::cp_params::CpParams;
use super::range_sensor::SECTORS;

/// The multicopter parameters Collision Prevention reads (PX4 v1.16 defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Px4Limits {
    /// MPC_VEL_MANUAL, m/s.
    pub vel_manual: f64,
    /// MPC_ACC_HOR, m/s².
    pub acc_hor: f64,
    /// MPC_JERK_MAX, m/s³.
    pub jerk_max: f64,
    /// MPC_XY_VEL_P_ACC, 1/s.
    pub xy_vel_p_acc: f64,
    /// MPC_XY_P, 1/s.
    pub xy_p: f64,
}

impl Default for Px4Limits {
    fn default() -> Self {
        Self {
            vel_manual: 10.0,
            acc_hor: 3.0,
            jerk_max: 8.0,
            xy_vel_p_acc: 1.8,
            xy_p: 0.95,
        }
    }
}

/// Collision Prevention's obstacle map: the last scan and its age.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObstacleMap {
    /// Per body sector, centimetres.
    pub bins: [u16; SECTORS],
    /// The sensor's range, centimetres.
    pub min_cm: u16,
    /// The sensor's farthest reading, centimetres.
    pub max_cm: u16,
    /// Seconds since the scan.
    pub age_s: f64,
}

const BIN_DEG: f64 = 360.0 / SECTORS as f64;

/// The (North, East) unit vector of body bin `i` for heading `yaw_rad`.
fn bin_dir(i: usize, yaw_rad: f64) -> [f64; 2] {
    let a = yaw_rad + (i as f64 * BIN_DEG).to_radians();
    [a.cos(), a.sin()]
}

/// The bin a world direction falls in.
fn bin_of(dir: [f64; 2], yaw_rad: f64) -> usize {
    let deg = (dir[1].atan2(dir[0]) - yaw_rad).to_degrees().rem_euclid(360.0);
    ((deg / BIN_DEG).floor() as usize) % SECTORS
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The highest speed that can still brake to rest within `dist` (jerk-limited ramp into `acc`).
pub fn max_speed_from_distance(jerk: f64, acc: f64, dist: f64) -> f64 {
    let b = 4.0 * acc * acc / jerk;
    let c = -2.0 * acc * dist;
    (0.5 * (-b + (b * b - 4.0 * c).sqrt())).max(0.0)
}

/// The constrained acceleration for the stick's `accel` with the current velocity setpoint `vel_sp`.
pub fn constrain(
    accel: [f64; 2],
    vel_sp: [f64; 2],
    yaw_rad: f64,
    map: &ObstacleMap,
    cp: &CpParams,
    lim: &Px4Limits,
) -> [f64; 2] {
    let length = accel[0].hypot(accel[1]);
    if !map.bins.iter().any(|b| *b < u16::MAX) {
        return [0.0, 0.0];
    }
    if length <= 0.001 {
        return accel;
    }
    let keep = (f64::from(map.min_cm) / 100.0).max(cp.dist_m);
    let (dir, index) = guide([accel[0] / length, accel[1] / length], yaw_rad, map, cp);
    let feasible = map.bins[index] != u16::MAX || cp.go_no_data;
    let mut out = if feasible {
        scaled(dir, length, yaw_rad, map, keep, lim)
    } else {
        [0.0, 0.0]
    };
    if let Some((a, d)) = braking(vel_sp, yaw_rad, map, cp, lim, keep) {
        out = [out[0] + a * d[0], out[1] + a * d[1]];
    }
    out
}

/// The stick's direction bent (within `CP_GUIDE_ANG`) toward the bin that trades deviation for clearance
/// best, and its bin.
fn guide(dir: [f64; 2], yaw_rad: f64, map: &ObstacleMap, cp: &CpParams) -> ([f64; 2], usize) {
    let original = bin_of(dir, yaw_rad) as i64;
    let n = SECTORS as i64;
    let guidance = (cp.guide_ang_deg / BIN_DEG).floor() as i64;
    let dist = |i: i64| {
        let b = map.bins[i.rem_euclid(n) as usize];
        if b == u16::MAX { cp.dist_m * 100.0 } else { f64::from(b) }
    };
    let mut best = (9999.0, original.rem_euclid(n) as usize);
    for i in original - guidance..=original + guidance {
        let bin = i.rem_euclid(n) as usize;
        let mean = (dist(i - 1) + dist(i) + dist(i + 1)) / 3.0;
        let cost = cp.dist_m * 50.0 * (i - original).abs() as f64 - mean - f64::from(map.bins[bin]);
        if cost < best.0 && map.bins[bin] != u16::MAX {
            best = (cost, bin);
        }
    }
    if best.1 == original.rem_euclid(n) as usize {
        (dir, best.1)
    } else {
        (bin_dir(best.1, yaw_rad), best.1)
    }
}

/// Collision Prevention's scale for a clearance `d`: 1 far away, shrinking (squared) toward `keep`,
/// negative (pushing back) inside it.
fn scale(d: f64, keep: f64, lim: &Px4Limits) -> f64 {
    let s = d - keep;
    let reach = keep.max(lim.vel_manual / lim.xy_p);
    (if s > 0.0 { (s / reach).powi(2) } else { s }).min(1.0)
}

/// The acceleration toward the closest obstacle scaled by its clearance, the tangential part by the
/// clearance along it.
fn scaled(dir: [f64; 2], length: f64, yaw_rad: f64, map: &ObstacleMap, keep: f64, lim: &Px4Limits) -> [f64; 2] {
    let (ci, cd) = map
        .bins
        .iter()
        .enumerate()
        .min_by_key(|(_, b)| **b)
        .map(|(i, b)| (i, f64::from(*b) / 100.0))
        .unwrap_or((0, f64::INFINITY));
    let closest = bin_dir(ci, yaw_rad);
    let along = dot(dir, closest);
    if along <= 0.0 {
        return [dir[0] * length, dir[1] * length];
    }
    let normal = [closest[0] * along, closest[1] * along];
    let tangential = [dir[0] - normal[0], dir[1] - normal[1]];
    let t_norm = tangential[0].hypot(tangential[1]);
    let t_dist = if t_norm > f64::EPSILON {
        f64::from(map.bins[bin_of(tangential, yaw_rad)]) / 100.0
    } else {
        0.0
    };
    let (ns, ts) = (scale(cd, keep, lim), scale(t_dist, keep, lim));
    [
        (tangential[0] * ts + normal[0] * ns) * length,
        (tangential[1] * ts + normal[1] * ns) * length,
    ]
}

/// The strongest braking any bin asks for: (acceleration along the direction, the bin's direction).
fn braking(
    vel_sp: [f64; 2],
    yaw_rad: f64,
    map: &ObstacleMap,
    cp: &CpParams,
    lim: &Px4Limits,
    keep: f64,
) -> Option<(f64, [f64; 2])> {
    let mut best: Option<(f64, [f64; 2])> = None;
    for (i, b) in map.bins.iter().enumerate() {
        if *b <= map.min_cm || *b == u16::MAX {
            continue;
        }
        let d = f64::from(*b) / 100.0;
        let dir = bin_dir(i, yaw_rad);
        let v = dot(vel_sp, dir).max(0.0);
        let mut delay = v * cp.delay_s;
        if *b < map.max_cm {
            delay += v * map.age_s;
        }
        let stop = d - keep - delay;
        let a = if stop >= 0.0 {
            lim.xy_vel_p_acc * (max_speed_from_distance(lim.jerk_max, lim.acc_hor, stop) - v).min(0.0)
        } else {
            -lim.xy_vel_p_acc * v
        };
        if best.is_none_or(|(x, _)| a < x) {
            best = Some((a, dir));
        }
    }
    best
}

#[cfg(test)]
#[path = "cp_constraint_tests.rs"]
mod tests;
