//! Bytes to and from PX4 over any stream (TCP socket, serial port): a reader task turning frames into
//! events, and an outbox that frames messages and writes them with a deadline.

use std::time::Duration;

use mavlink::dialects::common::MavMessage;
use mavlink::{AsyncMavlinkReader, MAVLinkMessageRaw, Message};
use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

use super::messages::header;

/// A frame from PX4.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Its bytes as received (forwarded untouched by a gateway).
    pub bytes: Vec<u8>,
    /// Its message id.
    pub message_id: u32,
    /// The message, when the common dialect knows it.
    pub message: Option<MavMessage>,
}

/// What the reader saw.
#[derive(Debug, Clone)]
pub enum LinkEvent {
    /// A CRC-valid frame.
    Frame(Box<Frame>),
    /// The stream ended or failed: the reason.
    Closed(String),
}

/// Reads frames (MAVLink 1 or 2) from `source` until it ends; aborting the handle stops it.
pub fn spawn_reader<R>(source: R) -> (mpsc::Receiver<LinkEvent>, JoinHandle<()>)
where
    R: AsyncRead + Unpin + Send + 'static,
{
    let (tx, rx) = mpsc::channel(4096);
    let task = tokio::spawn(async move {
        let mut reader = AsyncMavlinkReader::new(source);
        loop {
            let event = match reader.read_any_raw_message::<MavMessage>().await {
                Ok(raw) => LinkEvent::Frame(Box::new(frame_of(&raw))),
                Err(e) => LinkEvent::Closed(format!("{e:?}")),
            };
            let closed = matches!(event, LinkEvent::Closed(_));
            if tx.send(event).await.is_err() || closed {
                return;
            }
        }
    });
    (rx, task)
}

fn frame_of(raw: &MAVLinkMessageRaw) -> Frame {
    let (bytes, version) = match raw {
        MAVLinkMessageRaw::V1(m) => (m.raw_bytes().to_vec(), mavlink::MavlinkVersion::V1),
        MAVLinkMessageRaw::V2(m) => (m.raw_bytes().to_vec(), mavlink::MavlinkVersion::V2),
    };
    let message_id = raw.message_id();
    Frame {
        message: MavMessage::parse(version, message_id, raw.payload()).ok(),
        bytes,
        message_id,
    }
}

/// Messages framed as MAVLink 2 (system 1, component 200) and written in one go.
#[derive(Debug, Default)]
pub struct Outbox {
    buf: Vec<u8>,
    sequence: u8,
}

impl Outbox {
    /// Frames `msg` into the outbox.
    pub fn push(&mut self, msg: &MavMessage) {
        // Writing into a Vec cannot fail.
        let _ = mavlink::write_v2_msg(&mut self.buf, header(self.sequence), msg);
        self.sequence = self.sequence.wrapping_add(1);
    }

    /// Appends frames received elsewhere untouched (a gateway's traffic).
    pub fn push_raw(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Whether nothing is waiting.
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// Writes everything to `sink` within `deadline`.
    pub async fn flush<W: AsyncWrite + Unpin>(&mut self, sink: &mut W, deadline: Duration) -> Result<(), String> {
        if self.buf.is_empty() {
            return Ok(());
        }
        let write = async {
            sink.write_all(&self.buf).await?;
            sink.flush().await
        };
        let result = match tokio::time::timeout(deadline, write).await {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(format!("write failed: {e}")),
            Err(_) => Err(format!("PX4 took no data for {deadline:?}")),
        };
        self.buf.clear();
        result
    }
}

/// The id of a message (for counters).
pub fn id(msg: &MavMessage) -> u32 {
    msg.message_id()
}
