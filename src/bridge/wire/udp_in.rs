//! `udpin:HOST:PORT`: a bound UDP port that answers the vehicle, whoever else sends to it. rust-mavlink's own
//! `udpin` replies to the sender of the last datagram, any datagram: a peer flooding the port with garbage or
//! with another system's messages would carry every command to itself, and the vehicle would hear nothing. Here
//! replies go to where the last valid message of the vehicle came from (the system the link locked onto; before
//! that, an autopilot's heartbeat), and garbage or a ground station moves nothing.

use std::collections::VecDeque;
use std::io;
use std::net::SocketAddr;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU8, AtomicU32, Ordering};

use mavlink::dialects::common::{MavAutopilot, MavMessage};
use mavlink::{MavHeader, MavlinkReader, MavlinkVersion};
use tokio::net::UdpSocket;

use super::link::{BoxFuture, Transport};

/// The largest UDP payload.
const MAX_DATAGRAM: usize = 65_536;

/// A bound `udpin` socket.
pub struct UdpInTransport {
    socket: UdpSocket,
    /// Where replies go (`None` until a valid message arrived: nothing is sent before).
    peer: Mutex<Option<SocketAddr>>,
    /// The vehicle's system id, 0 before the link locked onto one.
    locked: AtomicU32,
    /// Messages of the last datagram not yet handed out (a datagram may hold several).
    pending: tokio::sync::Mutex<VecDeque<(MavHeader, MavMessage)>>,
    sequence: AtomicU8,
}

impl UdpInTransport {
    /// Binds `host_port` (`0.0.0.0:14540`).
    pub async fn bind(host_port: &str) -> io::Result<Self> {
        Ok(Self {
            socket: UdpSocket::bind(host_port).await?,
            peer: Mutex::new(None),
            locked: AtomicU32::new(0),
            pending: tokio::sync::Mutex::new(VecDeque::new()),
            sequence: AtomicU8::new(0),
        })
    }

    /// The address bound (with the port the system chose for port 0).
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// Where replies go now.
    pub fn peer(&self) -> Option<SocketAddr> {
        *self.peer.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Receives datagrams until one holds a valid message; queues its messages and notes its sender when it is
    /// the vehicle's.
    async fn fill(&self, queue: &mut VecDeque<(MavHeader, MavMessage)>) -> io::Result<()> {
        let mut buf = vec![0u8; MAX_DATAGRAM];
        while queue.is_empty() {
            let (n, from) = self.socket.recv_from(&mut buf).await?;
            queue.extend(frames(&buf[..n]));
            let lock = self.locked.load(Ordering::Relaxed);
            if queue.iter().any(|(h, m)| from_vehicle(h, m, lock)) {
                *self.peer.lock().unwrap_or_else(|p| p.into_inner()) = Some(from);
            }
        }
        Ok(())
    }
}

/// Whether a message is the vehicle's: from the system the link locked onto, or, before that, an autopilot's
/// heartbeat (what the bridge waits for; a ground station's does not count).
pub(super) fn from_vehicle(header: &MavHeader, msg: &MavMessage, locked: u32) -> bool {
    match (locked, msg) {
        (0, MavMessage::HEARTBEAT(h)) => h.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID,
        (0, _) => false,
        (system, _) => header.system_id == system,
    }
}

/// The valid MAVLink messages in one datagram; bad CRCs, unknown ids and garbage between frames are skipped (a
/// bogus header claiming more bytes than the datagram holds ends it: a vehicle sends whole frames).
fn frames(datagram: &[u8]) -> Vec<(MavHeader, MavMessage)> {
    let mut reader = MavlinkReader::new(datagram);
    let mut out = Vec::new();
    // Each attempt consumes at least one byte, so this ends; the bound only makes that plain.
    for _ in 0..=datagram.len() {
        match reader.read_any_message::<MavMessage>() {
            Ok(m) => out.push(m),
            // The end of the datagram.
            Err(mavlink::error::MessageReadError::Io(_)) => break,
            Err(_) => {}
        }
    }
    out
}

/// One MAVLink 2 frame of `msg`, numbered by the transport's own `sequence` (shared by the listening
/// transports, which answer whoever the vehicle is).
pub(super) fn encode(header: MavHeader, sequence: &AtomicU8, msg: &MavMessage) -> io::Result<Vec<u8>> {
    let header = MavHeader {
        sequence: sequence.fetch_add(1, Ordering::Relaxed),
        ..header
    };
    let mut bytes = Vec::with_capacity(280);
    mavlink::write_versioned_msg(&mut bytes, MavlinkVersion::V2, header, msg)
        .map_err(|e| io::Error::other(e.to_string()))?;
    Ok(bytes)
}

impl Transport for UdpInTransport {
    fn send<'a>(&'a self, header: MavHeader, msg: &'a MavMessage) -> BoxFuture<'a, io::Result<()>> {
        Box::pin(async move {
            // As rust-mavlink's udpin: nothing to answer before the vehicle spoke.
            let Some(peer) = self.peer() else { return Ok(()) };
            let bytes = encode(header, &self.sequence, msg)?;
            self.socket.send_to(&bytes, peer).await.map(|_| ())
        })
    }

    fn recv(&self) -> BoxFuture<'_, io::Result<(MavHeader, MavMessage)>> {
        Box::pin(async move {
            let mut queue = self.pending.lock().await;
            self.fill(&mut queue).await?;
            queue.pop_front().ok_or_else(|| io::Error::other("no message"))
        })
    }

    fn lock(&self, system_id: u8) {
        self.locked.store(u32::from(system_id), Ordering::Relaxed);
    }
}

#[cfg(test)]
#[path = "udp_in_tests.rs"]
mod tests;
