//! Byte transports behind one small trait: our own UDP socket (PX4-style, port discovery) and
//! any rust-mavlink connection address (tcp, serial, udp).

use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU8, Ordering};

use mavlink::dialects::common::MavMessage;
use mavlink::{AsyncConnection, AsyncMavConnection, MavHeader, MavlinkReader};
use tokio::net::UdpSocket;

use crate::vehicle::{COMPONENT_ID, SYSTEM_ID};

/// Moves MAVLink messages; the runner owns one and never needs more.
pub trait Transport: Send + Sync + 'static {
    /// Send one message as sysid 1 / compid 1.
    fn send(&self, msg: &MavMessage) -> impl Future<Output = io::Result<()>> + Send;
    /// Wait for the next batch of valid messages (a datagram may hold several).
    fn recv(&self) -> impl Future<Output = io::Result<Vec<(MavHeader, MavMessage)>>> + Send;
}

/// UDP like PX4's MAVLink module: bound locally, sends to a remote that follows the last sender.
#[derive(Debug)]
pub struct UdpTransport {
    socket: UdpSocket,
    remote: Mutex<Option<SocketAddr>>,
    sequence: AtomicU8,
}

impl UdpTransport {
    /// Bind `local`; send to `remote` until someone else talks to us.
    pub async fn bind(local: SocketAddr, remote: Option<SocketAddr>) -> io::Result<Self> {
        Ok(Self {
            socket: UdpSocket::bind(local).await?,
            remote: Mutex::new(remote),
            sequence: AtomicU8::new(0),
        })
    }

    /// The bound address (learn the port after binding port 0).
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    fn remote(&self) -> Option<SocketAddr> {
        self.remote.lock().map(|r| *r).unwrap_or(None)
    }
}

/// Parse every valid frame in `bytes`; garbage and bad CRCs are skipped.
pub fn parse_datagram(bytes: &[u8]) -> Vec<(MavHeader, MavMessage)> {
    let mut reader = MavlinkReader::new(bytes);
    let mut out = Vec::new();
    // Each call consumes at least one byte or ends at EOF, so this bound is never the limit.
    for _ in 0..=bytes.len() {
        match reader.read_any_message::<MavMessage>() {
            Ok(m) => out.push(m),
            Err(mavlink::error::MessageReadError::Io(_)) => break,
            Err(_) => continue,
        }
    }
    out
}

fn header(seq: &AtomicU8) -> MavHeader {
    MavHeader {
        system_id: SYSTEM_ID.into(),
        component_id: COMPONENT_ID,
        sequence: seq.fetch_add(1, Ordering::Relaxed),
    }
}

impl Transport for UdpTransport {
    async fn send(&self, msg: &MavMessage) -> io::Result<()> {
        let Some(remote) = self.remote() else {
            return Ok(()); // nobody to talk to yet
        };
        let mut buf = Vec::with_capacity(280);
        mavlink::write_v2_msg(&mut buf, header(&self.sequence), msg).map_err(|e| io::Error::other(e.to_string()))?;
        self.socket.send_to(&buf, remote).await.map(|_| ())
    }

    async fn recv(&self) -> io::Result<Vec<(MavHeader, MavMessage)>> {
        let mut buf = [0u8; 2048];
        let (n, from) = self.socket.recv_from(&mut buf).await?;
        if let Ok(mut r) = self.remote.lock() {
            *r = Some(from);
        }
        Ok(parse_datagram(&buf[..n]))
    }
}

/// Any rust-mavlink connection (`tcpin:`, `tcpout:`, `udpin:`, `udpout:`, `serial:` ...).
pub struct MavConnTransport {
    conn: AsyncConnection<MavMessage>,
    sequence: AtomicU8,
}

impl MavConnTransport {
    /// Open `address` (rust-mavlink syntax).
    pub async fn connect(address: &str) -> io::Result<Self> {
        let mut conn = mavlink::connect_async::<MavMessage>(address).await?;
        conn.set_allow_recv_any_version(true);
        Ok(Self {
            conn,
            sequence: AtomicU8::new(0),
        })
    }
}

impl Transport for MavConnTransport {
    async fn send(&self, msg: &MavMessage) -> io::Result<()> {
        self.conn
            .send(&header(&self.sequence), msg)
            .await
            .map(|_| ())
            .map_err(|e| io::Error::other(e.to_string()))
    }

    async fn recv(&self) -> io::Result<Vec<(MavHeader, MavMessage)>> {
        match self.conn.recv().await {
            Ok(m) => Ok(vec![m]),
            Err(mavlink::error::MessageReadError::Io(e)) => Err(e),
            Err(_) => Ok(Vec::new()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::HEARTBEAT_DATA;

    fn frame(msg: &MavMessage) -> Vec<u8> {
        let mut buf = Vec::new();
        let h = MavHeader {
            system_id: 255,
            component_id: 190,
            sequence: 3,
        };
        mavlink::write_v2_msg(&mut buf, h, msg).expect("serialize");
        buf
    }

    #[test]
    fn datagrams_with_garbage_and_bad_crc() {
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        let good = frame(&hb);
        let mut bad = good.clone();
        let last = bad.len() - 1;
        bad[last] ^= 0xFF;
        let mut dgram = vec![0xFD, 0x01, 0x02, 0x55];
        dgram.extend(&bad);
        dgram.extend(&good);
        dgram.extend(&good);
        dgram.extend([0xFE, 0x09]);
        let msgs = parse_datagram(&dgram);
        assert_eq!(msgs.len(), 2);
        assert_eq!(msgs[0].0.system_id, 255);
        assert!(parse_datagram(&[]).is_empty());
    }
}
