//! The HIL messages as PX4's `simulator_mavlink` reads and writes them: sensors, GPS and ground truth out,
//! motor commands and stream requests in. Pure conversions, no I/O.

use mavlink::dialects::common::{
    COMMAND_LONG_DATA, HEARTBEAT_DATA, HIL_ACTUATOR_CONTROLS_DATA, HIL_GPS_DATA, HIL_SENSOR_DATA,
    HIL_STATE_QUATERNION_DATA, HilActuatorControlsFlags, HilSensorUpdatedFlags, MavAutopilot, MavCmd, MavMessage,
    MavModeFlag, MavState, MavType,
};
use mavlink::{MavHeader, Message};

use crate::sensors::SensorFrame;
use crate::sensors::baro::BaroSample;
use crate::sensors::gps::GpsFix;
use crate::sim::GroundTruth;

/// The header of everything the simulator sends: system 1, component 200, as Gazebo's plugin.
pub fn header(sequence: u8) -> MavHeader {
    MavHeader {
        system_id: 1,
        component_id: 200,
        sequence,
    }
}

/// Message id of HIL_STATE_QUATERNION (what PX4 asks an interval for).
pub const HIL_STATE_QUATERNION_ID: u32 = 115;

/// What a message from PX4 means to the simulator.
#[derive(Debug, Clone, PartialEq)]
pub enum Incoming {
    /// A motor command (HIL_ACTUATOR_CONTROLS).
    Actuators {
        /// PX4's clock when it sent them, microseconds.
        time_usec: u64,
        /// Outputs, 0..1 for motors (zero while disarmed).
        controls: [f32; 16],
        /// MAV_MODE_FLAG_SAFETY_ARMED was set.
        armed: bool,
        /// PX4 runs in lockstep (flags bit 0).
        lockstep: bool,
    },
    /// SET_MESSAGE_INTERVAL for a message: the interval in microseconds (0 or negative: stop).
    MessageInterval {
        /// The message id.
        message_id: u32,
        /// Interval, microseconds.
        interval_us: i64,
    },
    /// A HEARTBEAT from PX4 (an autopilot, not another simulator).
    Heartbeat,
    /// Anything else.
    Other,
}

/// Reads a message from PX4.
pub fn classify(msg: &MavMessage) -> Incoming {
    match msg {
        MavMessage::HIL_ACTUATOR_CONTROLS(a) => Incoming::Actuators {
            time_usec: a.time_usec,
            controls: a.controls,
            armed: a.mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
            lockstep: a
                .flags
                .contains(HilActuatorControlsFlags::HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP),
        },
        MavMessage::COMMAND_LONG(c) if c.command == MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => Incoming::MessageInterval {
            message_id: c.param1 as u32,
            interval_us: c.param2 as i64,
        },
        MavMessage::HEARTBEAT(h) if h.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID => Incoming::Heartbeat,
        _ => Incoming::Other,
    }
}

/// The last magnetometer and barometer values, repeated in the steps that have no new reading (their
/// `fields_updated` bits are then clear and PX4 ignores them).
#[derive(Debug, Clone, Copy, Default)]
pub struct LastReadings {
    mag: [f32; 3],
    baro: Option<BaroSample>,
}

/// HIL_SENSOR for one step, `time_usec` on PX4's clock: accel and gyro always, the mag bits when the
/// magnetometer read, the baro bits (pressure, pressure altitude, temperature) when the barometer did.
pub fn hil_sensor(frame: &SensorFrame, time_usec: u64, last: &mut LastReadings) -> MavMessage {
    let mut fields = HilSensorUpdatedFlags::from_bits_truncate(0b11_1111);
    if let Some(m) = frame.mag_frd_gauss {
        last.mag = [m.x as f32, m.y as f32, m.z as f32];
        fields |= HilSensorUpdatedFlags::from_bits_truncate(0b1_1100_0000);
    }
    if let Some(b) = frame.baro {
        last.baro = Some(b);
        fields |= HilSensorUpdatedFlags::from_bits_truncate(0b1_1010_0000_0000);
    }
    let (a, g) = (frame.imu.accel_frd_m_s2, frame.imu.gyro_frd_rad_s);
    let baro = last.baro.unwrap_or(BaroSample {
        abs_pressure_hpa: 0.0,
        pressure_alt_m: 0.0,
        temperature_c: 0.0,
    });
    MavMessage::HIL_SENSOR(HIL_SENSOR_DATA {
        time_usec,
        xacc: a.x as f32,
        yacc: a.y as f32,
        zacc: a.z as f32,
        xgyro: g.x as f32,
        ygyro: g.y as f32,
        zgyro: g.z as f32,
        xmag: last.mag[0],
        ymag: last.mag[1],
        zmag: last.mag[2],
        abs_pressure: baro.abs_pressure_hpa as f32,
        diff_pressure: 0.0,
        pressure_alt: baro.pressure_alt_m as f32,
        temperature: baro.temperature_c as f32,
        fields_updated: fields,
        id: 0,
    })
}

/// HIL_GPS for a fix, `time_usec` the GPS's UTC time (microseconds since the Unix epoch).
pub fn hil_gps(fix: &GpsFix, time_usec: u64) -> MavMessage {
    let v = fix.velocity_ned_m_s;
    let ground = v.x.hypot(v.y);
    let cog_deg = v.y.atan2(v.x).to_degrees().rem_euclid(360.0);
    let cm = |x: f64| (x * 100.0).round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16;
    MavMessage::HIL_GPS(HIL_GPS_DATA {
        time_usec,
        lat: (fix.position.lat_deg * 1e7).round() as i32,
        lon: (fix.position.lon_deg * 1e7).round() as i32,
        alt: (fix.position.alt_m * 1e3).round() as i32,
        eph: (fix.eph_m * 100.0).round() as u16,
        epv: (fix.epv_m * 100.0).round() as u16,
        vel: (ground * 100.0).round().min(65534.0) as u16,
        vn: cm(v.x),
        ve: cm(v.y),
        vd: cm(v.z),
        cog: ((cog_deg * 100.0).round() as u16) % 36000,
        fix_type: 3,
        satellites_visible: fix.satellites,
        id: 0,
        yaw: 0,
    })
}

/// HIL_STATE_QUATERNION (PX4 SITL's ground-truth topics) for the true state.
pub fn hil_state_quaternion(t: &GroundTruth, time_usec: u64) -> MavMessage {
    let q = t.attitude.quaternion();
    let v = t.velocity_ned_m_s;
    let cm = |x: f64| (x * 100.0).round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16;
    let mg = |x: f64| {
        (x / 9.80665 * 1000.0)
            .round()
            .clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
    };
    let a = t.attitude * t.specific_force_frd_m_s2;
    let speed = (v.norm() * 100.0).round().min(65534.0) as u16;
    MavMessage::HIL_STATE_QUATERNION(HIL_STATE_QUATERNION_DATA {
        time_usec,
        attitude_quaternion: [q.w as f32, q.i as f32, q.j as f32, q.k as f32],
        rollspeed: t.rates_frd_rad_s.x as f32,
        pitchspeed: t.rates_frd_rad_s.y as f32,
        yawspeed: t.rates_frd_rad_s.z as f32,
        lat: (t.position.lat_deg * 1e7).round() as i32,
        lon: (t.position.lon_deg * 1e7).round() as i32,
        alt: (t.position.alt_m * 1e3).round() as i32,
        vx: cm(v.x),
        vy: cm(v.y),
        vz: cm(v.z),
        ind_airspeed: speed,
        true_airspeed: speed,
        xacc: mg(a.x),
        yacc: mg(a.y),
        zacc: mg(a.z),
    })
}

/// The simulator's HEARTBEAT (a generic vehicle with no autopilot: Gazebo's, which PX4 on USB needs
/// before it enables MAVLink).
pub fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GENERIC,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// Whether a message id is part of the HIL exchange (kept between the simulator and the autopilot, not
/// forwarded to a ground station).
pub fn is_hil(message_id: u32) -> bool {
    // HIL_CONTROLS 91, HIL_RC_INPUTS_RAW 92, HIL_ACTUATOR_CONTROLS 93, HIL_SENSOR 107, HIL_GPS 113,
    // HIL_OPTICAL_FLOW 114, HIL_STATE_QUATERNION 115.
    matches!(message_id, 91..=93 | 107 | 113..=115)
}

/// A SET_MESSAGE_INTERVAL command (what PX4 sends; used by tests standing in for PX4).
pub fn set_message_interval(message_id: u32, interval_us: f32) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: message_id as f32,
        param2: interval_us,
        command: MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        ..COMMAND_LONG_DATA::DEFAULT
    })
}

/// A HIL_ACTUATOR_CONTROLS as PX4 sends it (used by tests standing in for PX4).
pub fn actuator_controls(time_usec: u64, motors: &[f32], armed: bool) -> MavMessage {
    let mut controls = [0.0; 16];
    for (c, m) in controls.iter_mut().zip(motors) {
        *c = *m;
    }
    let mut mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    if armed {
        mode |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
    }
    MavMessage::HIL_ACTUATOR_CONTROLS(HIL_ACTUATOR_CONTROLS_DATA {
        time_usec,
        flags: HilActuatorControlsFlags::HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP,
        controls,
        mode,
    })
}

/// The message's id (for logs and counters).
pub fn id_of(msg: &MavMessage) -> u32 {
    msg.message_id()
}

#[cfg(test)]
mod tests;
