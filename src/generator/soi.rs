//! The segment of interest (SoI): the stretch of the mission the obstacles are placed on.

use crate::geometry::{P2, V2};
use crate::model::{Arena, Mission};

/// How the SoI was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SoiKind {
    /// A flight segment crossing both the bottom (`y.min`) and top (`y.max`) borders inside the arena.
    Crossing,
    /// No segment crosses both borders: the longest stretch of the path inside the arena.
    LongestInside,
}

/// The segment of interest in the local ground frame (`x` North, `y` East, metres).
///
/// `start` -> `end` is the direction of flight; for a [`SoiKind::Crossing`] SoI they are where the segment
/// crosses the two `y` borders, otherwise the ends of the stretch inside the arena.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Soi {
    /// Index of the mission segment (between flight-path points `segment` and `segment + 1`).
    pub segment: usize,
    /// Where the SoI enters the arena.
    #[serde(serialize_with = "ser_p2")]
    pub start: P2,
    /// Where it leaves.
    #[serde(serialize_with = "ser_p2")]
    pub end: P2,
    /// How it was chosen.
    pub kind: SoiKind,
}

fn ser_p2<S: serde::Serializer>(p: &P2, s: S) -> Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&[p.x, p.y], s)
}

impl Soi {
    /// Unit direction of flight.
    pub fn direction(&self) -> V2 {
        (self.end - self.start).normalize()
    }

    /// Length inside the arena, metres.
    pub fn length(&self) -> f64 {
        (self.end - self.start).norm()
    }
}

/// Picks the SoI of a mission: among the segments that cross both `y` borders of the arena with both
/// crossings inside its `x` extent, the one whose midpoint between the borders (its crossing of the
/// arena's middle `y`) lies closest, in `x`, to the arena's middle line; ties go to the earlier segment.
/// If none qualifies, the longest stretch of the path inside the arena; `None` if the path never enters it.
pub fn segment_of_interest(mission: &Mission, arena: &Arena) -> Option<Soi> {
    let path: Vec<P2> = mission
        .flight_path()
        .iter()
        .map(|p| P2::new(p.north_m, p.east_m))
        .collect();
    let mut best: Option<(f64, Soi)> = None;
    for (i, w) in path.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let (lo, hi) = (a.y.min(b.y), a.y.max(b.y));
        if !(lo <= arena.y.min && hi >= arena.y.max) || a.y == b.y {
            continue;
        }
        let at_y = |y: f64| P2::new(a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y), y);
        let (p_lo, p_hi) = (at_y(arena.y.min), at_y(arena.y.max));
        let inside = |p: P2| p.x > arena.x.min && p.x < arena.x.max;
        if !(inside(p_lo) && inside(p_hi)) {
            continue;
        }
        let (start, end) = if b.y > a.y { (p_lo, p_hi) } else { (p_hi, p_lo) };
        let mid_x = (p_lo.x + p_hi.x) / 2.0;
        let score = (mid_x - arena.middle_x()).abs();
        if best.is_none_or(|(s, _)| score < s) {
            best = Some((
                score,
                Soi {
                    segment: i,
                    start,
                    end,
                    kind: SoiKind::Crossing,
                },
            ));
        }
    }
    if let Some((_, soi)) = best {
        return Some(soi);
    }
    let mut longest: Option<Soi> = None;
    for (i, w) in path.windows(2).enumerate() {
        if let Some((start, end)) = clip_to_arena(w[0], w[1], arena)
            && (end - start).norm() > longest.map_or(1e-9, |s| s.length())
        {
            longest = Some(Soi {
                segment: i,
                start,
                end,
                kind: SoiKind::LongestInside,
            });
        }
    }
    longest
}

/// The part of segment `a`-`b` inside the arena's rectangle (Liang-Barsky clipping).
fn clip_to_arena(a: P2, b: P2, arena: &Arena) -> Option<(P2, P2)> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.x, a.x - arena.x.min),
        (d.x, arena.x.max - a.x),
        (-d.y, a.y - arena.y.min),
        (d.y, arena.y.max - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 < t1).then(|| (a + d * t0, a + d * t1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::SIM_HOME;

    fn mission_through(points: &[(f64, f64)]) -> Mission {
        Mission::through_local_points(points, 10.0, SIM_HOME)
    }

    #[test]
    fn picks_the_crossing_segment_closest_to_the_middle() {
        // Mission 3: the way up crosses the borders at x = 0.62 and 2.49 (mid 1.55, 6.55 m from x = -5), the
        // way down at x = -15.55 and -17.33 (mid -16.44, 11.44 m away): the way up wins.
        let m = mission_through(&[(0.0, 0.0), (3.30, 53.09), (-14.71, 54.11), (-17.87, 0.99)]);
        let s = segment_of_interest(&m, &Arena::default()).unwrap();
        assert_eq!((s.segment, s.kind), (0, SoiKind::Crossing));
        assert!((s.start.y - 10.0).abs() < 1e-12 && (s.end.y - 40.0).abs() < 1e-12);
        let m = mission_through(&[(0.0, 0.0), (3.30, 53.09), (-5.0, 54.0), (-6.0, 0.0)]);
        let s = segment_of_interest(&m, &Arena::default()).unwrap();
        assert_eq!(s.segment, 2);
        assert!(s.start.y > s.end.y, "flies down the arena");
    }

    #[test]
    fn falls_back_to_the_longest_stretch_inside() {
        let m = mission_through(&[(-50.0, 20.0), (50.0, 25.0), (0.0, 0.0)]);
        let s = segment_of_interest(&m, &Arena::default()).unwrap();
        assert_eq!((s.segment, s.kind), (0, SoiKind::LongestInside));
        assert!((s.start.x + 40.0).abs() < 1e-9 && (s.end.x - 30.0).abs() < 1e-9);
        assert!(segment_of_interest(&mission_through(&[(100.0, 0.0), (100.0, 50.0)]), &Arena::default()).is_none());
    }
}
