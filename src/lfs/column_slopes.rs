//! The slopes (rise per horizontal metre) at which the rays of one camera column meet the ground or a box,
//! within the sensor's range: the fast renderer casts only the pixels whose slopes fall near these
//! intervals' ends, and fills the others from them.

use nalgebra::Vector3;

use super::render::SceneBox;

/// Slopes (rise per horizontal metre) of rays that meet the ground at horizontal distance in
/// `[rho_lo, rho_hi]` and within `range` of the camera at height `cz`.
pub(super) fn ground_slopes(cz: f64, rho_lo: f64, rho_hi: f64, range: f64) -> Option<(f64, f64)> {
    if cz >= range {
        return None;
    }
    let far = rho_hi.min((range * range - cz * cz).sqrt());
    (far >= rho_lo).then(|| (-cz / rho_lo, -cz / far))
}

/// Where the horizontal ray from `cam` along `(ux, uy)` is inside box `b`'s footprint, as horizontal
/// distances `(enter, leave)` (a 2-D slab test in the footprint's frame; `enter` may be negative).
fn footprint_crossing(b: &SceneBox, cam: &Vector3<f64>, ux: f64, uy: f64) -> Option<(f64, f64)> {
    let (ou, ov) = b.to_local(cam.x, cam.y);
    let [c, s] = b.axis_l;
    let (du, dv) = (ux * c + uy * s, -ux * s + uy * c);
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for (o, d, half) in [(ou, du, b.half_l), (ov, dv, b.half_w)] {
        if d.abs() < 1e-12 {
            if o.abs() > half {
                return None;
            }
        } else {
            let (a, e) = ((-half - o) / d, (half - o) / d);
            t0 = t0.max(a.min(e));
            t1 = t1.min(a.max(e));
        }
    }
    Some((t0, t1))
}

/// Slopes of rays in the column plane (horizontal unit direction `(ux, uy)` from the camera) that meet box
/// `b` at horizontal distance in `[rho_lo, rho_hi]` and within `range`: the slope interval of the convex set
/// (box section rectangle) intersected with the range disc, from its corners and edge-circle crossings.
#[allow(clippy::too_many_arguments)]
pub(super) fn box_slopes(
    b: &SceneBox,
    cam: &Vector3<f64>,
    ux: f64,
    uy: f64,
    cz: f64,
    rho_lo: f64,
    rho_hi: f64,
    range: f64,
) -> Option<(f64, f64)> {
    let (t0, t1) = footprint_crossing(b, cam, ux, uy)?;
    let a = t0.max(rho_lo).max(1e-9);
    let bb = t1.min(rho_hi).min(range);
    if a > bb {
        return None;
    }
    let (z0, z1) = (b.base - cz, b.top - cz);
    let r2 = range * range;
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    // `on_circle` points are on the range circle by construction (no rounding-sensitive test).
    let mut see = |rho: f64, dz: f64, on_circle: bool| {
        if on_circle || rho * rho + dz * dz <= r2 {
            let sl = dz / rho;
            lo = lo.min(sl);
            hi = hi.max(sl);
        }
    };
    for rho in [a, bb] {
        see(rho, z0, false);
        see(rho, z1, false);
        // Vertical edge meets the circle.
        let q = r2 - rho * rho;
        if q >= 0.0 {
            let dz = q.sqrt();
            for z in [dz, -dz] {
                if z >= z0 && z <= z1 {
                    see(rho, z, true);
                }
            }
        }
    }
    for dz in [z0, z1] {
        // Horizontal edge meets the circle.
        let q = r2 - dz * dz;
        if q >= 0.0 {
            let rho = q.sqrt();
            if rho >= a && rho <= bb {
                see(rho, dz, true);
            }
        }
    }
    (lo <= hi).then_some((lo, hi))
}
