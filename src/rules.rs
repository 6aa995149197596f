//! The competition's rules for a valid test (`docs/formats.md`, rules), each violation named by field.

use serde::Serialize;
use serde_json::{Value, json};

use crate::geometry::{Footprint, footprint_distance};
use crate::model::{Arena, Mission, Obstacle, TestCase};

/// Gaps narrower than this between obstacles (or an obstacle and the arena's side border) are closed to the
/// drone when deciding whether obstacles wall off the mission: 2 m is the narrowest gap the 3DVFH* planner
/// reliably flies through with its 0.5 m-wide vehicle.
pub const MIN_PASSAGE_M: f64 = 2.0;

/// Gaps up to this count as touching (floating-point slack, metres).
pub const TOUCH_TOLERANCE_M: f64 = 1e-9;

/// One broken rule.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// Field path, e.g. `simulation.obstacles[0].size.l`.
    pub path: String,
    /// The offending value.
    pub value: Value,
    /// The rule, in words.
    pub rule: String,
}

fn v(path: String, value: Value, rule: impl Into<String>) -> Violation {
    Violation {
        path,
        value,
        rule: rule.into(),
    }
}

/// What a test needs to be flown and judged, beyond [`check`]'s rules: an obstacle. A file without one is a
/// case study, valid as such (`check` says so), but a flight of it has no distance to judge, and a test score
/// divides by the obstacles squared; `evaluate` and `score` refuse it by this rule.
pub fn judgeable(test: &TestCase) -> Option<Violation> {
    test.obstacles.is_empty().then(|| {
        v(
            "simulation.obstacles".into(),
            json!(0),
            "a test needs at least 1 obstacle to be judged (a file without obstacles is a case study)",
        )
    })
}

/// Every violation of `arena`'s rules by `test`; empty when the test is valid.
pub fn check(test: &TestCase, arena: &Arena) -> Vec<Violation> {
    check_obstacles(&test.obstacles, &test.mission, arena)
}

/// The rules applied to obstacles for a mission.
pub fn check_obstacles(obstacles: &[Obstacle], mission: &Mission, arena: &Arena) -> Vec<Violation> {
    let mut out = Vec::new();
    if obstacles.len() > arena.max_obstacles {
        out.push(v(
            "simulation.obstacles".into(),
            json!(obstacles.len()),
            format!("at most {} obstacles", arena.max_obstacles),
        ));
    }
    let altitude = arena.flight_altitude_m.max(mission.cruise_altitude_m());
    for (i, o) in obstacles.iter().enumerate() {
        let base = format!("simulation.obstacles[{i}]");
        let mut range = |field: &str, value: f64, r: crate::model::Range, what: &str| {
            if !r.contains(value) {
                out.push(v(
                    format!("{base}.{field}"),
                    json!(value),
                    format!("{what} must be in {} .. {}", r.min, r.max),
                ));
            }
        };
        range("size.l", o.size.l, arena.l, "length");
        range("size.w", o.size.w, arena.w, "width");
        range("size.h", o.size.h, arena.h, "height");
        range("position.x", o.position.x, arena.x, "centre x");
        range("position.y", o.position.y, arena.y, "centre y");
        range("position.r", o.position.r, arena.r, "rotation (degrees)");
        if o.size.h <= altitude {
            out.push(v(
                format!("{base}.size.h"),
                json!(o.size.h),
                format!("height must exceed the flight altitude {altitude} m"),
            ));
        }
        if o.position.z != 0.0 {
            out.push(v(
                format!("{base}.position.z"),
                json!(o.position.z),
                "boxes stand on the ground: z must be 0",
            ));
        }
        if o.size.l > 0.0 && o.size.w > 0.0 {
            out.extend(containment(&base, &o.footprint(), arena));
        }
    }
    for i in 0..obstacles.len() {
        for j in i + 1..obstacles.len() {
            let gap = footprint_distance(&obstacles[i].footprint(), &obstacles[j].footprint());
            if gap <= TOUCH_TOLERANCE_M {
                out.push(v(
                    format!("simulation.obstacles[{j}]"),
                    json!(format!("obstacles {i} and {j}")),
                    "obstacles must neither overlap nor touch",
                ));
            }
        }
    }
    out.extend(feasibility(obstacles, mission, arena));
    out
}

fn containment(base: &str, f: &Footprint, arena: &Arena) -> Option<Violation> {
    let (lo, hi) = f.bounds();
    let inside = lo.x > arena.x.min && hi.x < arena.x.max && lo.y > arena.y.min && hi.y < arena.y.max;
    (!inside).then(|| {
        v(
            format!("{base}.position"),
            json!({"x_min": lo.x, "x_max": hi.x, "y_min": lo.y, "y_max": hi.y}),
            format!(
                "the whole footprint must lie inside the arena {} < x < {}, {} < y < {}",
                arena.x.min, arena.x.max, arena.y.min, arena.y.max
            ),
        )
    })
}

/// Mission feasibility: no waypoint inside a box, and no chain of boxes walling off the arena from side to side.
fn feasibility(obstacles: &[Obstacle], mission: &Mission, arena: &Arena) -> Vec<Violation> {
    let mut out = Vec::new();
    let footprints: Vec<Footprint> = obstacles.iter().map(Obstacle::footprint).collect();
    for (k, p) in mission.flight_path().iter().enumerate() {
        let pt = crate::geometry::P2::new(p.north_m, p.east_m);
        for (i, f) in footprints.iter().enumerate() {
            if f.distance_to_point(pt) < MIN_PASSAGE_M / 2.0 {
                out.push(v(
                    format!("simulation.obstacles[{i}]"),
                    json!({"waypoint": k, "x": p.north_m, "y": p.east_m}),
                    format!(
                        "the mission must stay feasible: waypoint {k} lies within {} m of the box",
                        MIN_PASSAGE_M / 2.0
                    ),
                ));
            }
        }
    }
    // Union-find over obstacles plus the two side borders (x = min: node n, x = max: node n + 1).
    let n = footprints.len();
    let mut parent: Vec<usize> = (0..n + 2).collect();
    fn find(p: &mut [usize], mut a: usize) -> usize {
        while p[a] != a {
            p[a] = p[p[a]];
            a = p[a];
        }
        a
    }
    let join = |p: &mut Vec<usize>, a: usize, b: usize| {
        let (ra, rb) = (find(p, a), find(p, b));
        p[ra] = rb;
    };
    for i in 0..n {
        let (lo, hi) = footprints[i].bounds();
        if lo.x - arena.x.min < MIN_PASSAGE_M {
            join(&mut parent, i, n);
        }
        if arena.x.max - hi.x < MIN_PASSAGE_M {
            join(&mut parent, i, n + 1);
        }
        for j in i + 1..n {
            if footprint_distance(&footprints[i], &footprints[j]) < MIN_PASSAGE_M {
                join(&mut parent, i, j);
            }
        }
    }
    if n > 0 && find(&mut parent, n) == find(&mut parent, n + 1) {
        out.push(v(
            "simulation.obstacles".into(),
            json!(n),
            format!("the mission must stay feasible: the obstacles wall off the arena from x = {} to x = {} (gaps under {MIN_PASSAGE_M} m)", arena.x.min, arena.x.max),
        ));
    }
    out
}
