//! The `gate` family, for `--mode collision-prevention`: two boxes across the segment of interest leaving a
//! gap around 2 x `CP_DIST`, so PX4's Collision Prevention must let the vehicle through a gap where each side
//! is about `CP_DIST` away, with the gap perhaps off the path (one box beside it, one across it).
//!
//! In the canonical frame (the SoI flown toward +y, `generator::placement`): the gate's line crosses the SoI
//! at a drawn share of its length, tilted from the perpendicular by a drawn angle; the gap's width and its
//! centre's offset from the path are drawn too. Five unit draws, as the paper's family, so the adaptive
//! campaign learns over them the same way: `u[0]` box length, `u[1]` where along the SoI, `u[2]` tilt,
//! `u[3]` gap, `u[4]` offset.

use rand::Rng;

use super::adaptive::Proposal;
use super::config::{Family, GeneratorConfig};
use super::placement::{Draw, Mirror, left_of, lerp, oriented, unit_draws};
use super::soi::Soi;
use crate::geometry::P2;
use crate::model::{Arena, Obstacle, Range};

/// Each box's length across the path, metres.
pub const BOX_LENGTH_M: Range = Range::new(4.0, 10.0);
/// Where the gate stands, as a share of the SoI from its start.
pub const ALONG: Range = Range::new(0.25, 0.75);
/// The gate's tilt from the perpendicular to the SoI, degrees.
pub const TILT_DEG: Range = Range::new(-25.0, 25.0);
/// The gap as a multiple of 2 x `CP_DIST`.
pub const GAP_SHARE: Range = Range::new(0.75, 1.25);
/// The gap centre's offset from the path, as a share of the gap (0.5: a box edge on the path).
pub const OFFSET_SHARE: Range = Range::new(-0.75, 0.75);

/// Draws one gate for `cp_dist_m`; `None` when it leaves the arena (the caller draws again).
pub fn draw_gate(
    rng: &mut impl Rng,
    soi: &Soi,
    (mirror, arena): (Mirror, &Arena),
    cfg: &GeneratorConfig,
    dist: &Proposal,
    cp_dist_m: f64,
) -> Option<(Draw, Vec<Obstacle>)> {
    let u = unit_draws(rng, Family::Gate, dist);
    let (s0, s1) = (mirror.point(soi.start, arena), mirror.point(soi.end, arena));
    let d = (s1 - s0).normalize();
    let left = left_of(d);
    let length = lerp(BOX_LENGTH_M, u[0]);
    let on_path = s0 + (s1 - s0) * lerp(ALONG, u[1]);
    let tilt = lerp(TILT_DEG, u[2]).to_radians();
    let gap = 2.0 * cp_dist_m * lerp(GAP_SHARE, u[3]);
    let offset = gap * lerp(OFFSET_SHARE, u[4]);
    // The gate's line through the gap's centre, `a` pointing left of the path.
    let a = left * tilt.cos() + d * tilt.sin();
    let centre = on_path + a * offset;
    let half = gap / 2.0 + length / 2.0;
    let boxes: Vec<P2> = vec![centre + a * half, centre - a * half];
    let inside = |c: &P2| {
        let p = mirror.point(*c, arena);
        arena.x.contains(p.x) && arena.y.contains(p.y)
    };
    if !boxes.iter().all(inside) {
        return None;
    }
    let axis = mirror.direction(a);
    let obstacles = boxes
        .iter()
        .map(|c| oriented(mirror.point(*c, arena), axis, length, cfg.width_m, cfg.height_m))
        .collect();
    let draw = Draw {
        diagonal_m: length.hypot(cfg.width_m),
        length_m: length,
        angle_deg: 90.0 - tilt.to_degrees(),
        gap_m: gap,
        overhang: offset / gap,
        split: 0.5,
        third_ahead_m: None,
        crossing: mirror.point(centre, arena),
        unit: u,
    };
    Some((draw, obstacles))
}

#[cfg(test)]
#[path = "gate_tests.rs"]
mod tests;
