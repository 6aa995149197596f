//! A flight controller on a bench in the loop (HITL, `--hitl serial:/dev/ttyACM0:921600`): the simulator runs
//! on the board's serial port on the wall clock at 250 Hz (HEARTBEATs until PX4 answers, never
//! HIL_STATE_QUATERNION), and every other MAVLink frame of the board goes through the simulator's UDP
//! gateway to the bridge, which flies the board there. The board must be in HITL mode (`SYS_HITL 1`: the
//! bridge checks before it sets or arms anything).

use std::net::SocketAddr;

use simulator::hil::gateway::GatewayConfig;
use simulator::{SimConfig, SimError};

use super::run::{SimRun, SimSummary};
use crate::model::GeoPoint;

/// A board's serial port as `--hitl` names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BoardPort {
    /// The device (`/dev/ttyACM0`).
    pub device: String,
    /// Its baud rate (HIL needs more than 5000 B/s: 57600 at least; USB takes 921600).
    pub baud: u32,
}

impl BoardPort {
    /// Reads `serial:DEVICE:BAUD`.
    pub fn parse(url: &str) -> Result<BoardPort, String> {
        let example = "serial:/dev/ttyACM0:921600";
        let rest = url
            .strip_prefix("serial:")
            .ok_or_else(|| format!("--hitl {url:?}: expected {example}"))?;
        let (device, baud) = rest
            .rsplit_once(':')
            .ok_or_else(|| format!("--hitl {url:?}: expected {example} (the baud rate is missing)"))?;
        let baud: u32 = baud
            .parse()
            .map_err(|_| format!("--hitl {url:?}: baud {baud:?} is not a number (e.g. {example})"))?;
        if device.is_empty() {
            return Err(format!("--hitl {url:?}: no device (e.g. {example})"));
        }
        // PX4 enables HIL only on a link faster than 5000 B/s (mavlink_main.cpp).
        if baud < 57_600 {
            return Err(format!(
                "--hitl {url:?}: {baud} baud is too slow for HIL (PX4 enables it above 5000 B/s): use 57600 or more, \
                 921600 on USB"
            ));
        }
        Ok(BoardPort {
            device: device.to_string(),
            baud,
        })
    }
}

/// The simulator serving a board, and where the bridge flies it.
pub struct Board {
    sim: SimRun,
    url: String,
}

impl Board {
    /// Opens `port` and runs the simulator there with the vehicle at rest at `home`; the board's traffic goes
    /// to a free local UDP port the bridge listens on ([`Board::url`]).
    pub async fn start(port: &BoardPort, home: GeoPoint, seed: u64) -> Result<Board, SimError> {
        let gateway_err = |source| SimError::Gateway {
            addr: "127.0.0.1:0".into(),
            source,
        };
        // A port the bridge binds next: free now (a moment's race with another program is refused there).
        let probe = std::net::UdpSocket::bind("127.0.0.1:0").map_err(gateway_err)?;
        let bridge = probe.local_addr().map_err(gateway_err)?;
        drop(probe);
        let gateway = GatewayConfig {
            bind: SocketAddr::from(([127, 0, 0, 1], 0)),
            remote: bridge,
        };
        let config = SimConfig {
            home,
            seed,
            ..SimConfig::default()
        };
        let sim = SimRun::serve_serial(&port.device, port.baud, config, Some(gateway)).await?;
        Ok(Board {
            sim,
            url: format!("udpin:{bridge}"),
        })
    }

    /// The bridge's address of the board, through the gateway.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// Why the simulator ended on its own (the device gone, the board silent), if it did.
    pub fn failure(&self) -> Option<String> {
        self.sim.failure()
    }

    /// Stops the simulator and lets go of the serial port.
    pub async fn stop(self) -> SimSummary {
        self.sim.stop().await
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_board_url_names_its_device_and_a_baud_fast_enough_for_hil() {
        let p = BoardPort::parse("serial:/dev/ttyACM0:921600").unwrap();
        assert_eq!((p.device.as_str(), p.baud), ("/dev/ttyACM0", 921_600));
        for (bad, says) in [
            ("/dev/ttyACM0:921600", "expected serial:"),
            ("serial:/dev/ttyACM0", "baud rate is missing"),
            ("serial:/dev/ttyACM0:fast", "is not a number"),
            ("serial::921600", "no device"),
            ("serial:/dev/ttyUSB0:9600", "too slow for HIL"),
        ] {
            let e = BoardPort::parse(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }

    #[tokio::test]
    async fn a_missing_device_is_refused_naming_it() {
        let port = BoardPort::parse("serial:/dev/prgenuav-no-such-board:921600").unwrap();
        let e = match Board::start(&port, crate::model::SIM_HOME, 0).await {
            Err(e) => e.to_string(),
            Ok(_) => panic!("no such device"),
        };
        assert!(
            e.contains("/dev/prgenuav-no-such-board") && e.contains("plugged in"),
            "{e}"
        );
    }
}
