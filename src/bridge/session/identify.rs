//! Who answered: before anything is uploaded, `fly` names the vehicle it locked onto (system id, autopilot,
//! vehicle type and, when the vehicle says, its flight software version), so a wrong vehicle on a shared port
//! is seen before it flies.

use std::sync::Arc;
use std::time::Duration;

use mavlink::dialects::common::{COMMAND_LONG_DATA, HEARTBEAT_DATA, MavAutopilot, MavCmd, MavMessage};
use serde::Serialize;
use tokio::sync::broadcast;

use crate::bridge::px4_version::Px4Version;
use crate::bridge::wire::cancel::CancelToken;
use crate::bridge::wire::exchange::Target;
use crate::bridge::wire::link::{Inbound, Link, Sender};

/// How long the vehicle gets to say its version (vehicle time); without an answer the version is left out.
const VERSION_WAIT: Duration = Duration::from_millis(1500);

/// Who answered, as its heartbeat and AUTOPILOT_VERSION said; in `fly --json` as `vehicle`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct VehicleIdentity {
    /// MAVLink system id the bridge locked onto.
    pub system: u8,
    /// Its component id.
    pub component: u8,
    /// The autopilot, in words (`PX4`, `ArduPilot`, `generic`).
    pub autopilot: String,
    /// The vehicle type, in words (`quadrotor`).
    pub vehicle_type: String,
    /// Its flight software version (`1.14.0`), when it answered the request for it.
    pub flight_software: Option<String>,
}

impl std::fmt::Display for VehicleIdentity {
    /// E.g. `system 1, component 1: PX4 quadrotor, flight software 1.14.0`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "system {}, component {}: {} {}",
            self.system, self.component, self.autopilot, self.vehicle_type
        )?;
        match &self.flight_software {
            Some(v) => write!(f, ", flight software {v}"),
            None => Ok(()),
        }
    }
}

/// The vehicle `heartbeat` came from, with its AUTOPILOT_VERSION.flight_sw_version (from [`flight_sw_version`]).
pub fn identity(target: Target, heartbeat: &HEARTBEAT_DATA, flight_sw: Option<u32>) -> VehicleIdentity {
    VehicleIdentity {
        system: target.system,
        component: target.component,
        autopilot: words(&format!("{:?}", heartbeat.autopilot), "MAV_AUTOPILOT_"),
        vehicle_type: words(&format!("{:?}", heartbeat.mavtype), "MAV_TYPE_"),
        flight_software: flight_sw.map(software_version),
    }
}

/// The PX4 release a PX4 vehicle reports (None for another autopilot or no usable answer).
pub fn px4_version(heartbeat: &HEARTBEAT_DATA, flight_sw: Option<u32>) -> Option<Px4Version> {
    if heartbeat.autopilot != MavAutopilot::MAV_AUTOPILOT_PX4 {
        return None;
    }
    Px4Version::from_flight_sw(flight_sw?)
}

/// Asks for AUTOPILOT_VERSION and waits a bounded while for its flight_sw_version.
#[expect(deprecated, reason = "PX4 still answers MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES")]
pub async fn flight_sw_version(
    link: &Link,
    rx: &mut broadcast::Receiver<Arc<Inbound>>,
    target: Target,
    cancel: &CancelToken,
) -> Option<u32> {
    let ask = MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: 1.0,
        param2: 0.0,
        param3: 0.0,
        param4: 0.0,
        param5: 0.0,
        param6: 0.0,
        param7: 0.0,
        command: MavCmd::MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
        target_system: target.system,
        target_component: target.component,
        confirmation: 0,
    });
    link.send(Sender::Gcs, &ask).await.ok()?;
    let deadline = tokio::time::Instant::now() + link.clock().wall(VERSION_WAIT);
    loop {
        tokio::select! {
            biased;
            _ = cancel.cancelled() => return None,
            _ = tokio::time::sleep_until(deadline) => return None,
            r = rx.recv() => match r {
                Ok(inb) if inb.header.system_id == u32::from(target.system) => {
                    if let MavMessage::AUTOPILOT_VERSION(v) = &inb.msg {
                        return Some(v.flight_sw_version);
                    }
                }
                Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => return None,
            },
        }
    }
}

/// MAVLink's `flight_sw_version`: major, minor and patch in the top three bytes; the low byte is the release
/// type (255: official release).
fn software_version(v: u32) -> String {
    let (major, minor, patch, kind) = (v >> 24, (v >> 16) & 0xff, (v >> 8) & 0xff, v & 0xff);
    let kind = match kind {
        255 => "",
        192.. => " (release candidate)",
        128.. => " (beta)",
        64.. => " (alpha)",
        _ => " (development)",
    };
    format!("{major}.{minor}.{patch}{kind}")
}

/// `MAV_AUTOPILOT_PX4` -> `PX4`, `MAV_TYPE_QUADROTOR` -> `quadrotor`: an enum's MAVLink name in words.
fn words(debug: &str, prefix: &str) -> String {
    let name = debug.strip_prefix(prefix).unwrap_or(debug);
    match name {
        "PX4" | "ARDUPILOTMEGA" => name.replace("ARDUPILOTMEGA", "ArduPilot"),
        _ => name.to_lowercase().replace('_', " "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_and_names_read_as_words() {
        assert_eq!(software_version(0x010E_00FF), "1.14.0");
        assert_eq!(software_version(0x010F_0240), "1.15.2 (alpha)");
        assert_eq!(words("MAV_AUTOPILOT_PX4", "MAV_AUTOPILOT_"), "PX4");
        assert_eq!(words("MAV_TYPE_QUADROTOR", "MAV_TYPE_"), "quadrotor");
        assert_eq!(words("MAV_AUTOPILOT_ARDUPILOTMEGA", "MAV_AUTOPILOT_"), "ArduPilot");
        assert_eq!(words("MAV_TYPE_FIXED_WING", "MAV_TYPE_"), "fixed wing");
        let mut who = VehicleIdentity {
            system: 1,
            component: 1,
            autopilot: "PX4".into(),
            vehicle_type: "quadrotor".into(),
            flight_software: Some("1.14.0".into()),
        };
        assert_eq!(
            who.to_string(),
            "system 1, component 1: PX4 quadrotor, flight software 1.14.0"
        );
        who.flight_software = None;
        assert_eq!(who.to_string(), "system 1, component 1: PX4 quadrotor");
    }
}
