//! The paper's canonical two-obstacle construction, and the mirror transforms that serve every SoI.

use rand::Rng;

use super::adaptive::{DIMS, PAPER_DIMS, Proposal, SPLIT, THIRD, THIRD_AHEAD, THIRD_FROM};
use super::config::{Family, GeneratorConfig};
use super::soi::{Soi, SoiKind};
use crate::geometry::{P2, V2};
use crate::model::{Arena, Obstacle, Range};

/// Which side of the direction of flight a thing lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Counter-clockwise of the direction of flight in the x-y plane (plotted with x across, y up).
    Left,
    /// To the right (clockwise of it).
    Right,
}

/// Reflections about the arena's middle lines; they map the arena onto itself.
///
/// The canonical construction assumes the SoI is flown towards increasing `y` and obstacle 1's A part lies
/// on its left; `y` decides the first, and `x` (together with `y`, as every reflection swaps left and right)
/// the second.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Mirror {
    /// Reflect `x` about the arena's middle `x`.
    pub x: bool,
    /// Reflect `y` about the arena's middle `y`.
    pub y: bool,
}

impl Mirror {
    /// The point's image (the map is its own inverse).
    pub fn point(&self, p: P2, arena: &Arena) -> P2 {
        P2::new(
            if self.x { 2.0 * arena.x.mid() - p.x } else { p.x },
            if self.y { 2.0 * arena.y.mid() - p.y } else { p.y },
        )
    }

    /// The direction's image.
    pub fn direction(&self, v: V2) -> V2 {
        V2::new(if self.x { -v.x } else { v.x }, if self.y { -v.y } else { v.y })
    }
}

/// The left-hand perpendicular of `v` (counter-clockwise by 90 degrees in the x-y plane).
pub fn left_of(v: V2) -> V2 {
    V2::new(-v.y, v.x)
}

/// Distance from `p` along unit `u` to the arena's border (0 if `p` is outside).
pub fn room(p: P2, u: V2, arena: &Arena) -> f64 {
    let mut t = f64::INFINITY;
    for (pc, uc, lo, hi) in [
        (p.x, u.x, arena.x.min, arena.x.max),
        (p.y, u.y, arena.y.min, arena.y.max),
    ] {
        if uc > 0.0 {
            t = t.min((hi - pc) / uc);
        } else if uc < 0.0 {
            t = t.min((lo - pc) / uc);
        }
    }
    t.max(0.0)
}

/// The transform for a SoI: flown towards +y in the canonical frame, A part on the world side with more room
/// (it also carries obstacle 2), measured from the SoI's midpoint.
pub fn canonical_mirror(soi: &Soi, arena: &Arena) -> (Mirror, Side) {
    let d = soi.direction();
    let mid = P2::from((soi.start.coords + soi.end.coords) / 2.0);
    let a_side = if room(mid, left_of(d), arena) >= room(mid, -left_of(d), arena) {
        Side::Left
    } else {
        Side::Right
    };
    let y = d.y < 0.0;
    // One reflection turns the world's left into the canonical right.
    let x = y ^ (a_side == Side::Right);
    (Mirror { x, y }, a_side)
}

/// The numbers drawn for one test, and where the SoI crosses obstacle 1.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Draw {
    /// Diagonal of obstacle 1's base, metres.
    pub diagonal_m: f64,
    /// Length of obstacle 1's base, metres.
    pub length_m: f64,
    /// Acute angle between obstacle 1's A direction and the direction of flight, degrees.
    pub angle_deg: f64,
    /// Gap between obstacle 1's A end and obstacle 2, metres.
    pub gap_m: f64,
    /// Share of obstacle 2's length past obstacle 1's back face.
    pub overhang: f64,
    /// Share of obstacle 1's length on the A side of the SoI.
    pub split: f64,
    /// The third obstacle's clear distance beyond the pair along the SoI, metres (`None`: two obstacles).
    pub third_ahead_m: Option<f64>,
    /// Where the SoI crosses obstacle 1's long axis (world frame, `x` North, `y` East).
    #[serde(serialize_with = "ser_p2")]
    pub crossing: P2,
    /// The five draws in [0, 1] as used (after the [`Proposal`]): what an adaptive campaign learns from.
    pub unit: [f64; DIMS],
}

fn ser_p2<S: serde::Serializer>(p: &P2, s: S) -> Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&[p.x, p.y], s)
}

/// Draws one candidate test (two obstacles, or three in the extended family); `None` when the draw cannot fit
/// (the caller draws again).
///
/// Always makes the same number of draws from `rng` (five for the paper's family, [`DIMS`] for the extended
/// one), so a test's numbers do not depend on earlier rejections' paths; `dist` shapes where in their ranges
/// they fall (a uniform histogram: the paper's generator).
pub fn draw_test(
    rng: &mut impl Rng,
    soi: &Soi,
    (mirror, arena): (Mirror, &Arena),
    cfg: &GeneratorConfig,
    (family, dist): (Family, &Proposal),
) -> Option<(Draw, Vec<Obstacle>)> {
    let mut u = unit_draws(rng, family, dist);
    let split = split_of(cfg, family, &mut u);
    let w = cfg.width_m;
    let (diagonal, length) = diagonal_and_length(cfg, arena, u[0]);

    // Canonical frame: flown towards +y, A on the left.
    let (s0, s1) = (mirror.point(soi.start, arena), mirror.point(soi.end, arena));
    let d = (s1 - s0).normalize();
    let crossing = soi_crossing(soi.kind, (s0, s1), diagonal, u[1], arena)?;
    // The paper's containment test: split x diagonal fits on the A side, the rest on the B side.
    let left = left_of(d);
    if room(crossing, left, arena) <= split * diagonal || room(crossing, -left, arena) <= (1.0 - split) * diagonal {
        return None;
    }
    let angle = lerp(cfg.angle_deg, u[2]).to_radians();
    let a = d * angle.cos() + left * angle.sin();
    let c1 = crossing - a * ((0.5 - split) * length);
    let (gap, overhang) = (lerp(cfg.gap_m, u[3]), lerp(cfg.overhang, u[4]));
    let (c2, a2, length2) = second_box(cfg, (crossing, a), split * length, (gap, overhang), length);

    let axis = mirror.direction(a);
    let mut obstacles = vec![
        oriented(mirror.point(c1, arena), axis, length, w, cfg.height_m),
        oriented(mirror.point(c2, arena), mirror.direction(a2), length2, w, cfg.height_m),
    ];
    let third_ahead_m =
        (family == Family::Extended && u[THIRD] >= THIRD_FROM).then(|| lerp(cfg.third_ahead_m, u[THIRD_AHEAD]));
    if let Some(ahead) = third_ahead_m {
        let pair = Pair {
            d,
            left,
            angle,
            split,
            crossing,
            boxes: [(c1, a, length), (c2, a2, length2)],
            w,
        };
        obstacles.push(third_obstacle(&pair, ahead, (s0, s1), (mirror, arena), cfg)?);
    }
    let draw = Draw {
        diagonal_m: diagonal,
        length_m: length,
        angle_deg: angle.to_degrees(),
        gap_m: gap,
        overhang,
        split,
        third_ahead_m,
        crossing: mirror.point(crossing, arena),
        unit: u,
    };
    Some((draw, obstacles))
}

/// Obstacle 2 (`length_factor` x obstacle 1's `length`), `gap` metres beyond obstacle 1's end (`beyond` metres
/// from the crossing along obstacle 1's axis `a`) and shifted forward by its `overhang`: centre, axis, length.
fn second_box(
    cfg: &GeneratorConfig,
    (crossing, a): (P2, V2),
    beyond: f64,
    (gap, overhang): (f64, f64),
    length: f64,
) -> (P2, V2, f64) {
    let w = cfg.width_m;
    let m = V2::new(a.y, -a.x); // perpendicular to a, pointing forward (m . d = sin(angle) > 0)
    let length2 = cfg.length_factor * length;
    let along_m = w / 2.0 + overhang * length2 - length2 / 2.0;
    let c2 = crossing + a * (beyond + gap + w / 2.0) + m * along_m;
    (c2, V2::new(-a.y, a.x), length2)
}

/// Obstacle 1's diagonal and length from draw `t`; the diagonal's top is lowered so that obstacle 2
/// (`length_factor` x obstacle 1) respects the length rule too.
fn diagonal_and_length(cfg: &GeneratorConfig, arena: &Arena, t: f64) -> (f64, f64) {
    let w = cfg.width_m;
    let d_max = cfg
        .diagonal_m
        .max
        .min(((arena.l.max.min(arena.w.max) / cfg.length_factor).powi(2) + w * w).sqrt());
    let diagonal = cfg.diagonal_m.min + (d_max - cfg.diagonal_m.min) * t;
    (diagonal, (diagonal * diagonal - w * w).sqrt())
}

/// The extended family's third box, `ahead` metres beyond the pair along the SoI, as long as obstacle 1;
/// `None` when it cannot fit.
fn third_obstacle(
    pair: &Pair,
    ahead: f64,
    soi: (P2, P2),
    (mirror, arena): (Mirror, &Arena),
    cfg: &GeneratorConfig,
) -> Option<Obstacle> {
    let (c3, a3) = pair.third(ahead, soi)?;
    Some(oriented(
        mirror.point(c3, arena),
        mirror.direction(a3),
        pair.boxes[0].2,
        pair.w,
        cfg.height_m,
    ))
}

pub(super) fn lerp(r: Range, t: f64) -> f64 {
    r.min + (r.max - r.min) * t
}

/// The family's unit draws (uniform, then mapped through the proposal `dist`); the others stay 0.
pub(super) fn unit_draws(rng: &mut impl Rng, family: Family, dist: &Proposal) -> [f64; DIMS] {
    let taken = match family {
        Family::Paper | Family::Gate => PAPER_DIMS,
        Family::Extended => DIMS,
    };
    let mut u = [0.0; DIMS];
    for x in u.iter_mut().take(taken) {
        *x = rng.random::<f64>();
    }
    for (d, x) in u.iter_mut().enumerate().take(taken) {
        *x = dist.map(d, *x);
    }
    u
}

/// The split: the paper's fixed one (recorded in `u[SPLIT]` where it sits in the extended range, for the
/// reports), or the extended family's draw.
fn split_of(cfg: &GeneratorConfig, family: Family, u: &mut [f64; DIMS]) -> f64 {
    match family {
        Family::Paper | Family::Gate => {
            let r = cfg.adapted_split;
            u[SPLIT] = if r.max > r.min {
                ((cfg.split - r.min) / (r.max - r.min)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            cfg.split
        }
        Family::Extended => lerp(cfg.adapted_split, u[SPLIT]),
    }
}

/// Where obstacle 1's diagonal crosses the canonical SoI `s0 -> s1` for unit draw `u1`; `None` when the
/// diagonal does not fit.
fn soi_crossing(kind: SoiKind, (s0, s1): (P2, P2), diagonal: f64, u1: f64, arena: &Arena) -> Option<P2> {
    match kind {
        // The paper: draw y so the diagonal fits between the bottom and top borders, x from the SoI's line.
        SoiKind::Crossing => {
            let (lo, hi) = (arena.y.min + diagonal / 2.0, arena.y.max - diagonal / 2.0);
            if lo > hi {
                return None;
            }
            let y = lo + (hi - lo) * u1;
            Some(s0 + (s1 - s0) * ((y - s0.y) / (s1.y - s0.y)))
        }
        SoiKind::LongestInside => {
            let len = (s1 - s0).norm();
            if len < diagonal {
                return None;
            }
            let d = (s1 - s0).normalize();
            Some(s0 + d * (diagonal / 2.0 + (len - diagonal) * u1))
        }
    }
}

/// Obstacles 1 and 2 in the canonical frame: the unit direction of flight `d` and its left, the drawn angle
/// (radians) and split, the SoI crossing, each box's centre, long axis and length, and the common width (metres).
struct Pair {
    d: V2,
    left: V2,
    angle: f64,
    split: f64,
    crossing: P2,
    boxes: [(P2, V2, f64); 2],
    w: f64,
}

impl Pair {
    /// Obstacle 1 mirrored across the SoI, its near face `ahead` metres beyond the pair's farthest point: its
    /// centre and long axis, or `None` when it would not cross the SoI `s0 -> s1` (the drone would never meet it).
    fn third(&self, ahead: f64, (s0, s1): (P2, P2)) -> Option<(P2, V2)> {
        let (d, w, split) = (self.d, self.w, self.split);
        let [(c1, a, length), (c2, a2, length2)] = self.boxes;
        let a3 = d * self.angle.cos() - self.left * self.angle.sin();
        let reach = extent(c1, a, length, w, d).1.max(extent(c2, a2, length2, w, d).1) - self.crossing.coords.dot(&d);
        let offset = -a3 * ((0.5 - split) * length);
        let back = extent(P2::from(offset), a3, length, w, d).0;
        let t = reach + ahead - back;
        if (self.crossing - s0).dot(&d) + t > (s1 - s0).norm() {
            return None;
        }
        Some((self.crossing + d * t + offset, a3))
    }
}

/// The smallest and largest projection on `d` of the rectangle centred at `c` with its `long` side along unit
/// `axis` and its `short` side across it.
fn extent(c: P2, axis: V2, long: f64, short: f64, d: V2) -> (f64, f64) {
    let half = (axis.dot(&d) * long / 2.0).abs() + (V2::new(-axis.y, axis.x).dot(&d) * short / 2.0).abs();
    let mid = c.coords.dot(&d);
    (mid - half, mid + half)
}

/// A box whose long side (`long`) lies along `axis`, written with `r` in [0, 90] degrees as the rules want:
/// a rectangle turned by more than 90 degrees is the same rectangle with `l` and `w` swapped.
pub(super) fn oriented(center: P2, axis: V2, long: f64, short: f64, height: f64) -> Obstacle {
    let mut psi = axis.y.atan2(axis.x).to_degrees().rem_euclid(180.0);
    if psi >= 180.0 {
        psi = 0.0;
    }
    if psi <= 90.0 {
        Obstacle::new(long, short, height, center.x, center.y, psi)
    } else {
        Obstacle::new(short, long, height, center.x, center.y, psi - 90.0)
    }
}
