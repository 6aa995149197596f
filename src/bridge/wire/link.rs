//! The bridge's one connection to a vehicle: a transport (any rust-mavlink address) behind a small trait, one
//! receive task that fans every message out to subscribers, a send path for the GCS and the avoidance
//! companion identities, locking onto one vehicle's system id, and packet counters.

use std::future::Future;
use std::io;
use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::time::Duration;

use mavlink::dialects::common::MavMessage;
use mavlink::{AsyncConnection, AsyncMavConnection, MavHeader};
use serde::Serialize;
use tokio::sync::broadcast;
use tokio::task::JoinHandle;

use super::cancel::CancelToken;
use super::clock::VehicleClock;
use super::exchange::{Exchange, ProtocolError};

/// Our system id as a ground station (MAVSDK's default for a GCS, so QGroundControl's 255 stays free).
pub const GCS_SYSTEM_ID: u8 = 245;
/// Our component id as a ground station (MAV_COMP_ID_MISSIONPLANNER).
pub const GCS_COMPONENT_ID: u8 = 190;
/// The avoidance companion's component id (MAV_COMP_ID_OBSTACLE_AVOIDANCE).
pub const AVOIDANCE_COMPONENT_ID: u8 = 196;

/// A boxed future, so transports can live behind `dyn`.
pub type BoxFuture<'a, T> = Pin<Box<dyn Future<Output = T> + Send + 'a>>;

/// Moves MAVLink messages; nothing else.
pub trait Transport: Send + Sync + 'static {
    /// Sends one message with `header` (the transport may fill in the sequence number).
    fn send<'a>(&'a self, header: MavHeader, msg: &'a MavMessage) -> BoxFuture<'a, io::Result<()>>;
    /// The next valid message (invalid frames are skipped inside).
    fn recv(&self) -> BoxFuture<'_, io::Result<(MavHeader, MavMessage)>>;
    /// The link locked onto the vehicle `system_id` (a transport that picks whom to answer listens).
    fn lock(&self, _system_id: u8) {}
}

/// Any rust-mavlink connection (udpin/udpout/tcpout/tcpin/serial).
pub struct MavTransport {
    conn: AsyncConnection<MavMessage>,
}

impl MavTransport {
    /// Opens `address` in rust-mavlink syntax; MAVLink 2 out, 1 or 2 in.
    pub async fn open(address: &str) -> io::Result<Self> {
        let mut conn = mavlink::connect_async::<MavMessage>(address).await?;
        conn.set_allow_recv_any_version(true);
        Ok(Self { conn })
    }
}

impl Transport for MavTransport {
    fn send<'a>(&'a self, header: MavHeader, msg: &'a MavMessage) -> BoxFuture<'a, io::Result<()>> {
        Box::pin(async move {
            self.conn
                .send(&header, msg)
                .await
                .map(|_| ())
                .map_err(|e| io::Error::other(e.to_string()))
        })
    }

    fn recv(&self) -> BoxFuture<'_, io::Result<(MavHeader, MavMessage)>> {
        Box::pin(async move {
            loop {
                match self.conn.recv().await {
                    Ok(m) => return Ok(m),
                    Err(mavlink::error::MessageReadError::Io(e)) => return Err(e),
                    Err(_) => continue, // bad CRC, unknown id: skip the frame
                }
            }
        })
    }
}

/// One received message.
#[derive(Debug, Clone)]
pub struct Inbound {
    /// Its header (sender ids).
    pub header: MavHeader,
    /// The message.
    pub msg: MavMessage,
}

/// Packet counts of a link.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct LinkStats {
    /// Messages received from the vehicle we locked onto (or from anyone before locking).
    pub packets_received: u64,
    /// Messages from other systems, ignored.
    pub packets_ignored: u64,
    /// Messages sent.
    pub packets_sent: u64,
    /// Protocol messages re-sent after a timeout.
    pub retries: u64,
}

#[derive(Debug, Default)]
struct Counters {
    received: AtomicU64,
    ignored: AtomicU64,
    sent: AtomicU64,
    retries: AtomicU64,
}

/// Who a message is from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sender {
    /// The ground station ([`GCS_SYSTEM_ID`] / [`GCS_COMPONENT_ID`]).
    Gcs,
    /// The avoidance companion: the vehicle's own system id, component 196.
    Companion,
}

/// A connection to one vehicle; dropping it stops the receive task.
pub struct Link {
    transport: Arc<dyn Transport>,
    fanout: broadcast::Sender<Arc<Inbound>>,
    counters: Arc<Counters>,
    /// 0 = not locked yet.
    locked: Arc<AtomicU32>,
    clock: std::sync::Mutex<VehicleClock>,
    /// `None` once [`Link::close`] stopped it.
    rx_task: std::sync::Mutex<Option<JoinHandle<()>>>,
}

impl Drop for Link {
    fn drop(&mut self) {
        if let Some(t) = self.rx_task.lock().unwrap_or_else(|p| p.into_inner()).take() {
            t.abort();
        }
    }
}

/// How many messages a slow subscriber may fall behind before it loses some.
const FANOUT_CAPACITY: usize = 16_384;

impl Link {
    /// Starts the receive task on `transport` (needs a tokio runtime).
    pub fn new(transport: Arc<dyn Transport>, clock: VehicleClock) -> Self {
        let (fanout, _) = broadcast::channel(FANOUT_CAPACITY);
        let counters = Arc::new(Counters::default());
        let locked = Arc::new(AtomicU32::new(0));
        let rx_task = tokio::spawn(receive_loop(
            transport.clone(),
            fanout.clone(),
            counters.clone(),
            locked.clone(),
        ));
        Self {
            transport,
            fanout,
            counters,
            locked,
            clock: std::sync::Mutex::new(clock),
            rx_task: std::sync::Mutex::new(Some(rx_task)),
        }
    }

    /// Stops the receive task and waits until it has let go of the transport, so that once the last `Link`
    /// handle is dropped the transport (a `udpin` socket) is closed at once, not whenever the runtime next
    /// polls the aborted task: a campaign re-binds the same port for the vehicle's next flight straight away.
    pub async fn close(&self) {
        let task = self.rx_task.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(t) = task {
            t.abort();
            let _ = t.await; // cancelled: nothing to report
        }
    }

    /// The vehicle clock every timeout of this link uses.
    pub fn clock(&self) -> VehicleClock {
        *self.clock.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// From now on the vehicle's time runs `scale` times wall time (a measured rate), continuing from the
    /// current vehicle time. Call before anything holds deadlines on the old scale.
    pub fn set_time_scale(&self, scale: f64) {
        let mut c = self.clock.lock().unwrap_or_else(|p| p.into_inner());
        *c = c.rescaled(scale);
    }

    /// A receiver of every message from now on.
    pub fn subscribe(&self) -> broadcast::Receiver<Arc<Inbound>> {
        self.fanout.subscribe()
    }

    /// From now on, only messages from `system_id` are delivered.
    pub fn lock(&self, system_id: u8) {
        self.locked.store(u32::from(system_id), Ordering::Relaxed);
        self.transport.lock(system_id);
    }

    /// The locked system id, if any.
    pub fn locked(&self) -> Option<u8> {
        match self.locked.load(Ordering::Relaxed) {
            0 => None,
            s => Some(s as u8),
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> LinkStats {
        LinkStats {
            packets_received: self.counters.received.load(Ordering::Relaxed),
            packets_ignored: self.counters.ignored.load(Ordering::Relaxed),
            packets_sent: self.counters.sent.load(Ordering::Relaxed),
            retries: self.counters.retries.load(Ordering::Relaxed),
        }
    }

    /// Sends `msg` as `from`; transport errors are returned, not retried.
    pub async fn send(&self, from: Sender, msg: &MavMessage) -> io::Result<()> {
        let header = match from {
            Sender::Gcs => MavHeader {
                system_id: GCS_SYSTEM_ID.into(),
                component_id: GCS_COMPONENT_ID,
                sequence: 0,
            },
            Sender::Companion => MavHeader {
                system_id: self.locked().unwrap_or(1).into(),
                component_id: AVOIDANCE_COMPONENT_ID,
                sequence: 0,
            },
        };
        self.counters.sent.fetch_add(1, Ordering::Relaxed);
        self.transport.send(header, msg).await
    }

    /// Runs a protocol exchange to its end: subscribe, send its first messages, feed it messages and
    /// timeouts (vehicle time) until it is done. Bounded by the exchange's own retries, or `cancel`.
    pub async fn exchange<E: Exchange>(&self, mut ex: E, cancel: &CancelToken) -> Result<E::Output, ProtocolError> {
        let mut rx = self.subscribe();
        let mut counted = 0;
        let clock = self.clock();
        for m in ex.start(clock.now()) {
            let _ = self.send(Sender::Gcs, &m).await;
        }
        loop {
            let wait = clock.wall_until(ex.deadline());
            let step = tokio::select! {
                biased;
                _ = cancel.cancelled() => return Err(ProtocolError::Cancelled),
                r = rx.recv() => match r {
                    Ok(inb) => ex.on_message(&inb.msg, clock.now()),
                    Err(broadcast::error::RecvError::Lagged(_)) => continue,
                    // The receive task ended (transport gone): only timeouts remain.
                    Err(broadcast::error::RecvError::Closed) => {
                        tokio::time::sleep(wait).await;
                        ex.on_timeout(clock.now())
                    }
                },
                _ = tokio::time::sleep(wait) => ex.on_timeout(clock.now()),
            };
            let r = ex.retries();
            self.counters
                .retries
                .fetch_add(u64::from(r - counted), Ordering::Relaxed);
            counted = r;
            for m in &step.send {
                let _ = self.send(Sender::Gcs, m).await;
            }
            if let Some(done) = step.done {
                return done;
            }
        }
    }
}

fn is_closed(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::UnexpectedEof | io::ErrorKind::ConnectionAborted | io::ErrorKind::BrokenPipe
    )
}

async fn receive_loop(
    transport: Arc<dyn Transport>,
    fanout: broadcast::Sender<Arc<Inbound>>,
    counters: Arc<Counters>,
    locked: Arc<AtomicU32>,
) {
    loop {
        match transport.recv().await {
            Ok((header, msg)) => {
                let lock = locked.load(Ordering::Relaxed);
                if lock != 0 && header.system_id != lock {
                    counters.ignored.fetch_add(1, Ordering::Relaxed);
                    continue;
                }
                counters.received.fetch_add(1, Ordering::Relaxed);
                // No subscriber is fine: nobody is waiting for this message.
                let _ = fanout.send(Arc::new(Inbound { header, msg }));
            }
            // TCP EOF repeats forever once the peer closed: stop instead of spinning.
            Err(e) if is_closed(&e) => return,
            // UDP ICMP errors (peer not listening yet) and serial hiccups: back off briefly.
            Err(_) => tokio::time::sleep(Duration::from_millis(10)).await,
        }
    }
}

/// An in-memory transport pair for tests: what one end sends, the other receives.
pub mod memory {
    use super::*;
    use tokio::sync::{Mutex, mpsc};

    /// One end of a pair.
    pub struct MemoryTransport {
        tx: mpsc::UnboundedSender<(MavHeader, MavMessage)>,
        rx: Mutex<mpsc::UnboundedReceiver<(MavHeader, MavMessage)>>,
    }

    /// Two connected ends.
    pub fn pair() -> (MemoryTransport, MemoryTransport) {
        let (a_tx, a_rx) = mpsc::unbounded_channel();
        let (b_tx, b_rx) = mpsc::unbounded_channel();
        (
            MemoryTransport {
                tx: a_tx,
                rx: Mutex::new(b_rx),
            },
            MemoryTransport {
                tx: b_tx,
                rx: Mutex::new(a_rx),
            },
        )
    }

    impl Transport for MemoryTransport {
        fn send<'a>(&'a self, header: MavHeader, msg: &'a MavMessage) -> BoxFuture<'a, io::Result<()>> {
            let r = self
                .tx
                .send((header, msg.clone()))
                .map_err(|_| io::Error::from(io::ErrorKind::BrokenPipe));
            Box::pin(async move { r })
        }

        fn recv(&self) -> BoxFuture<'_, io::Result<(MavHeader, MavMessage)>> {
            Box::pin(async move {
                self.rx
                    .lock()
                    .await
                    .recv()
                    .await
                    .ok_or_else(|| io::Error::from(io::ErrorKind::UnexpectedEof))
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::{HEARTBEAT_DATA, MavCmd, MavResult};

    fn hb() -> MavMessage {
        MavMessage::HEARTBEAT(HEARTBEAT_DATA::default())
    }

    fn from(sys: u8) -> MavHeader {
        MavHeader {
            system_id: sys.into(),
            component_id: 1,
            sequence: 0,
        }
    }

    #[tokio::test]
    async fn locks_onto_one_system_and_counts() {
        let (ours, theirs) = memory::pair();
        let link = Link::new(Arc::new(ours), VehicleClock::new(1.0));
        let mut rx = link.subscribe();
        theirs.send(from(7), &hb()).await.unwrap();
        let got = tokio::time::timeout(Duration::from_secs(5), rx.recv())
            .await
            .unwrap()
            .unwrap();
        assert_eq!(got.header.system_id, 7);
        link.lock(1);
        theirs.send(from(7), &hb()).await.unwrap();
        theirs.send(from(1), &hb()).await.unwrap();
        let got = tokio::time::timeout(Duration::from_secs(5), rx.recv())
            .await
            .unwrap()
            .unwrap();
        assert_eq!(got.header.system_id, 1);
        let s = link.stats();
        assert_eq!((s.packets_received, s.packets_ignored), (2, 1));
        link.send(Sender::Companion, &hb()).await.unwrap();
        let (h, _) = theirs.recv().await.unwrap();
        assert_eq!((h.system_id, h.component_id), (1, AVOIDANCE_COMPONENT_ID));
        assert_eq!(link.stats().packets_sent, 1);
    }

    #[tokio::test]
    async fn exchange_over_a_link_counts_retries_and_cancels() {
        use super::super::command::AckedCommand;
        use super::super::exchange::{RetryPolicy, Target};
        use mavlink::dialects::common::COMMAND_ACK_DATA;
        let (ours, theirs) = memory::pair();
        // Vehicle time runs 100x, so the 1 s command timeout is 10 ms of wall time.
        let link = Link::new(Arc::new(ours), VehicleClock::new(100.0));
        let theirs = Arc::new(theirs);
        let vehicle = theirs.clone();
        tokio::spawn(async move {
            let mut n = 0;
            while let Ok((_, m)) = vehicle.recv().await {
                n += 1;
                if let (MavMessage::COMMAND_LONG(c), true) = (m, n >= 3) {
                    let ack = MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                        command: c.command,
                        result: MavResult::MAV_RESULT_ACCEPTED,
                        ..Default::default()
                    });
                    let _ = vehicle.send(from(1), &ack).await;
                }
            }
        });
        let t = Target {
            system: 1,
            component: 1,
        };
        let cmd = AckedCommand::new(t, MavCmd::MAV_CMD_NAV_LAND, [0.0; 7], RetryPolicy::COMMAND);
        let cancel = CancelToken::new();
        let r = tokio::time::timeout(Duration::from_secs(5), link.exchange(cmd, &cancel))
            .await
            .unwrap();
        assert_eq!(r, Ok(()));
        assert_eq!(link.stats().retries, 2);
        cancel.cancel();
        let cmd = AckedCommand::new(t, MavCmd::MAV_CMD_NAV_LAND, [0.0; 7], RetryPolicy::COMMAND);
        let r = tokio::time::timeout(Duration::from_secs(5), link.exchange(cmd, &cancel))
            .await
            .unwrap();
        assert_eq!(r, Err(ProtocolError::Cancelled));
    }
}
