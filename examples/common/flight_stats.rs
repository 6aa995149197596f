//! Speed, stop and clearance statistics of flown trajectories (0.5 s bins, test frame), shared by the examples
//! that compare the competition's recorded flights with PX4 flights of the same cases.
//!
//! Speeds are horizontal and taken over a centred window (`SPEED_WINDOW_S`): the recorded trajectories were
//! digitised from plots (0.15 m and 0.4-2.6 s per pixel), so a 0.5 s difference would be mostly pixel noise.

use std::path::Path;

use prgenuav::geometry::{Footprint, P2};
use prgenuav::lfs::fidelity::{FlightCase, competition_params, load_flight};
use prgenuav::model::Trajectory;

/// Width of the centred window a speed is measured over, seconds.
pub const SPEED_WINDOW_S: f64 = 4.0;
/// Height above which a sample counts as cruise, metres (the missions fly at 10 m).
pub const CRUISE_ABOVE_M: f64 = 8.0;
/// A stop: speed below this (m/s) for at least `STOP_MIN_S`.
pub const STOP_BELOW: f64 = 0.1;
/// Shortest stop counted, seconds.
pub const STOP_MIN_S: f64 = 2.0;
/// The crawl band, m/s: PX4 v1.12.3's turning lock holds the speed just above its 0.2 m/s threshold.
pub const CRAWL_BAND: (f64, f64) = (0.12, 0.5);
/// Shortest run inside the crawl band counted as a latched crawl, seconds.
pub const CRAWL_MIN_S: f64 = 20.0;
/// PX4's "turning" test: trajectory speed above 0.2 m/s and velocity more than acos(0.98) = 11.5 degrees off
/// the direction to the target (FlightTaskAutoLineSmoothVel::_updateTurningCheck).
pub const TURN_MIN_SPEED: f64 = 0.2;
/// cos of the turning angle threshold.
pub const TURN_COS: f64 = 0.98;

/// One flown trajectory with what it is judged against.
#[derive(Debug, Clone)]
pub struct Track {
    /// Case id.
    pub id: String,
    /// Who flew it (the recorded flight's repository owner, or `px4-v1.14-sih`).
    pub source: String,
    /// Seconds per pixel of the plot the trajectory was digitised from (recorded flights only).
    pub t_px: Option<f64>,
    /// `(t, x, y, z)`: seconds, North, East, height up.
    pub samples: Vec<[f64; 4]>,
    /// Heading per sample, radians clockwise from North, where known.
    pub heading: Vec<Option<f64>>,
    /// Box footprints.
    pub boxes: Vec<Footprint>,
    /// Positional mission items (takeoff, waypoints, land), North / East.
    pub route: Vec<[f64; 2]>,
    /// The flight's minimum distance in the case's definition.
    pub min_distance: Option<f64>,
    /// NAV_ACC_RAD the flight used (the acceptance radius and PX4 v1.12.3's off-track threshold).
    pub nav_acc_rad: f64,
    /// Whether the recorded flight landed (its `flight.landed`); `None` for PX4 flights.
    pub landed: Option<bool>,
}

/// NAV_ACC_RAD among `params` (PX4's multicopter default 2 m where unset).
fn nav_acc_rad(params: &[prgenuav::model::Param]) -> f64 {
    params.iter().find(|p| p.name == "NAV_ACC_RAD").map_or(2.0, |p| p.value)
}

/// The recorded trajectory of a tier-A flight file (`None` for other tiers), with its source, plot resolution,
/// route and boxes; flights without boxes (the organisers' samples) are kept, with no distance.
pub fn recorded_track(path: &Path) -> Option<Track> {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()?;
    if !v["tier"].as_str()?.starts_with('A') {
        return None;
    }
    let case: Option<FlightCase> = load_flight(path).ok().flatten();
    let samples = v["trajectory"]
        .as_array()?
        .iter()
        .map(|s| Some([s[0].as_f64()?, s[1].as_f64()?, s[2].as_f64()?, s[3].as_f64()?]))
        .collect::<Option<Vec<_>>>()?;
    let route = v["mission"]["waypoints"]
        .as_array()?
        .iter()
        .filter(|w| matches!(w["cmd"].as_u64(), Some(16 | 21 | 22)))
        .filter_map(|w| Some([w["x"].as_f64()?, w["y"].as_f64()?]))
        .collect();
    let repo = v["source"]["repo"].as_str().unwrap_or("?");
    let params = case.as_ref().map_or_else(competition_params, |c| c.params.clone());
    Some(Track {
        id: v["id"].as_str()?.to_string(),
        source: repo.split('/').next().unwrap_or(repo).to_string(),
        t_px: v["digitization_quality"]["t_s_per_px"].as_f64(),
        heading: vec![None; samples.len()],
        samples,
        boxes: case
            .as_ref()
            .map_or_else(Vec::new, |c| c.obstacles.iter().map(|o| o.footprint()).collect()),
        route,
        min_distance: case.as_ref().map(|c| c.real_m),
        nav_acc_rad: nav_acc_rad(&params),
        landed: v["flight"]["landed"].as_bool(),
    })
}

/// The PX4 flight of `recorded`'s case (`PX4_DIR/traj/<id>.csv`, test frame), with the re-judged distance `d`.
pub fn px4_track(px4_dir: &Path, recorded: &Track, d: Option<f64>) -> Option<Track> {
    let traj = Trajectory::load_csv(&px4_dir.join("traj").join(format!("{}.csv", recorded.id))).ok()?;
    Some(Track {
        source: "px4-v1.14-sih".into(),
        t_px: None,
        samples: traj.samples.iter().map(|s| [s.t_s, s.x, s.y, s.z]).collect(),
        heading: traj.samples.iter().map(|s| s.r).collect(),
        min_distance: d,
        landed: None,
        ..recorded.clone()
    })
}

/// A maximal run of samples, by index (inclusive).
#[derive(Debug, Clone, Copy)]
pub struct Run {
    /// First sample.
    pub from: usize,
    /// Last sample.
    pub to: usize,
}

/// Per-sample quantities of a track's cruise.
#[derive(Debug, Clone, Default)]
pub struct Cruise {
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Horizontal speed over the window, m/s.
    pub v: Vec<f64>,
    /// Horizontal speed over a 1 s window (noisier; shows short stops the long window smooths away), m/s.
    pub v_short: Vec<f64>,
    /// Velocity over the window (North, East), m/s.
    pub vel: Vec<[f64; 2]>,
    /// Distance to the nearest box footprint, m (infinite without boxes).
    pub clear: Vec<f64>,
    /// Distance from the current leg's line, m.
    pub off_track: Vec<f64>,
    /// Distance to the current leg's target, m.
    pub to_target: Vec<f64>,
    /// Whether PX4 v1.12.3 would count the vehicle as turning (and so lock its speed limit).
    pub turning: Vec<bool>,
    /// Heading, radians, where known.
    pub heading: Vec<Option<f64>>,
    /// Positions (North, East).
    pub pos: Vec<[f64; 2]>,
}

impl Cruise {
    /// Seconds covered by sample `i` (half the gaps to its neighbours).
    pub fn dt(&self, i: usize) -> f64 {
        let n = self.t.len();
        let a = if i > 0 { self.t[i - 1] } else { self.t[i] };
        let b = if i + 1 < n { self.t[i + 1] } else { self.t[i] };
        ((b - a) / 2.0).max(0.0)
    }

    /// Total seconds of the samples where `keep` holds.
    pub fn time_where(&self, keep: impl Fn(usize) -> bool) -> f64 {
        (0..self.t.len()).filter(|&i| keep(i)).map(|i| self.dt(i)).sum()
    }

    /// Duration of the cruise, s.
    pub fn duration(&self) -> f64 {
        match (self.t.first(), self.t.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }

    /// Maximal runs of samples where `keep` holds lasting at least `min_s` seconds.
    pub fn runs(&self, keep: impl Fn(usize) -> bool, min_s: f64) -> Vec<Run> {
        let mut out = Vec::new();
        let mut i = 0;
        while i < self.t.len() {
            if !keep(i) {
                i += 1;
                continue;
            }
            let from = i;
            while i + 1 < self.t.len() && keep(i + 1) {
                i += 1;
            }
            if self.t[i] - self.t[from] >= min_s {
                out.push(Run { from, to: i });
            }
            i += 1;
        }
        out
    }

    /// Direction of travel (radians from North, clockwise) over `[t0, t1]`, if it moved at least 0.3 m.
    pub fn course(&self, t0: f64, t1: f64) -> Option<f64> {
        let a = self.t.iter().position(|&t| t >= t0)?;
        let b = self.t.iter().rposition(|&t| t <= t1)?;
        let (p, q) = (self.pos[a], self.pos[b.max(a)]);
        let (dn, de) = (q[0] - p[0], q[1] - p[1]);
        (dn.hypot(de) >= 0.3).then(|| de.atan2(dn))
    }
}

/// The cruise (first to last sample above `CRUISE_ABOVE_M`) of a track; `None` if it never got there.
pub fn cruise(track: &Track) -> Option<Cruise> {
    let s = &track.samples;
    let first = s.iter().position(|p| p[3] > CRUISE_ABOVE_M)?;
    let last = s.iter().rposition(|p| p[3] > CRUISE_ABOVE_M)?;
    let h = SPEED_WINDOW_S / 2.0;
    let mut c = Cruise::default();
    let (mut lo, mut hi) = (0usize, 0usize);
    let (mut slo, mut shi) = (0usize, 0usize);
    let mut leg = 1usize;
    for i in first..=last {
        let t = s[i][0];
        while s[lo][0] < t - h {
            lo += 1;
        }
        while hi + 1 < s.len() && s[hi + 1][0] <= t + h {
            hi += 1;
        }
        while s[slo][0] < t - 0.5 {
            slo += 1;
        }
        while shi + 1 < s.len() && s[shi + 1][0] <= t + 0.5 {
            shi += 1;
        }
        let short = (s[shi][1] - s[slo][1]).hypot(s[shi][2] - s[slo][2]) / (s[shi][0] - s[slo][0]).max(1e-6);
        let span = (s[hi][0] - s[lo][0]).max(1e-6);
        let vel = [(s[hi][1] - s[lo][1]) / span, (s[hi][2] - s[lo][2]) / span];
        let p = P2::new(s[i][1], s[i][2]);
        let clear = track
            .boxes
            .iter()
            .map(|b| b.distance_to_point(p))
            .fold(f64::INFINITY, f64::min);
        leg = advance_leg(&track.route, leg, p);
        let (off, to_target, aim) = leg_geometry(&track.route, leg, p, track.nav_acc_rad);
        let speed = vel[0].hypot(vel[1]);
        let aim_len = aim[0].hypot(aim[1]);
        let cos = if speed > 0.0 && aim_len > 0.0 {
            (vel[0] * aim[0] + vel[1] * aim[1]) / (speed * aim_len)
        } else {
            1.0
        };
        c.t.push(t);
        c.v.push(speed);
        c.v_short.push(short);
        c.vel.push(vel);
        c.clear.push(clear);
        c.off_track.push(off);
        c.to_target.push(to_target);
        c.turning
            .push(speed > TURN_MIN_SPEED && cos < TURN_COS && aim_len > track.nav_acc_rad);
        c.heading.push(track.heading.get(i).copied().flatten());
        c.pos.push([s[i][1], s[i][2]]);
    }
    Some(c)
}

/// The leg (index of its target in `route`) after `p`: the next one once `p` is within 1.5 m of the target or
/// past it along the leg (PX4 then widens the acceptance radius: ObstacleAvoidance::checkAvoidanceProgress).
fn advance_leg(route: &[[f64; 2]], mut leg: usize, p: P2) -> usize {
    while leg + 1 < route.len() {
        let (a, b) = (route[leg - 1], route[leg]);
        let (ux, uy, len) = unit(a, b);
        let along = (p.x - a[0]) * ux + (p.y - a[1]) * uy;
        if (p.x - b[0]).hypot(p.y - b[1]) < 1.5 || along > len {
            leg += 1;
        } else {
            break;
        }
    }
    leg
}

fn unit(a: [f64; 2], b: [f64; 2]) -> (f64, f64, f64) {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len = dx.hypot(dy).max(1e-9);
    (dx / len, dy / len, len)
}

/// Off-track distance, distance to the leg's target, and the vector to PX4 v1.12.3's internal target: the
/// closest point on the leg when more than the acceptance radius off it (State::offtrack), else the target.
fn leg_geometry(route: &[[f64; 2]], leg: usize, p: P2, acc_rad: f64) -> (f64, f64, [f64; 2]) {
    if route.len() < 2 {
        return (0.0, 0.0, [0.0, 0.0]);
    }
    let leg = leg.min(route.len() - 1).max(1);
    let (a, b) = (route[leg - 1], route[leg]);
    let (ux, uy, _) = unit(a, b);
    let along = (p.x - a[0]) * ux + (p.y - a[1]) * uy;
    let closest = [a[0] + ux * along, a[1] + uy * along];
    let off = (p.x - closest[0]).hypot(p.y - closest[1]);
    let target = if off > acc_rad { closest } else { b };
    (off, (p.x - b[0]).hypot(p.y - b[1]), [target[0] - p.x, target[1] - p.y])
}

/// Median of `v` (NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    quantile(v, 0.5)
}

/// The `q` quantile of `v` by linear interpolation (NaN when empty).
pub fn quantile(v: &[f64], q: f64) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < s.len() {
        s[i] * (1.0 - f) + s[i + 1] * f
    } else {
        s[i]
    }
}

/// Smallest absolute difference of two angles, degrees.
pub fn angle_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).to_degrees().rem_euclid(360.0);
    d.min(360.0 - d)
}
