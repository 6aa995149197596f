//! The HIL messages as PX4 decodes them.

use mavlink::dialects::common::MavMessage;
use nalgebra::Vector3;

use super::*;
use crate::sensors::SensorFrame;
use crate::sensors::gps::GpsFix;
use crate::sensors::imu::ImuSample;
use crate::time::SimTime;

fn frame(mag: bool, baro: bool) -> SensorFrame {
    SensorFrame {
        time: SimTime::from_millis(4),
        imu: ImuSample {
            accel_frd_m_s2: Vector3::new(0.1, -0.2, -9.8),
            gyro_frd_rad_s: Vector3::new(0.01, 0.02, -0.03),
        },
        mag_frd_gauss: mag.then(|| Vector3::new(0.21, 0.01, 0.43)),
        baro: baro.then_some(BaroSample {
            abs_pressure_hpa: 955.98,
            pressure_alt_m: 488.0,
            temperature_c: 11.8,
        }),
        gps: None,
    }
}

fn bits(m: &MavMessage) -> u32 {
    match m {
        MavMessage::HIL_SENSOR(s) => s.fields_updated.bits(),
        _ => panic!("not HIL_SENSOR"),
    }
}

#[test]
fn fields_updated_carries_each_group_only_when_it_read() {
    let mut last = LastReadings::default();
    assert_eq!(bits(&hil_sensor(&frame(false, false), 4000, &mut last)), 0b111111);
    assert_eq!(bits(&hil_sensor(&frame(true, false), 4000, &mut last)), 0b1_1111_1111);
    assert_eq!(
        bits(&hil_sensor(&frame(false, true), 4000, &mut last)),
        0b1_1010_0011_1111
    );
    // A step without a reading repeats the last values with the bits clear.
    match hil_sensor(&frame(false, false), 8000, &mut last) {
        MavMessage::HIL_SENSOR(s) => {
            assert_eq!((s.xmag, s.abs_pressure, s.id, s.time_usec), (0.21, 955.98, 0, 8000));
            assert_eq!((s.xacc, s.zgyro), (0.1, -0.03));
        }
        _ => unreachable!(),
    }
}

#[test]
fn hil_gps_is_in_px4s_units() {
    let fix = GpsFix {
        measured_at: SimTime::ZERO,
        position: geodesy::SIM_HOME,
        velocity_ned_m_s: Vector3::new(0.0, 2.0, -0.5),
        eph_m: 1.0,
        epv_m: 1.0,
        satellites: 10,
    };
    match hil_gps(&fix, 123) {
        MavMessage::HIL_GPS(g) => {
            assert_eq!((g.lat, g.lon, g.alt), (473_977_420, 85_455_940, 488_000));
            assert_eq!((g.eph, g.epv, g.vel, g.vn, g.ve, g.vd), (100, 100, 200, 0, 200, -50));
            assert_eq!(
                (g.cog, g.fix_type, g.satellites_visible, g.time_usec),
                (9000, 3, 10, 123)
            );
        }
        _ => unreachable!(),
    }
}

#[test]
fn px4s_messages_are_understood_after_a_round_trip() {
    let mut buf = Vec::new();
    let sent = actuator_controls(4000, &[0.7, 0.7, 0.6, 0.6], true);
    mavlink::write_v2_msg(&mut buf, header(0), &sent).expect("write");
    let mut reader = mavlink::MavlinkReader::new(&buf[..]);
    let (_, got) = reader.read_any_message::<MavMessage>().expect("read");
    match classify(&got) {
        Incoming::Actuators {
            time_usec,
            controls,
            armed,
            lockstep,
        } => {
            assert_eq!((time_usec, armed, lockstep), (4000, true, true));
            assert_eq!(&controls[..4], &[0.7, 0.7, 0.6, 0.6]);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        classify(&set_message_interval(115, 5000.0)),
        Incoming::MessageInterval {
            message_id: 115,
            interval_us: 5000
        }
    );
    assert_eq!(
        classify(&heartbeat()),
        Incoming::Other,
        "a simulator's own heartbeat is no autopilot's"
    );
    assert!(is_hil(93) && is_hil(107) && !is_hil(0) && !is_hil(33));
}
