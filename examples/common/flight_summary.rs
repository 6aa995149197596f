//! One flight's summary for `competition_flights`: latched crawls (PX4 v1.12.3's turning lock holding the
//! speed just above 0.2 m/s), stops, and the time PX4's own path would take under that lock; plus the
//! number formatting of its tables.

use crate::flight_stats::{
    self, CRAWL_BAND, CRAWL_MIN_S, Cruise, STOP_BELOW, STOP_MIN_S, Track, angle_deg, cruise, median, quantile,
};

/// One latched crawl: a run in the crawl band lasting at least `CRAWL_MIN_S`.
#[derive(Debug, Clone)]
pub struct Crawl {
    pub start_s: f64,
    pub dur_s: f64,
    pub v_med: f64,
    /// Lowest 1-s speed in the 10 s before the run (a stop or the start of the leg arms PX4's lock low).
    pub pre_min: f64,
    /// Share of the run more than NAV_ACC_RAD off the leg's line.
    pub off_share: f64,
    /// Share of the run with PX4 v1.12.3's turning condition true.
    pub turning_share: f64,
    /// How it ended: back on the line, at the leg's target, or with the cruise.
    pub end: &'static str,
    /// Highest speed in the 15 s after it.
    pub after_max: f64,
    pub path_m: f64,
}

/// One stop (hover).
#[derive(Debug, Clone, Copy)]
pub struct Stop {
    /// Seconds.
    pub dur_s: f64,
    /// Distance to the nearest box during it, m.
    pub clear_m: f64,
    /// Direction of travel after it against before it, degrees.
    pub course_deg: Option<f64>,
    /// Heading at its end against its start, degrees (PX4 flights only).
    pub heading_deg: Option<f64>,
}

/// One flight's figures.
#[derive(Debug, Clone)]
pub struct Flight {
    pub id: String,
    pub source: String,
    pub t_px: Option<f64>,
    pub c: Cruise,
    pub crawls: Vec<Crawl>,
    /// Stops: (duration s, clearance m, course change degrees, heading change degrees).
    pub stops: Vec<Stop>,
    pub d: Option<f64>,
}

impl Flight {
    pub fn t_alt(&self) -> f64 {
        self.c.duration()
    }
    pub fn crawl_s(&self) -> f64 {
        self.crawls.iter().map(|c| c.dur_s).sum()
    }
    pub fn v_med(&self) -> f64 {
        median(&self.c.v)
    }
    pub fn v_p90(&self) -> f64 {
        quantile(&self.c.v, 0.9)
    }
    /// Mean speed over +-5 s of the sample closest to a box.
    pub fn v_at_closest(&self) -> Option<f64> {
        let i = (0..self.c.t.len()).min_by(|&a, &b| self.c.clear[a].total_cmp(&self.c.clear[b]))?;
        let near: Vec<f64> = (0..self.c.t.len())
            .filter(|&j| (self.c.t[j] - self.c.t[i]).abs() <= 5.0)
            .map(|j| self.c.v[j])
            .collect();
        Some(near.iter().sum::<f64>() / near.len().max(1) as f64)
    }
}

pub fn analyse(t: &Track) -> Option<Flight> {
    let c = cruise(t)?;
    let t0 = c.t[0];
    let in_band = |i: usize| c.v[i] > CRAWL_BAND.0 && c.v[i] < CRAWL_BAND.1;
    let crawls = c
        .runs(in_band, CRAWL_MIN_S)
        .into_iter()
        .map(|r| {
            let idx: Vec<usize> = (r.from..=r.to).collect();
            let v: Vec<f64> = idx.iter().map(|&i| c.v[i]).collect();
            let before: Vec<f64> = (0..=r.from)
                .filter(|&i| c.t[i] >= c.t[r.from] - 10.0)
                .map(|i| c.v_short[i])
                .collect();
            let after: Vec<f64> = (r.to..c.t.len())
                .filter(|&i| c.t[i] <= c.t[r.to] + 15.0)
                .map(|i| c.v[i])
                .collect();
            let last = r.to;
            let end = if c.to_target[last] < 3.0 {
                "at target"
            } else if c.off_track[last] < 1.0 {
                "rejoined line"
            } else if last + 1 >= c.t.len() {
                "cruise ended"
            } else if c.v[last + 1] <= CRAWL_BAND.0 {
                "slowed down"
            } else {
                "sped up off the line"
            };
            let share =
                |keep: &dyn Fn(usize) -> bool| idx.iter().filter(|&&i| keep(i)).count() as f64 / idx.len() as f64;
            let path_m = idx.windows(2).map(|w| dist(c.pos[w[0]], c.pos[w[1]])).sum();
            Crawl {
                start_s: c.t[r.from] - t0,
                dur_s: c.t[r.to] - c.t[r.from],
                v_med: median(&v),
                pre_min: before.iter().copied().fold(f64::INFINITY, f64::min),
                off_share: share(&|i| c.off_track[i] > t.nav_acc_rad),
                turning_share: share(&|i| c.turning[i]),
                end,
                after_max: after.iter().copied().fold(0.0, f64::max),
                path_m,
            }
        })
        .collect();
    let stops = c
        .runs(|i| c.v[i] < STOP_BELOW, STOP_MIN_S)
        .into_iter()
        .map(|r| {
            let (a, b) = (c.t[r.from], c.t[r.to]);
            let course = match (c.course(a - 4.0, a), c.course(b, b + 4.0)) {
                (Some(x), Some(y)) => Some(angle_deg(x, y)),
                _ => None,
            };
            let yaw = match (c.heading[r.from], c.heading[r.to]) {
                (Some(x), Some(y)) => Some(angle_deg(x, y)),
                _ => None,
            };
            let clear = (r.from..=r.to).map(|i| c.clear[i]).fold(f64::INFINITY, f64::min);
            Stop {
                dur_s: b - a,
                clear_m: clear,
                course_deg: course,
                heading_deg: yaw,
            }
        })
        .collect();
    Some(Flight {
        id: t.id.clone(),
        source: t.source.clone(),
        t_px: t.t_px,
        c,
        crawls,
        stops,
        d: t.min_distance,
    })
}

/// Seconds the cruise would take under PX4 v1.12.3's turning lock, replayed on the flown path: while turning
/// the speed is capped at the speed of the last sample that was not (at least 0.2 m/s, the lock's threshold).
/// An approximation: the 4-s speed stands in for PX4's trajectory speed and its braking-law limit, and the
/// slower flight is not allowed to change the planner's path.
pub fn lock_replay_s(c: &Cruise) -> f64 {
    let mut lock = f64::INFINITY;
    let mut total = 0.0;
    for i in 1..c.t.len() {
        if !c.turning[i] {
            lock = c.v[i].max(flight_stats::TURN_MIN_SPEED);
        }
        let dt = c.t[i] - c.t[i - 1];
        let ds = dist(c.pos[i], c.pos[i - 1]);
        let v = if dt > 0.0 { ds / dt } else { 0.0 };
        let capped = if c.turning[i] { v.min(lock) } else { v };
        total += if ds > 0.01 { ds / capped.max(1e-3) } else { dt };
    }
    total
}

pub fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

pub fn f2(v: f64) -> String {
    if v.is_finite() { format!("{v:.2}") } else { "-".into() }
}

pub fn range(v: &[f64], digits: usize) -> String {
    if v.is_empty() {
        return "-".into();
    }
    let q = |p| quantile(v, p);
    format!("{:.d$} ({:.d$}-{:.d$})", median(v), q(0.0), q(1.0), d = digits)
}

/// PX4's braking law (TrajMath::computeMaxSpeedFromDistance with final speed 0): the highest speed from which
/// the vehicle stops within `d` metres, with acceleration `a` and jerk `j`.
pub fn braking_speed(j: f64, a: f64, d: f64) -> f64 {
    let b = 4.0 * a * a / j;
    0.5 * (-b + (b * b + 8.0 * a * d).sqrt())
}

/// Speed (m/s) and clearance (m) per 10 s of cruise, as `speed/clearance`.
pub fn trace(f: &Flight) {
    let c = &f.c;
    let mut cells = Vec::new();
    let mut i = 0;
    while i < c.t.len() {
        let j = (i..c.t.len())
            .find(|&j| c.t[j] >= c.t[i] + 10.0)
            .unwrap_or(c.t.len() - 1);
        if j == i {
            break;
        }
        let v = (c.pos[j][0] - c.pos[i][0]).hypot(c.pos[j][1] - c.pos[i][1]) / (c.t[j] - c.t[i]);
        cells.push(format!("{v:.2}/{:.0}", c.clear[i]));
        i = j;
    }
    println!(
        "\n{} ({}), per 10 s from the start of the cruise: {}",
        f.id,
        f.source,
        cells.join(" ")
    );
}
