//! The EKF origin stays where the vehicle booted; a second flight starts where the first landed; the origin,
//! home and global positions agree with the local ones.

use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavMessage, MavMissionType};

use crate::scenarios::{GCS, case_study_params, command, fly_until_disarmed, mission2, upload};
use crate::telemetry::ids;
use crate::vehicle::{Vehicle, VehicleConfig};
use geodesy::{GeoPoint, LocalProjection};

const DT: Duration = Duration::from_millis(4);
const BOOT: GeoPoint = GeoPoint {
    lat_deg: 47.3980,
    lon_deg: 8.5460,
    alt_m: 500.0,
};

fn run(v: &mut Vehicle, secs: u64, out: &mut Vec<MavMessage>) {
    let end = v.now() + Duration::from_secs(secs);
    while v.now() < end {
        v.step(DT);
        out.extend(v.drain_outbox());
    }
}

fn origins(msgs: &[MavMessage]) -> Vec<(i32, i32, i32)> {
    msgs.iter()
        .filter_map(|m| match m {
            MavMessage::GPS_GLOBAL_ORIGIN(o) => Some((o.latitude, o.longitude, o.altitude)),
            _ => None,
        })
        .collect()
}

#[test]
fn origin_is_sent_once_per_boot_and_on_request() {
    let mut v = Vehicle::new(VehicleConfig {
        home: BOOT,
        ..Default::default()
    });
    let mut out = Vec::new();
    run(&mut v, 5, &mut out);
    assert_eq!(
        origins(&out),
        vec![(473_980_000, 85_460_000, 500_000)],
        "once, not every second"
    );
    out.clear();
    v.handle(
        &GCS,
        &command(
            MavCmd::MAV_CMD_REQUEST_MESSAGE,
            [ids::GPS_GLOBAL_ORIGIN as f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
    );
    run(&mut v, 3, &mut out);
    assert_eq!(origins(&out).len(), 1, "on request");
    out.clear();
    v.reboot();
    run(&mut v, 2, &mut out);
    assert_eq!(origins(&out).len(), 1, "again after a reboot");
}

#[test]
fn a_second_flight_starts_where_the_first_landed_with_the_boot_origin() {
    let mut v = Vehicle::new(VehicleConfig {
        home: BOOT,
        params: case_study_params(),
        ..Default::default()
    });
    let proj = LocalProjection::new(BOOT);
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    fly_until_disarmed(&mut v, DT, Duration::from_secs(200), |_, _| {}).expect("first flight");
    let landed = v.state().pos_ned;
    assert!(
        landed.xy().norm() > 5.0,
        "mission 2 ends away from where it started: {landed:?}"
    );
    let mut out = Vec::new();
    run(&mut v, 3, &mut out);
    assert_eq!(v.state().pos_ned, landed, "no jump back between flights");
    let mut msgs = Vec::new();
    fly_until_disarmed(&mut v, DT, Duration::from_secs(200), |_, m| msgs.push(m)).expect("second flight");
    let first_local = msgs.iter().find_map(|m| match m {
        MavMessage::LOCAL_POSITION_NED(p) => Some((p.x, p.y)),
        _ => None,
    });
    let (x, y) = first_local.expect("positions");
    assert!((f64::from(x) - landed.x).abs() < 0.05 && (f64::from(y) - landed.y).abs() < 0.05);
    // Home is where the second flight armed; the EKF origin stays at boot.
    let home = msgs.iter().find_map(|m| match m {
        MavMessage::HOME_POSITION(h) => Some(h.clone()),
        _ => None,
    });
    let home = home.expect("HOME_POSITION on arming");
    let (hn, he) = proj.project(f64::from(home.latitude) / 1e7, f64::from(home.longitude) / 1e7);
    assert!(
        (hn - landed.x).abs() < 0.05 && (he - landed.y).abs() < 0.05,
        "home {hn} {he}"
    );
    v.handle(
        &GCS,
        &command(
            MavCmd::MAV_CMD_REQUEST_MESSAGE,
            [ids::GPS_GLOBAL_ORIGIN as f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
    );
    let mut out = Vec::new();
    run(&mut v, 1, &mut out);
    assert_eq!(origins(&out), vec![(473_980_000, 85_460_000, 500_000)]);
    // GLOBAL_POSITION_INT is the local position projected about the origin (within the 1e-7 degree grid).
    let mut checked = 0;
    let mut last_local = None;
    for m in &msgs {
        match m {
            MavMessage::LOCAL_POSITION_NED(p) => last_local = Some((p.time_boot_ms, p.x, p.y)),
            MavMessage::GLOBAL_POSITION_INT(g) => {
                if let Some((t, x, y)) = last_local
                    && t == g.time_boot_ms
                {
                    let (n, e) = proj.project(f64::from(g.lat) / 1e7, f64::from(g.lon) / 1e7);
                    assert!((n - f64::from(x)).abs() < 0.02 && (e - f64::from(y)).abs() < 0.02);
                    checked += 1;
                }
            }
            _ => {}
        }
    }
    assert!(checked > 100, "{checked} pairs");
}
