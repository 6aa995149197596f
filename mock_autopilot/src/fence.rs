//! The geofence as PX4 stores it (a FENCE-type mission) and its breach check.
//!
//! PX4's rule: the vehicle must be inside at least one inclusion shape (when any exists) and
//! outside every exclusion shape. Shapes live in the local NED plane (x North, y East, metres).

use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd};

use geodesy::LocalProjection;

/// One fence shape in local NED metres.
#[derive(Debug, Clone, PartialEq)]
pub enum FenceShape {
    /// A polygon; vertices (north_m, east_m) in upload order.
    Polygon {
        /// True for inclusion (stay inside), false for exclusion (stay outside).
        inclusion: bool,
        /// Vertices (north_m, east_m).
        vertices: Vec<(f64, f64)>,
    },
    /// A circle.
    Circle {
        /// True for inclusion, false for exclusion.
        inclusion: bool,
        /// Centre (north_m, east_m).
        center: (f64, f64),
        /// Radius in metres.
        radius_m: f64,
    },
}

/// Which rule a position breaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Breach {
    /// Inside exclusion shape number `n` (index in the fence).
    InsideExclusion(usize),
    /// Outside every inclusion shape.
    OutsideInclusion,
}

/// A set of fence shapes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Fence {
    /// The shapes in upload order.
    pub shapes: Vec<FenceShape>,
}

fn polygon_kind(cmd: MavCmd) -> Option<bool> {
    match cmd {
        MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION => Some(true),
        MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION => Some(false),
        _ => None,
    }
}

/// Split items into polygon groups; Err names the first item that breaks the grouping.
fn groups(items: &[MISSION_ITEM_INT_DATA]) -> Result<Vec<(usize, usize)>, String> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < items.len() {
        let it = &items[i];
        let len = if polygon_kind(it.command).is_some() {
            let n = it.param1 as usize;
            if n < 3 || i + n > items.len() {
                return Err(format!("Fence polygon at item {i} has a bad vertex count"));
            }
            for (k, v) in items[i..i + n].iter().enumerate() {
                if v.command != it.command || v.param1 as usize != n {
                    return Err(format!("Fence polygon vertex {} is inconsistent", i + k));
                }
            }
            n
        } else {
            1
        };
        out.push((i, len));
        i += len;
    }
    Ok(out)
}

impl Fence {
    /// Check that fence items form whole polygons (PX4 refuses broken polygons).
    pub fn validate(items: &[MISSION_ITEM_INT_DATA]) -> Result<(), String> {
        groups(items).map(|_| ())
    }

    /// Build the fence from stored FENCE items, projecting about the local origin.
    pub fn from_items(items: &[MISSION_ITEM_INT_DATA], proj: &LocalProjection) -> Result<Fence, String> {
        let to_ned = |it: &MISSION_ITEM_INT_DATA| proj.project(f64::from(it.x) * 1e-7, f64::from(it.y) * 1e-7);
        let mut shapes = Vec::new();
        for (start, len) in groups(items)? {
            let first = &items[start];
            if let Some(inclusion) = polygon_kind(first.command) {
                let vertices = items[start..start + len].iter().map(to_ned).collect();
                shapes.push(FenceShape::Polygon { inclusion, vertices });
                continue;
            }
            let inclusion = match first.command {
                MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION => true,
                MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION => false,
                _ => continue, // return point
            };
            shapes.push(FenceShape::Circle {
                inclusion,
                center: to_ned(first),
                radius_m: f64::from(first.param1),
            });
        }
        Ok(Fence { shapes })
    }

    /// True when the fence has no shapes.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// The rule broken at (north_m, east_m), if any.
    pub fn check(&self, north_m: f64, east_m: f64) -> Option<Breach> {
        let p = (north_m, east_m);
        let mut any_inclusion = false;
        let mut inside_inclusion = false;
        for (i, s) in self.shapes.iter().enumerate() {
            let (inclusion, inside) = match s {
                FenceShape::Polygon { inclusion, vertices } => (*inclusion, point_in_polygon(p, vertices)),
                FenceShape::Circle {
                    inclusion,
                    center,
                    radius_m,
                } => (*inclusion, (p.0 - center.0).hypot(p.1 - center.1) <= *radius_m),
            };
            if inclusion {
                any_inclusion = true;
                inside_inclusion |= inside;
            } else if inside {
                return Some(Breach::InsideExclusion(i));
            }
        }
        (any_inclusion && !inside_inclusion).then_some(Breach::OutsideInclusion)
    }
}

/// Even-odd ray casting; points exactly on an edge may go either way.
pub fn point_in_polygon(p: (f64, f64), vertices: &[(f64, f64)]) -> bool {
    let mut inside = false;
    let n = vertices.len();
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + n - 1) % n]);
        if (a.1 > p.1) != (b.1 > p.1) {
            let x_cross = a.0 + (p.1 - a.1) * (b.0 - a.0) / (b.1 - a.1);
            if p.0 < x_cross {
                inside = !inside;
            }
        }
    }
    inside
}

#[cfg(test)]
mod tests {
    use super::*;
    use geodesy::SIM_HOME;
    use proptest::prelude::*;

    fn vertex(cmd: MavCmd, n: f32, proj: &LocalProjection, north: f64, east: f64) -> MISSION_ITEM_INT_DATA {
        let (lat, lon) = proj.unproject(north, east);
        MISSION_ITEM_INT_DATA {
            command: cmd,
            param1: n,
            x: (lat * 1e7).round() as i32,
            y: (lon * 1e7).round() as i32,
            ..Default::default()
        }
    }

    #[test]
    fn exclusion_square_and_inclusion_circle() {
        let proj = LocalProjection::new(SIM_HOME);
        let ex = MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION;
        let mut items: Vec<_> = [(10.0, 10.0), (10.0, 20.0), (20.0, 20.0), (20.0, 10.0)]
            .iter()
            .map(|&(n, e)| vertex(ex, 4.0, &proj, n, e))
            .collect();
        items.push(vertex(
            MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
            100.0,
            &proj,
            0.0,
            0.0,
        ));
        let fence = Fence::from_items(&items, &proj).expect("valid fence");
        assert_eq!(fence.shapes.len(), 2);
        assert_eq!(fence.check(0.0, 0.0), None);
        assert_eq!(fence.check(15.0, 15.0), Some(Breach::InsideExclusion(0)));
        assert_eq!(fence.check(150.0, 0.0), Some(Breach::OutsideInclusion));
    }

    #[test]
    fn broken_polygons_are_refused() {
        let proj = LocalProjection::new(SIM_HOME);
        let inc = MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION;
        let items: Vec<_> = (0..3).map(|k| vertex(inc, 4.0, &proj, k as f64, 0.0)).collect();
        assert!(Fence::validate(&items).is_err());
        let mut items: Vec<_> = (0..3).map(|k| vertex(inc, 3.0, &proj, k as f64, 1.0)).collect();
        items[2].param1 = 5.0;
        assert!(Fence::validate(&items).is_err());
    }

    proptest! {
        #[test]
        fn regular_polygon_contains_inner_disc(n in 3usize..12, r in 1.0f64..100.0,
                                               ang in 0.0f64..std::f64::consts::TAU, frac in 0.0f64..0.99) {
            let verts: Vec<(f64, f64)> = (0..n)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / n as f64;
                    (r * a.cos(), r * a.sin())
                })
                .collect();
            let inner = r * (std::f64::consts::PI / n as f64).cos() * frac;
            prop_assert!(point_in_polygon((inner * ang.cos(), inner * ang.sin()), &verts));
            prop_assert!(!point_in_polygon((1.01 * r * ang.cos(), 1.01 * r * ang.sin()), &verts));
        }
    }
}
