//! Which mission, fence and rally items PX4 accepts, and the checksum it reports as `opaque_id`.
//!
//! PX4 rejects local frames (`MAV_MISSION_UNSUPPORTED_FRAME`), unknown commands
//! (`MAV_MISSION_UNSUPPORTED`) and fence/rally commands inside a mission (`MAV_MISSION_ERROR`).

#[expect(deprecated, reason = "PX4 still speaks MISSION_REQUEST and MISSION_ITEM")]
use mavlink::dialects::common::{
    MISSION_ITEM_DATA, MISSION_ITEM_INT_DATA, MavCmd, MavFrame, MavMissionResult, MavMissionType,
};

/// True for the global frames PX4 accepts for positional items.
#[expect(deprecated, reason = "PX4 accepts MAV_FRAME_GLOBAL_RELATIVE_ALT_INT")]
pub fn is_global_frame(frame: MavFrame) -> bool {
    matches!(
        frame,
        MavFrame::MAV_FRAME_GLOBAL
            | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT
            | MavFrame::MAV_FRAME_GLOBAL_INT
            | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    )
}

/// True when `z` of an item in `frame` is relative to home rather than AMSL.
#[expect(deprecated, reason = "PX4 accepts MAV_FRAME_GLOBAL_RELATIVE_ALT_INT")]
pub fn is_relative_alt(frame: MavFrame) -> bool {
    matches!(
        frame,
        MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    )
}

/// Commands whose x/y/z are a position.
pub fn is_positional(cmd: MavCmd) -> bool {
    use MavCmd::*;
    matches!(
        cmd,
        MAV_CMD_NAV_WAYPOINT
            | MAV_CMD_NAV_LOITER_UNLIM
            | MAV_CMD_NAV_LOITER_TURNS
            | MAV_CMD_NAV_LOITER_TIME
            | MAV_CMD_NAV_LAND
            | MAV_CMD_NAV_TAKEOFF
            | MAV_CMD_NAV_LOITER_TO_ALT
            | MAV_CMD_NAV_VTOL_TAKEOFF
            | MAV_CMD_NAV_VTOL_LAND
            | MAV_CMD_DO_SET_ROI_LOCATION
            | MAV_CMD_NAV_FENCE_RETURN_POINT
            | MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
            | MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
            | MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
            | MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
            | MAV_CMD_NAV_RALLY_POINT
    )
}

/// Non-positional mission commands PX4's mission parser knows.
#[expect(
    deprecated,
    reason = "PX4's mission parser still knows MAV_CMD_DO_SET_ROI and the like"
)]
fn is_mission_other(cmd: MavCmd) -> bool {
    use MavCmd::*;
    matches!(
        cmd,
        MAV_CMD_NAV_RETURN_TO_LAUNCH
            | MAV_CMD_NAV_DELAY
            | MAV_CMD_CONDITION_DELAY
            | MAV_CMD_DO_JUMP
            | MAV_CMD_DO_CHANGE_SPEED
            | MAV_CMD_DO_SET_HOME
            | MAV_CMD_DO_SET_SERVO
            | MAV_CMD_DO_SET_ACTUATOR
            | MAV_CMD_DO_LAND_START
            | MAV_CMD_DO_SET_ROI
            | MAV_CMD_DO_SET_ROI_NONE
            | MAV_CMD_DO_DIGICAM_CONTROL
            | MAV_CMD_DO_DIGICAM_CONFIGURE
            | MAV_CMD_DO_MOUNT_CONTROL
            | MAV_CMD_DO_MOUNT_CONFIGURE
            | MAV_CMD_IMAGE_START_CAPTURE
            | MAV_CMD_IMAGE_STOP_CAPTURE
            | MAV_CMD_VIDEO_START_CAPTURE
            | MAV_CMD_VIDEO_STOP_CAPTURE
            | MAV_CMD_SET_CAMERA_MODE
            | MAV_CMD_SET_CAMERA_ZOOM
            | MAV_CMD_SET_CAMERA_FOCUS
            | MAV_CMD_DO_SET_CAM_TRIGG_DIST
            | MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL
            | MAV_CMD_DO_VTOL_TRANSITION
            | MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW
            | MAV_CMD_DO_WINCH
            | MAV_CMD_DO_GRIPPER
    )
}

fn is_fence_cmd(cmd: MavCmd) -> bool {
    use MavCmd::*;
    matches!(
        cmd,
        MAV_CMD_NAV_FENCE_RETURN_POINT
            | MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
            | MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
            | MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
            | MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
    )
}

/// Check one item of an upload of `ty` the way PX4's parser does.
pub fn validate_item(ty: MavMissionType, item: &MISSION_ITEM_INT_DATA) -> Result<(), MavMissionResult> {
    let cmd = item.command;
    let allowed = match ty {
        MavMissionType::MAV_MISSION_TYPE_MISSION => {
            if is_fence_cmd(cmd) || cmd == MavCmd::MAV_CMD_NAV_RALLY_POINT {
                return Err(MavMissionResult::MAV_MISSION_ERROR);
            }
            is_positional(cmd) || is_mission_other(cmd)
        }
        MavMissionType::MAV_MISSION_TYPE_FENCE => is_fence_cmd(cmd),
        MavMissionType::MAV_MISSION_TYPE_RALLY => cmd == MavCmd::MAV_CMD_NAV_RALLY_POINT,
        _ => return Err(MavMissionResult::MAV_MISSION_ERROR),
    };
    if !allowed {
        return Err(MavMissionResult::MAV_MISSION_UNSUPPORTED);
    }
    if is_positional(cmd) {
        if !is_global_frame(item.frame) {
            return Err(MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME);
        }
        if !(-900_000_000..=900_000_000).contains(&item.x) {
            return Err(MavMissionResult::MAV_MISSION_INVALID_PARAM5_X);
        }
        if !(-1_800_000_000..=1_800_000_000).contains(&item.y) {
            return Err(MavMissionResult::MAV_MISSION_INVALID_PARAM6_Y);
        }
        if !item.z.is_finite() && cmd != MavCmd::MAV_CMD_NAV_LAND {
            return Err(MavMissionResult::MAV_MISSION_INVALID_PARAM7);
        }
    } else if !(item.frame == MavFrame::MAV_FRAME_MISSION || is_global_frame(item.frame)) {
        return Err(MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME);
    }
    use MavCmd::*;
    match cmd {
        MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION | MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
            if !(item.param1 >= 3.0 && item.param1 <= 1000.0) =>
        {
            Err(MavMissionResult::MAV_MISSION_INVALID_PARAM1)
        }
        MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION | MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
            if !(item.param1 > 0.0 && item.param1.is_finite()) =>
        {
            Err(MavMissionResult::MAV_MISSION_INVALID_PARAM1)
        }
        MAV_CMD_NAV_WAYPOINT | MAV_CMD_NAV_LOITER_TIME if item.param1.is_nan() || item.param1 < 0.0 => {
            Err(MavMissionResult::MAV_MISSION_INVALID_PARAM1)
        }
        _ => Ok(()),
    }
}

/// A float `MISSION_ITEM` (deprecated) in the int form PX4 stores.
#[expect(deprecated, reason = "PX4 still speaks MISSION_REQUEST and MISSION_ITEM")]
pub fn from_float_item(m: &MISSION_ITEM_DATA) -> MISSION_ITEM_INT_DATA {
    let to_e7 = |deg: f32| -> i32 {
        let v = f64::from(deg) * 1e7;
        if v.is_finite() {
            v.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
        } else {
            i32::MAX
        }
    };
    let positional = is_positional(m.command);
    MISSION_ITEM_INT_DATA {
        param1: m.param1,
        param2: m.param2,
        param3: m.param3,
        param4: m.param4,
        x: if positional { to_e7(m.x) } else { m.x as i32 },
        y: if positional { to_e7(m.y) } else { m.y as i32 },
        z: m.z,
        seq: m.seq,
        command: m.command,
        target_system: m.target_system,
        target_component: m.target_component,
        frame: m.frame,
        current: m.current,
        autocontinue: m.autocontinue,
        mission_type: m.mission_type,
    }
}

/// The float form of a stored item (answer to the deprecated `MISSION_REQUEST`).
#[expect(deprecated, reason = "PX4 still speaks MISSION_REQUEST and MISSION_ITEM")]
pub fn to_float_item(m: &MISSION_ITEM_INT_DATA) -> MISSION_ITEM_DATA {
    let positional = is_positional(m.command);
    let conv = |v: i32| {
        if positional { v as f32 * 1e-7 } else { v as f32 }
    };
    MISSION_ITEM_DATA {
        param1: m.param1,
        param2: m.param2,
        param3: m.param3,
        param4: m.param4,
        x: conv(m.x),
        y: conv(m.y),
        z: m.z,
        seq: m.seq,
        command: m.command,
        target_system: m.target_system,
        target_component: m.target_component,
        frame: m.frame,
        current: m.current,
        autocontinue: m.autocontinue,
        mission_type: m.mission_type,
    }
}

/// CRC-32 (IEEE) over the items' content, reported as `opaque_id` like PX4 does.
pub fn plan_checksum(items: &[MISSION_ITEM_INT_DATA]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    let mut feed = |bytes: &[u8]| {
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                let mask = (crc & 1).wrapping_neg();
                crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
            }
        }
    };
    for it in items {
        feed(&(it.command as u32).to_le_bytes());
        feed(&(it.frame as u32).to_le_bytes());
        for p in [it.param1, it.param2, it.param3, it.param4, it.z] {
            feed(&p.to_bits().to_le_bytes());
        }
        feed(&it.x.to_le_bytes());
        feed(&it.y.to_le_bytes());
        feed(&[it.autocontinue]);
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(cmd: MavCmd, frame: MavFrame) -> MISSION_ITEM_INT_DATA {
        MISSION_ITEM_INT_DATA {
            command: cmd,
            frame,
            x: 473_977_420,
            y: 85_455_940,
            z: 10.0,
            ..Default::default()
        }
    }

    #[test]
    fn px4_item_rules() {
        let m = MavMissionType::MAV_MISSION_TYPE_MISSION;
        let rel = MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT;
        assert_eq!(validate_item(m, &item(MavCmd::MAV_CMD_NAV_WAYPOINT, rel)), Ok(()));
        assert_eq!(
            validate_item(m, &item(MavCmd::MAV_CMD_NAV_WAYPOINT, MavFrame::MAV_FRAME_LOCAL_NED)),
            Err(MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME)
        );
        assert_eq!(
            validate_item(m, &item(MavCmd::MAV_CMD_SET_CAMERA_MODE, MavFrame::MAV_FRAME_MISSION)),
            Ok(())
        );
        assert_eq!(
            validate_item(m, &item(MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, rel)),
            Err(MavMissionResult::MAV_MISSION_ERROR)
        );
        assert_eq!(
            validate_item(m, &item(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, rel)),
            Err(MavMissionResult::MAV_MISSION_UNSUPPORTED)
        );
        let mut far = item(MavCmd::MAV_CMD_NAV_WAYPOINT, rel);
        far.x = 950_000_000;
        assert_eq!(
            validate_item(m, &far),
            Err(MavMissionResult::MAV_MISSION_INVALID_PARAM5_X)
        );
        let f = MavMissionType::MAV_MISSION_TYPE_FENCE;
        let mut poly = item(MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION, rel);
        poly.param1 = 2.0;
        assert_eq!(
            validate_item(f, &poly),
            Err(MavMissionResult::MAV_MISSION_INVALID_PARAM1)
        );
        poly.param1 = 4.0;
        assert_eq!(validate_item(f, &poly), Ok(()));
    }

    #[test]
    fn float_roundtrip_and_checksum() {
        let it = item(MavCmd::MAV_CMD_NAV_WAYPOINT, MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT);
        let back = from_float_item(&to_float_item(&it));
        assert!((back.x - it.x).abs() <= 40 && (back.y - it.y).abs() <= 40);
        let a = plan_checksum(std::slice::from_ref(&it));
        let mut it2 = it.clone();
        it2.z = 11.0;
        assert_ne!(a, plan_checksum(&[it2]));
        assert_eq!(plan_checksum(&[]), 0);
    }
}
