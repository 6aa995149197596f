//! `tcpin:HOST:PORT`: a TCP listener that flies with the client that is the vehicle, not the first one to
//! connect. rust-mavlink's own `tcpin` waits, without a deadline and deaf to a stop, for one client and keeps
//! it: an idle or babbling client that connects first takes the link, and a bridge with no vehicle never
//! returns. Here the port is bound at once, clients are accepted in the background (a few at a time, the
//! oldest undecided one dropped for a newcomer), and the link settles on the first client whose messages are
//! the vehicle's (an autopilot's heartbeat); the others are closed and nothing more is accepted. The waits
//! stay the bridge's own (the heartbeat wait, the cancel token).

use std::collections::VecDeque;
use std::io;
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, AtomicU32, AtomicU64, Ordering};

use mavlink::dialects::common::MavMessage;
use mavlink::error::MessageReadError;
use mavlink::{AsyncMavlinkReader, MavHeader};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpListener;
use tokio::net::tcp::OwnedWriteHalf;
use tokio::sync::{Mutex, Notify, mpsc};
use tokio::task::{AbortHandle, JoinSet};

use super::link::{BoxFuture, Transport};
use super::udp_in::{encode, from_vehicle};

/// Clients held at once before one is the vehicle; a newcomer past it drops the oldest.
pub const MAX_UNDECIDED: usize = 8;
/// Messages of the vehicle queued for the bridge (a reader waits when it is full: TCP's own back-pressure).
const QUEUE: usize = 1024;

/// What the readers share.
struct Shared {
    /// The client chosen as the vehicle (its connection number), 0 before.
    chosen: AtomicU64,
    /// The vehicle's system id, 0 before the link locked onto one.
    locked: AtomicU32,
    /// Raised when a client is chosen, so the acceptor stops at once.
    decided: Notify,
    /// The chosen client's writing half.
    writer: Mutex<Option<OwnedWriteHalf>>,
    /// The vehicle's messages, or the error that ended its connection.
    queue: mpsc::Sender<io::Result<(MavHeader, MavMessage)>>,
}

/// A bound `tcpin` listener.
pub struct TcpInTransport {
    local: SocketAddr,
    shared: Arc<Shared>,
    incoming: Mutex<mpsc::Receiver<io::Result<(MavHeader, MavMessage)>>>,
    acceptor: AbortHandle,
    sequence: AtomicU8,
}

impl TcpInTransport {
    /// Binds `host_port` (`0.0.0.0:5760`) and starts accepting clients.
    pub async fn bind(host_port: &str) -> io::Result<Self> {
        let listener = TcpListener::bind(host_port).await?;
        let local = listener.local_addr()?;
        let (queue, incoming) = mpsc::channel(QUEUE);
        let shared = Arc::new(Shared {
            chosen: AtomicU64::new(0),
            locked: AtomicU32::new(0),
            decided: Notify::new(),
            writer: Mutex::new(None),
            queue,
        });
        let acceptor = tokio::spawn(accept_clients(listener, shared.clone())).abort_handle();
        Ok(Self {
            local,
            shared,
            incoming: Mutex::new(incoming),
            acceptor,
            sequence: AtomicU8::new(0),
        })
    }

    /// The address bound (with the port the system chose for port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }
}

impl Drop for TcpInTransport {
    fn drop(&mut self) {
        // The acceptor owns the readers (a JoinSet): ending it closes every client.
        self.acceptor.abort();
    }
}

/// Accepts clients until one is the vehicle, then keeps its reader running and closes the others.
async fn accept_clients(listener: TcpListener, shared: Arc<Shared>) {
    let mut readers = JoinSet::new();
    let mut undecided: VecDeque<(u64, AbortHandle)> = VecDeque::new();
    let mut number = 0u64;
    while shared.chosen.load(Ordering::SeqCst) == 0 {
        tokio::select! {
            accepted = listener.accept() => {
                let Ok((stream, _)) = accepted else { continue };
                number += 1;
                let (read, write) = stream.into_split();
                let handle = readers.spawn(read_client(number, read, write, shared.clone()));
                undecided.push_back((number, handle));
                if undecided.len() > MAX_UNDECIDED
                    && let Some((_, oldest)) = undecided.pop_front()
                {
                    oldest.abort();
                }
            }
            () = shared.decided.notified() => {}
            // A reader that ended (its client left) frees its place; one that became the vehicle ends the loop.
            Some(_) = readers.join_next(), if !readers.is_empty() => {
                undecided.retain(|(_, h)| !h.is_finished());
            }
        }
    }
    let chosen = shared.chosen.load(Ordering::SeqCst);
    for (n, handle) in undecided {
        if n != chosen {
            handle.abort();
        }
    }
    drop(listener);
    while readers.join_next().await.is_some() {}
}

/// Reads client `number`: ignores it until it shows itself the vehicle (and no other has), then forwards its
/// messages; ends when another client is chosen, or when its connection ends (told to the bridge if chosen).
async fn read_client(number: u64, read: tokio::net::tcp::OwnedReadHalf, write: OwnedWriteHalf, shared: Arc<Shared>) {
    let mut reader = AsyncMavlinkReader::new(read);
    let mut write = Some(write);
    loop {
        let message = match reader.read_any_message::<MavMessage>().await {
            Ok(m) => m,
            Err(MessageReadError::Io(e)) => {
                if shared.chosen.load(Ordering::SeqCst) == number {
                    let ended = io::Error::new(e.kind(), format!("the vehicle's TCP connection ended: {e}"));
                    let _ = shared.queue.send(Err(ended)).await;
                }
                return;
            }
            // Garbage between frames, a bad CRC or an unknown message: skipped, as the other transports do.
            Err(_) => continue,
        };
        let chosen = shared.chosen.load(Ordering::SeqCst);
        if chosen == 0 && from_vehicle(&message.0, &message.1, shared.locked.load(Ordering::SeqCst)) {
            if shared
                .chosen
                .compare_exchange(0, number, Ordering::SeqCst, Ordering::SeqCst)
                .is_ok()
            {
                *shared.writer.lock().await = write.take();
                shared.decided.notify_one();
            }
        } else if chosen != number && chosen != 0 {
            return;
        }
        if shared.chosen.load(Ordering::SeqCst) == number && shared.queue.send(Ok(message)).await.is_err() {
            return;
        }
    }
}

impl Transport for TcpInTransport {
    fn send<'a>(&'a self, header: MavHeader, msg: &'a MavMessage) -> BoxFuture<'a, io::Result<()>> {
        Box::pin(async move {
            // As `udpin`: nothing to answer before the vehicle spoke.
            let mut writer = self.shared.writer.lock().await;
            let Some(w) = writer.as_mut() else { return Ok(()) };
            w.write_all(&encode(header, &self.sequence, msg)?).await
        })
    }

    fn recv(&self) -> BoxFuture<'_, io::Result<(MavHeader, MavMessage)>> {
        Box::pin(async move {
            let mut incoming = self.incoming.lock().await;
            match incoming.recv().await {
                Some(message) => message,
                None => Err(io::Error::new(io::ErrorKind::NotConnected, "the TCP listener stopped")),
            }
        })
    }

    fn lock(&self, system_id: u8) {
        self.shared.locked.store(u32::from(system_id), Ordering::SeqCst);
    }
}

#[cfg(test)]
#[path = "tcp_in_tests.rs"]
mod tests;
