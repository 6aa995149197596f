//! The simulator's errors, each naming what went wrong and what to do about it.

use std::time::Duration;

/// Why a simulator run could not start or had to stop.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The TCP port PX4 connects to is taken.
    #[error(
        "TCP port {port} is in use: another simulator (Gazebo, jMAVSim, prgenuav-sim) is serving it; stop it, or \
         use another instance (PX4 instance N connects to 4560+N)"
    )]
    PortInUse {
        /// The port.
        port: u16,
    },
    /// Binding or accepting failed otherwise.
    #[error("cannot listen on {addr}: {source}")]
    Listen {
        /// The address.
        addr: String,
        /// The cause.
        source: std::io::Error,
    },
    /// PX4 did not connect in time.
    #[error(
        "PX4 did not connect to TCP {addr} within {waited:?}: start PX4 SITL for this instance (PX4_SIM_MODEL=none_iris)"
    )]
    NoConnection {
        /// The address.
        addr: String,
        /// How long we waited.
        waited: Duration,
    },
    /// The serial device could not be opened.
    #[error(
        "cannot open serial device {device} at {baud} baud: {source} (is the board plugged in, the path right, and no other program using it?)"
    )]
    SerialOpen {
        /// The device path.
        device: String,
        /// The baud rate.
        baud: u32,
        /// The cause.
        source: tokio_serial::Error,
    },
    /// The gateway's UDP socket could not be set up.
    #[error("cannot open the gateway's UDP socket {addr}: {source}")]
    Gateway {
        /// The address.
        addr: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The link to PX4 went away or fell silent.
    #[error("link lost: {0}")]
    LinkLost(String),
    /// PX4 connected but never sent a motor command.
    #[error(
        "PX4 connected but sent no HIL_ACTUATOR_CONTROLS within {0:?}: is it PX4 SITL with an external simulator (none_iris)?"
    )]
    NeverAnswered(Duration),
}
