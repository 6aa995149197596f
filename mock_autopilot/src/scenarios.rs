//! Ready-made missions (the case studies' mission 2) and a scripted in-process upload, shared by
//! tests, benches and examples.

use std::time::Duration;

use mavlink::MavHeader;
use mavlink::dialects::common::{
    COMMAND_LONG_DATA, MISSION_COUNT_DATA, MISSION_ITEM_INT_DATA, MavCmd, MavFrame, MavMessage, MavMissionResult,
    MavMissionType,
};

use crate::vehicle::Vehicle;

/// Header of a ground station (sysid 255, compid 190).
pub const GCS: MavHeader = MavHeader {
    system_id: 255,
    component_id: 190,
    sequence: 0,
};

/// One global-relative-alt item.
pub fn item(seq: u16, command: MavCmd, lat_deg: f64, lon_deg: f64, rel_alt_m: f32) -> MISSION_ITEM_INT_DATA {
    MISSION_ITEM_INT_DATA {
        seq,
        command,
        frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
        x: (lat_deg * 1e7).round() as i32,
        y: (lon_deg * 1e7).round() as i32,
        z: rel_alt_m,
        target_system: 1,
        target_component: 1,
        autocontinue: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
        ..Default::default()
    }
}

/// Case-study mission 2 (QGC plan): SET_CAMERA_MODE, takeoff to 10 m at home, waypoint at
/// (-6.84 N, 53.97 E), land at (-12.36 N, 0.13 E).
pub fn mission2() -> Vec<MISSION_ITEM_INT_DATA> {
    let mut cam = item(0, MavCmd::MAV_CMD_SET_CAMERA_MODE, 0.0, 0.0, 0.0);
    cam.frame = MavFrame::MAV_FRAME_MISSION;
    cam.param2 = 2.0;
    vec![
        cam,
        item(1, MavCmd::MAV_CMD_NAV_TAKEOFF, 47.3977419, 8.545593799999999, 10.0),
        item(
            2,
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            47.39768051930175,
            8.546310969707491,
            10.0,
        ),
        item(3, MavCmd::MAV_CMD_NAV_LAND, 47.39763082431753, 8.545595709237233, 0.0),
    ]
}

/// The case-study parameter file (mission-params.csv) as overrides.
pub fn case_study_params() -> Vec<(String, crate::params::ParamValue)> {
    use crate::params::ParamValue::{Float, Int};
    [
        ("NAV_ACC_RAD", Float(0.5)),
        ("NAV_MC_ALT_RAD", Float(0.5)),
        ("NAV_RCL_ACT", Int(3)),
        ("NAV_DLL_ACT", Int(0)),
        ("MIS_YAW_ERR", Float(12.0)),
        ("MIS_TAKEOFF_ALT", Float(1.0)),
        ("MPC_YAW_MODE", Int(0)),
        ("SDLOG_PROFILE", Int(7)),
    ]
    .into_iter()
    .map(|(n, v)| (n.to_string(), v))
    .collect()
}

/// Upload `items` into `v` through the mission protocol, in process. Returns the final ACK code.
pub fn upload(v: &mut Vehicle, ty: MavMissionType, items: &[MISSION_ITEM_INT_DATA]) -> Option<MavMissionResult> {
    v.handle(
        &GCS,
        &MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
            count: items.len() as u16,
            target_system: 1,
            target_component: 1,
            mission_type: ty,
            opaque_id: 0,
        }),
    );
    let mut result = None;
    for _ in 0..=items.len() {
        let out: Vec<MavMessage> = v.drain_outbox().collect();
        for m in out {
            match m {
                MavMessage::MISSION_REQUEST_INT(r) => {
                    if let Some(it) = items.get(usize::from(r.seq)) {
                        let mut it = it.clone();
                        it.mission_type = ty;
                        v.handle(&GCS, &MavMessage::MISSION_ITEM_INT(it));
                    }
                }
                MavMessage::MISSION_ACK(a) => result = Some(a.mavtype),
                _ => {}
            }
        }
    }
    result
}

/// A COMMAND_LONG from the GCS.
pub fn command(cmd: MavCmd, p: [f32; 7]) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: p[0],
        param2: p[1],
        param3: p[2],
        param4: p[3],
        param5: p[4],
        param6: p[5],
        param7: p[6],
        command: cmd,
        target_system: 1,
        target_component: 1,
        confirmation: 0,
    })
}

/// Fly the uploaded mission (MISSION_START) until disarmed or `limit`; returns simulated time
/// to disarm. Messages are discarded unless `sink` keeps them.
pub fn fly_until_disarmed(
    v: &mut Vehicle,
    dt: Duration,
    limit: Duration,
    mut sink: impl FnMut(&Vehicle, MavMessage),
) -> Option<Duration> {
    let start = v.now();
    v.handle(&GCS, &command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]));
    let mut was_armed = false;
    while v.now() - start < limit {
        v.step(dt);
        let out: Vec<MavMessage> = v.drain_outbox().collect();
        for m in out {
            sink(v, m);
        }
        let s = v.state();
        was_armed |= s.armed;
        if was_armed && !s.armed {
            return Some(v.now() - start);
        }
    }
    None
}
