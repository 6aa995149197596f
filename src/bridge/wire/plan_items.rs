//! What the bridge uploads: the test's mission as MISSION_ITEM_INTs, the obstacles' footprints as geofence
//! exclusion polygons, and the comparison of an uploaded plan with the one read back.

use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd, MavFrame, MavMissionType};
use num_traits::FromPrimitive;

use crate::model::{LocalProjection, Mission, Obstacle};

/// The mission's items in order, in the frames the plan gives (PX4 accepts its global frames).
///
/// Positions go as degrees x 1e7 (the `_INT` encoding); `null` params go as NaN, as QGroundControl sends them.
pub fn mission_items(mission: &Mission) -> Result<Vec<MISSION_ITEM_INT_DATA>, String> {
    mission
        .items
        .iter()
        .enumerate()
        .map(|(seq, item)| {
            let command = MavCmd::from_u16(item.command)
                .ok_or_else(|| format!("mission item {seq}: command {} is not a MAV_CMD", item.command))?;
            let frame = MavFrame::from_u8(item.frame)
                .ok_or_else(|| format!("mission item {seq}: frame {} is not a MAV_FRAME", item.frame))?;
            let p = |i: usize| item.params[i].map_or(f32::NAN, |v| v as f32);
            let (x, y, z) = match item.global {
                Some(g) => (deg_e7(g.lat_deg), deg_e7(g.lon_deg), g.alt_m as f32),
                None => (
                    item.params[4].map_or(0, |v| v as i32),
                    item.params[5].map_or(0, |v| v as i32),
                    p(6),
                ),
            };
            Ok(MISSION_ITEM_INT_DATA {
                param1: p(0),
                param2: p(1),
                param3: p(2),
                param4: p(3),
                x,
                y,
                z,
                seq: seq as u16,
                command,
                target_system: 0,
                target_component: 0,
                frame,
                current: u8::from(seq == 0),
                autocontinue: u8::from(item.auto_continue),
                mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            })
        })
        .collect()
}

fn deg_e7(deg: f64) -> i32 {
    (deg * 1e7).round() as i32
}

/// Each obstacle's footprint as an exclusion polygon (4 vertices, `param1` = 4), corners unprojected about
/// `home` with PX4's projection, in MAV_FRAME_GLOBAL_INT (altitude unused by PX4's polygon check).
#[expect(deprecated, reason = "PX4 accepts MAV_FRAME_GLOBAL_RELATIVE_ALT_INT")]
pub fn fence_items(obstacles: &[Obstacle], home: &LocalProjection) -> Vec<MISSION_ITEM_INT_DATA> {
    let mut out = Vec::with_capacity(obstacles.len() * 4);
    for o in obstacles {
        for corner in o.footprint().corners() {
            let (lat, lon) = home.unproject(corner.x, corner.y);
            out.push(MISSION_ITEM_INT_DATA {
                param1: 4.0,
                param2: 0.0,
                param3: 0.0,
                param4: 0.0,
                x: deg_e7(lat),
                y: deg_e7(lon),
                z: 0.0,
                seq: out.len() as u16,
                command: MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
                target_system: 0,
                target_component: 0,
                frame: MavFrame::MAV_FRAME_GLOBAL_INT,
                current: 0,
                autocontinue: 1,
                mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
            });
        }
    }
    out
}

fn same_f32(a: f32, b: f32) -> bool {
    (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-4 * a.abs().max(1.0)
}

/// The first difference between an uploaded plan and the one read back, if any.
///
/// Frames are compared loosely (`GLOBAL_RELATIVE_ALT` and its `_INT` twin are the same frame to PX4) and
/// NaN equals NaN, since a vehicle may store either spelling.
#[expect(deprecated, reason = "PX4 accepts MAV_FRAME_GLOBAL_RELATIVE_ALT_INT")]
pub fn first_difference(sent: &[MISSION_ITEM_INT_DATA], got: &[MISSION_ITEM_INT_DATA]) -> Option<String> {
    if sent.len() != got.len() {
        return Some(format!("{} items uploaded, {} read back", sent.len(), got.len()));
    }
    let frame_class = |f: MavFrame| match f {
        MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT => MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
        MavFrame::MAV_FRAME_GLOBAL_INT => MavFrame::MAV_FRAME_GLOBAL,
        f => f,
    };
    for (a, b) in sent.iter().zip(got) {
        let what = if a.command != b.command {
            format!("command {:?} became {:?}", a.command, b.command)
        } else if frame_class(a.frame) != frame_class(b.frame) {
            format!("frame {:?} became {:?}", a.frame, b.frame)
        } else if (a.x - b.x).abs() > 1 || (a.y - b.y).abs() > 1 {
            format!("position ({}, {}) became ({}, {})", a.x, a.y, b.x, b.y)
        } else if !same_f32(a.z, b.z) {
            format!("altitude {} became {}", a.z, b.z)
        } else if let Some(k) = [
            (a.param1, b.param1),
            (a.param2, b.param2),
            (a.param3, b.param3),
            (a.param4, b.param4),
        ]
        .iter()
        .position(|(x, y)| !same_f32(*x, *y))
        {
            format!("param{} changed", k + 1)
        } else {
            continue;
        };
        return Some(format!("item {}: {what}", a.seq));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{GeoPoint, SIM_HOME};

    fn mission2() -> Mission {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.plan");
        Mission::load(&path, SIM_HOME).unwrap()
    }

    #[test]
    fn mission2_items() {
        let items = mission_items(&mission2()).unwrap();
        assert_eq!(items.len(), 4);
        assert_eq!(items[0].command, MavCmd::MAV_CMD_SET_CAMERA_MODE);
        assert!(items[0].param3.is_nan());
        assert_eq!(items[1].command, MavCmd::MAV_CMD_NAV_TAKEOFF);
        assert_eq!(items[1].x, 473_977_419);
        assert_eq!(items[1].z, 10.0);
        assert_eq!(items[3].command, MavCmd::MAV_CMD_NAV_LAND);
        assert_eq!(items.iter().map(|i| i.seq).collect::<Vec<_>>(), vec![0, 1, 2, 3]);
        assert_eq!(first_difference(&items, &items), None);
        let mut moved = items.clone();
        moved[2].x += 5;
        assert!(
            first_difference(&items, &moved)
                .unwrap()
                .starts_with("item 2: position")
        );
        assert!(
            first_difference(&items, &items[..3])
                .unwrap()
                .contains("4 items uploaded")
        );
    }

    #[test]
    fn fence_polygons_round_trip_through_the_projection() {
        let o = Obstacle::new(10.0, 4.0, 20.0, 12.0, -6.0, 30.0);
        let home = LocalProjection::new(GeoPoint {
            lat_deg: 47.0,
            lon_deg: 8.0,
            alt_m: 400.0,
        });
        let items = fence_items(&[o, o], &home);
        assert_eq!(items.len(), 8);
        assert!(items.iter().all(|i| i.param1 == 4.0));
        assert_eq!(items[7].seq, 7);
        for (item, corner) in items.iter().zip(o.footprint().corners()) {
            let (n, e) = home.project(f64::from(item.x) / 1e7, f64::from(item.y) / 1e7);
            // 1e-7 degree is about 1.1 cm.
            assert!(
                (n - corner.x).abs() < 0.02 && (e - corner.y).abs() < 0.02,
                "{n} {e} vs {corner}"
            );
        }
    }
}
