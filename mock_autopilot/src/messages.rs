//! Builders for the telemetry messages, filled the way PX4 fills them.

use mavlink::dialects::common::{
    ATTITUDE_DATA, AUTOPILOT_VERSION_DATA, EXTENDED_SYS_STATE_DATA, GLOBAL_POSITION_INT_DATA, GPS_GLOBAL_ORIGIN_DATA,
    GPS_RAW_INT_DATA, GpsFixType, HEARTBEAT_DATA, HOME_POSITION_DATA, LOCAL_POSITION_NED_DATA, MISSION_CURRENT_DATA,
    MavAutopilot, MavMessage, MavMissionType, MavProtocolCapability, MavSysStatusSensor, MavType, MavVtolState,
    MissionState, SYS_STATUS_DATA, VFR_HUD_DATA,
};

use crate::modes::FlightMode;
use crate::telemetry::ids;
use crate::vehicle::Vehicle;

/// PX4 v1.14.0 release, encoded as AUTOPILOT_VERSION.flight_sw_version (major, minor, patch, type).
pub const FLIGHT_SW_VERSION: u32 = (1 << 24) | (14 << 16) | 255;

impl Vehicle {
    /// The message with MAVLink id `id`, if the mock can produce it.
    pub(crate) fn build_message(&self, id: u32) -> Option<MavMessage> {
        Some(match id {
            ids::HEARTBEAT => self.heartbeat(),
            ids::SYS_STATUS => self.sys_status(),
            ids::ATTITUDE => self.attitude(),
            ids::LOCAL_POSITION_NED => self.local_position(),
            ids::GLOBAL_POSITION_INT => self.global_position(),
            ids::MISSION_CURRENT => self.mission_current(),
            ids::VFR_HUD => self.vfr_hud(),
            // No home before the estimator has a global position (PX4 sets it once GPS is valid).
            ids::HOME_POSITION if self.estimator_settled() => self.home_position(),
            ids::GPS_RAW_INT => self.gps_raw(),
            ids::EXTENDED_SYS_STATE => MavMessage::EXTENDED_SYS_STATE(EXTENDED_SYS_STATE_DATA {
                vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
                landed_state: self.landed_state(),
            }),
            ids::AUTOPILOT_VERSION => self.autopilot_version(),
            ids::GPS_GLOBAL_ORIGIN => self.gps_global_origin(),
            _ => return None,
        })
    }

    fn heartbeat(&self) -> MavMessage {
        let mode: FlightMode = self.nav.mode();
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: mode.custom_mode(),
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode: mode.base_mode(self.armed),
            system_status: self.system_status(),
            mavlink_version: 3,
        })
    }

    fn sys_status(&self) -> MavMessage {
        use MavSysStatusSensor as S;
        let sensors = S::MAV_SYS_STATUS_SENSOR_3D_GYRO
            | S::MAV_SYS_STATUS_SENSOR_3D_ACCEL
            | S::MAV_SYS_STATUS_SENSOR_3D_MAG
            | S::MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
            | S::MAV_SYS_STATUS_SENSOR_GPS
            | S::MAV_SYS_STATUS_AHRS
            | S::MAV_SYS_STATUS_SENSOR_BATTERY;
        // PX4 v1.14 (streams/SYS_STATUS.hpp): a component with an arming-check error is unhealthy, and the
        // pre-arm bit is only ever set in `health`, for the current navigation state.
        let mut health = sensors;
        if !self.estimator_settled() {
            health.remove(S::MAV_SYS_STATUS_AHRS | S::MAV_SYS_STATUS_SENSOR_GPS);
        }
        if self.prearm_ok() {
            health |= S::MAV_SYS_STATUS_PREARM_CHECK;
        }
        MavMessage::SYS_STATUS(SYS_STATUS_DATA {
            onboard_control_sensors_present: sensors,
            onboard_control_sensors_enabled: sensors,
            onboard_control_sensors_health: health,
            load: 200,
            voltage_battery: 16_200,
            current_battery: if self.armed { 1_000 } else { 0 },
            battery_remaining: 100,
            ..Default::default()
        })
    }

    fn attitude(&self) -> MavMessage {
        let (roll, pitch) = self.body.roll_pitch_rad();
        MavMessage::ATTITUDE(ATTITUDE_DATA {
            time_boot_ms: self.time_boot_ms(),
            roll: roll as f32,
            pitch: pitch as f32,
            yaw: self.body.yaw_rad as f32,
            rollspeed: 0.0,
            pitchspeed: 0.0,
            yawspeed: self.body.yaw_rate_rad_s as f32,
        })
    }

    fn local_position(&self) -> MavMessage {
        let (p, v) = (self.body.pos_ned, self.body.vel_ned);
        MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
            time_boot_ms: self.time_boot_ms(),
            x: p.x as f32,
            y: p.y as f32,
            z: p.z as f32,
            vx: v.x as f32,
            vy: v.y as f32,
            vz: v.z as f32,
        })
    }

    fn global_position(&self) -> MavMessage {
        let (p, v) = (self.body.pos_ned, self.body.vel_ned);
        let (lat, lon) = self.proj.unproject(p.x, p.y);
        let alt_amsl = self.origin.alt_m - p.z;
        let home_alt = self.origin.alt_m - self.home_ned.z;
        let hdg = self.body.yaw_rad.to_degrees().rem_euclid(360.0);
        MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
            time_boot_ms: self.time_boot_ms(),
            lat: (lat * 1e7).round() as i32,
            lon: (lon * 1e7).round() as i32,
            alt: (alt_amsl * 1000.0).round() as i32,
            relative_alt: ((alt_amsl - home_alt) * 1000.0).round() as i32,
            vx: (v.x * 100.0).round() as i16,
            vy: (v.y * 100.0).round() as i16,
            vz: (v.z * 100.0).round() as i16,
            hdg: ((hdg * 100.0).round() as u16) % 36_000,
        })
    }

    /// The EKF origin: where the vehicle booted (PX4 v1.14 streams/GPS_GLOBAL_ORIGIN.hpp: ref_lat/ref_lon in
    /// degE7, ref_alt in mm, time_usec the origin's timestamp since boot).
    fn gps_global_origin(&self) -> MavMessage {
        MavMessage::GPS_GLOBAL_ORIGIN(GPS_GLOBAL_ORIGIN_DATA {
            latitude: (self.origin.lat_deg * 1e7).round() as i32,
            longitude: (self.origin.lon_deg * 1e7).round() as i32,
            altitude: (self.origin.alt_m * 1000.0).round() as i32,
            time_usec: 0,
        })
    }

    fn vfr_hud(&self) -> MavMessage {
        let v = self.body.vel_ned;
        MavMessage::VFR_HUD(VFR_HUD_DATA {
            airspeed: v.norm() as f32,
            groundspeed: v.xy().norm() as f32,
            alt: (self.origin.alt_m - self.body.pos_ned.z) as f32,
            climb: -v.z as f32,
            heading: self.body.yaw_rad.to_degrees().rem_euclid(360.0) as i16,
            throttle: if self.armed { 50 } else { 0 },
        })
    }

    /// GPS_RAW_INT: a 3D fix once the estimator has settled, none before (SIH's GPS, at the home position).
    fn gps_raw(&self) -> MavMessage {
        let (lat, lon) = self.proj.unproject(self.body.pos_ned.x, self.body.pos_ned.y);
        let fixed = self.estimator_settled();
        MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
            time_usec: u64::from(self.time_boot_ms()) * 1000,
            lat: (lat * 1e7).round() as i32,
            lon: (lon * 1e7).round() as i32,
            alt: ((self.origin.alt_m - self.body.pos_ned.z) * 1000.0).round() as i32,
            eph: if fixed { 70 } else { u16::MAX },
            epv: if fixed { 100 } else { u16::MAX },
            vel: (self.body.vel_ned.xy().norm() * 100.0).round() as u16,
            cog: u16::MAX,
            fix_type: if fixed {
                GpsFixType::GPS_FIX_TYPE_3D_FIX
            } else {
                GpsFixType::GPS_FIX_TYPE_NO_FIX
            },
            satellites_visible: if fixed { 16 } else { 0 },
            ..Default::default()
        })
    }

    pub(crate) fn home_position(&self) -> MavMessage {
        let h = self.home_ned;
        let (lat, lon) = self.proj.unproject(h.x, h.y);
        MavMessage::HOME_POSITION(HOME_POSITION_DATA {
            latitude: (lat * 1e7).round() as i32,
            longitude: (lon * 1e7).round() as i32,
            altitude: ((self.origin.alt_m - h.z) * 1000.0).round() as i32,
            x: h.x as f32,
            y: h.y as f32,
            z: h.z as f32,
            q: [1.0, 0.0, 0.0, 0.0],
            approach_x: 0.0,
            approach_y: 0.0,
            approach_z: 0.0,
            time_usec: u64::from(self.time_boot_ms()) * 1000,
        })
    }

    pub(crate) fn mission_current(&self) -> MavMessage {
        let total = self.nav.count() as u16;
        let in_mission = self.nav.mode() == FlightMode::Mission;
        let mission_state = if total == 0 {
            MissionState::MISSION_STATE_NO_MISSION
        } else if self.nav.mission_finished() {
            MissionState::MISSION_STATE_COMPLETE
        } else if in_mission && self.armed {
            MissionState::MISSION_STATE_ACTIVE
        } else if self.nav.current() > 0 {
            MissionState::MISSION_STATE_PAUSED
        } else {
            MissionState::MISSION_STATE_NOT_STARTED
        };
        MavMessage::MISSION_CURRENT(MISSION_CURRENT_DATA {
            seq: (self.nav.current().min(usize::from(total.saturating_sub(1)))) as u16,
            total,
            mission_state,
            mission_mode: u8::from(in_mission),
            mission_id: self.missions.plan(MavMissionType::MAV_MISSION_TYPE_MISSION).opaque_id,
            fence_id: self.missions.plan(MavMissionType::MAV_MISSION_TYPE_FENCE).opaque_id,
            rally_points_id: self.missions.plan(MavMissionType::MAV_MISSION_TYPE_RALLY).opaque_id,
        })
    }

    pub(crate) fn send_mission_current(&mut self) {
        let m = self.mission_current();
        self.outbox.push(m);
    }

    fn autopilot_version(&self) -> MavMessage {
        use MavProtocolCapability as C;
        MavMessage::AUTOPILOT_VERSION(AUTOPILOT_VERSION_DATA {
            capabilities: C::MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT
                | C::MAV_PROTOCOL_CAPABILITY_MISSION_INT
                | C::MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | C::MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
                | C::MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
                | C::MAV_PROTOCOL_CAPABILITY_MAVLINK2
                | C::MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
                | C::MAV_PROTOCOL_CAPABILITY_MISSION_RALLY,
            uid: 0x4D4F_434B_5058_3401,
            flight_sw_version: self.flight_sw_version,
            middleware_sw_version: self.flight_sw_version,
            os_sw_version: 0,
            board_version: 0,
            vendor_id: 0,
            product_id: 0,
            flight_custom_version: *b"mockpx4\0",
            middleware_custom_version: [0; 8],
            os_custom_version: [0; 8],
            uid2: [0; 18],
        })
    }
}

#[cfg(test)]
#[path = "origin_tests.rs"]
mod origin_tests;
