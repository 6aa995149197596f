//! Connection addresses: rust-mavlink's `udpin:HOST:PORT` form and MAVSDK's `udpin://HOST:PORT` form, checked
//! up front so a typo gets a clear error instead of a socket error later.

use std::fmt;

/// Where the bridge talks to the vehicle.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkAddress {
    /// Bind `host:port` and answer whoever talks first (PX4 SITL's API link: `udpin:0.0.0.0:14540`).
    UdpIn {
        /// Address to bind.
        host: String,
        /// UDP port.
        port: u16,
    },
    /// Send to `host:port` from an ephemeral port.
    UdpOut {
        /// Peer address.
        host: String,
        /// UDP port.
        port: u16,
    },
    /// Broadcast to `host:port`.
    UdpBcast {
        /// Broadcast address.
        host: String,
        /// UDP port.
        port: u16,
    },
    /// Connect to a TCP server.
    TcpOut {
        /// Server address.
        host: String,
        /// TCP port.
        port: u16,
    },
    /// Listen for one TCP client.
    TcpIn {
        /// Address to bind.
        host: String,
        /// TCP port.
        port: u16,
    },
    /// A serial device (`/dev/ttyACM0`, `/dev/ttyUSB0`, `COM3`) at `baud`.
    Serial {
        /// Device path.
        path: String,
        /// Baud rate.
        baud: u32,
    },
}

/// The default: PX4 SITL instance 0's API/offboard link, as MAVSDK listens.
pub const DEFAULT_URL: &str = "udpin:0.0.0.0:14540";

/// A connection address that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "connection address {url:?}: {reason} (expected e.g. udpin:0.0.0.0:14540, udpout:127.0.0.1:14580, \
     tcpout:127.0.0.1:5760, serial:/dev/ttyACM0:57600, or MAVSDK's udpin://0.0.0.0:14540)"
)]
pub struct UrlError {
    /// The address as given.
    pub url: String,
    /// What is wrong with it.
    pub reason: String,
}

impl LinkAddress {
    /// Parses either spelling; see [`LinkAddress`].
    pub fn parse(url: &str) -> Result<Self, UrlError> {
        let err = |reason: String| UrlError {
            url: url.to_string(),
            reason,
        };
        let (scheme, rest) = url
            .trim()
            .split_once(':')
            .ok_or_else(|| err("no scheme (udpin:, udpout:, tcpout:, tcpin:, serial:)".into()))?;
        // MAVSDK writes `scheme://rest`; `serial:///dev/tty..` keeps the path's own slash.
        let rest = rest.strip_prefix("//").unwrap_or(rest);
        let scheme = scheme.to_ascii_lowercase();
        if scheme == "serial" {
            let (path, baud) = serial(rest).map_err(err)?;
            return Ok(Self::Serial { path, baud });
        }
        let socket: fn(String, u16) -> Self = match scheme.as_str() {
            "udpin" | "udp" => |host, port| Self::UdpIn { host, port },
            "udpout" => |host, port| Self::UdpOut { host, port },
            "udpbcast" => |host, port| Self::UdpBcast { host, port },
            "tcpout" | "tcp" => |host, port| Self::TcpOut { host, port },
            "tcpin" => |host, port| Self::TcpIn { host, port },
            other => return Err(err(format!("unknown scheme {other:?}"))),
        };
        let (host, port) = host_port(rest).map_err(err)?;
        Ok(socket(host, port))
    }

    /// The address in rust-mavlink's syntax (`mavlink::connect_async`).
    pub fn to_mavlink(&self) -> String {
        self.to_string()
    }
}

impl fmt::Display for LinkAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UdpIn { host, port } => write!(f, "udpin:{host}:{port}"),
            Self::UdpOut { host, port } => write!(f, "udpout:{host}:{port}"),
            Self::UdpBcast { host, port } => write!(f, "udpbcast:{host}:{port}"),
            Self::TcpOut { host, port } => write!(f, "tcpout:{host}:{port}"),
            Self::TcpIn { host, port } => write!(f, "tcpin:{host}:{port}"),
            Self::Serial { path, baud } => write!(f, "serial:{path}:{baud}"),
        }
    }
}

/// `HOST:PORT` of a socket address; an empty host (MAVSDK's `udp://:14540`) means every interface.
fn host_port(rest: &str) -> Result<(String, u16), String> {
    let (host, port) = rest.rsplit_once(':').ok_or_else(|| format!("{rest:?} has no :PORT"))?;
    let port: u16 = port
        .parse()
        .map_err(|_| format!("port {port:?} is not a number from 0 to 65535"))?;
    let host = if host.is_empty() { "0.0.0.0" } else { host };
    if host.contains(['/', ' ']) {
        return Err(format!("host {host:?} is not a host name or IP address"));
    }
    Ok((host.to_string(), port))
}

/// `PATH:BAUD` of a serial device.
fn serial(rest: &str) -> Result<(String, u32), String> {
    let (path, baud) = rest
        .rsplit_once(':')
        .ok_or_else(|| format!("{rest:?} has no :BAUD (e.g. /dev/ttyACM0:57600)"))?;
    let baud: u32 = baud
        .parse()
        .ok()
        .filter(|b| *b > 0)
        .ok_or_else(|| format!("baud rate {baud:?} is not a positive number"))?;
    if path.is_empty() {
        return Err("no serial device path".into());
    }
    Ok((path.to_string(), baud))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn both_spellings() {
        let a = LinkAddress::parse("udpin:0.0.0.0:14540").unwrap();
        assert_eq!(a, LinkAddress::parse("udpin://0.0.0.0:14540").unwrap());
        assert_eq!(a.to_mavlink(), "udpin:0.0.0.0:14540");
        assert_eq!(LinkAddress::parse("udp://:14540").unwrap(), a);
        assert_eq!(
            LinkAddress::parse("serial:/dev/ttyACM0:57600").unwrap(),
            LinkAddress::Serial {
                path: "/dev/ttyACM0".into(),
                baud: 57600
            }
        );
        assert_eq!(
            LinkAddress::parse("serial:///dev/ttyUSB0:921600").unwrap().to_mavlink(),
            "serial:/dev/ttyUSB0:921600"
        );
        assert_eq!(
            LinkAddress::parse("tcpout:127.0.0.1:5760").unwrap().to_mavlink(),
            "tcpout:127.0.0.1:5760"
        );
        assert_eq!(
            LinkAddress::parse("tcp://localhost:5760").unwrap().to_mavlink(),
            "tcpout:localhost:5760"
        );
        assert!(matches!(
            LinkAddress::parse("UDPOUT:127.0.0.1:14580").unwrap(),
            LinkAddress::UdpOut { port: 14580, .. }
        ));
    }

    #[test]
    fn clear_errors() {
        for (url, words) in [
            ("14540", "no scheme"),
            ("udpin:0.0.0.0", "no :PORT"),
            ("udpin:0.0.0.0:99999", "port \"99999\""),
            ("serial:/dev/ttyACM0", "no :BAUD"),
            ("serial:/dev/ttyACM0:fast", "baud rate"),
            ("serial:/dev/ttyACM0:0", "baud rate"),
            ("http://x:80", "unknown scheme \"http\""),
            ("file:/tmp/x.tlog", "unknown scheme"),
        ] {
            let e = LinkAddress::parse(url).unwrap_err().to_string();
            assert!(e.contains(words) && e.contains(url), "{url}: {e}");
        }
    }

    proptest! {
        #[test]
        fn display_round_trips(host in "[a-z0-9.]{1,20}", port: u16, baud in 1u32..4_000_000) {
            for a in [
                LinkAddress::UdpIn { host: host.clone(), port },
                LinkAddress::TcpOut { host: host.clone(), port },
                LinkAddress::Serial { path: format!("/dev/{host}"), baud },
            ] {
                prop_assert_eq!(LinkAddress::parse(&a.to_string()).unwrap(), a);
            }
        }

        #[test]
        fn never_panics(s in "\\PC{0,40}") {
            let _ = LinkAddress::parse(&s);
        }
    }
}
