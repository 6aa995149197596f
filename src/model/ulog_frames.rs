//! A ULog's framing, checked message by message before the parser reads it. The parser keeps the valid
//! prefix of a damaged log and says only that it stopped early, which would score a cut or bit-flipped log as
//! a shorter flight. Here every message must be whole, of a known type, and shaped as the ULog spec says, so
//! damage is refused naming the byte where it starts. A log cut exactly between two messages cannot be told
//! from a shorter one (ULog has no end marker), as a CSV cut after a row's newline cannot.

use std::collections::HashSet;
use std::fs::File;
use std::io::{BufReader, ErrorKind, Read};
use std::path::Path;

/// The first 7 bytes of every ULog.
const MAGIC: [u8; 7] = *b"ULog\x01\x12\x35";
/// The header: magic, version, timestamp.
const HEADER_BYTES: u64 = 16;
/// The payload of a sync message.
const SYNC_MAGIC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
/// The flag-bits message's size, and its incompat bit saying data was appended.
const FLAG_BITS_BYTES: usize = 40;
const DATA_APPENDED: u8 = 1;

/// Where the framing breaks: the byte offset of the damaged message (or of the end), and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Damage {
    /// Byte offset from the file's start.
    pub offset: u64,
    /// What is wrong there.
    pub why: String,
}

/// The byte offsets where a message starts, and the file's length: for tests that cut a log between messages.
#[derive(Debug, Default)]
pub struct Frames {
    /// Offsets of the message headers, in order.
    pub starts: Vec<u64>,
    /// The file's length.
    pub len: u64,
}

/// Checks the framing of the ULog at `path`; `Ok` with its message boundaries, or where it breaks.
pub fn check_frames(path: &Path) -> std::io::Result<Result<Frames, Damage>> {
    let file = File::open(path)?;
    let len = file.metadata()?.len();
    let mut walk = Walk {
        input: BufReader::with_capacity(1 << 16, file),
        at: 0,
        len,
        ids: HashSet::new(),
        frames: Frames {
            starts: Vec::new(),
            len,
        },
        appended: Vec::new(),
    };
    walk.run()
}

struct Walk<R> {
    input: R,
    at: u64,
    len: u64,
    /// Message ids added (`A`) and not removed (`R`): what a data message may name.
    ids: HashSet<u16>,
    frames: Frames,
    /// Where appended data sections start (flag bits), ascending.
    appended: Vec<u64>,
}

impl<R: Read> Walk<R> {
    fn run(&mut self) -> std::io::Result<Result<Frames, Damage>> {
        let mut header = [0u8; HEADER_BYTES as usize];
        if !self.read(&mut header)? || header[..7] != MAGIC {
            return Ok(Err(damage(0, "not a ULog (no ULog header)")));
        }
        let mut first = true;
        loop {
            let start = self.at;
            if start == self.len {
                return Ok(Ok(std::mem::take(&mut self.frames)));
            }
            let end = self.section_end();
            if end - start < 3 && end < self.len {
                self.skip_to(end)?;
                continue;
            }
            let mut head = [0u8; 3];
            if !self.read(&mut head)? {
                return Ok(Err(self.cut(start, "its message header")));
            }
            let size = usize::from(u16::from_le_bytes([head[0], head[1]]));
            // A section the logger cut before it appended data may end inside a message.
            if start + 3 + size as u64 > end && end < self.len {
                self.skip_to(end)?;
                continue;
            }
            let mut payload = vec![0u8; size];
            if !self.read(&mut payload)? {
                let what = format!("its {size}-byte '{}' message", printable(head[2]));
                return Ok(Err(self.cut(start, &what)));
            }
            self.frames.starts.push(start);
            if let Err(why) = self.message(head[2], &payload, first) {
                return Ok(Err(damage(start, &why)));
            }
            first = false;
        }
    }

    /// Where the section being read ends: the next appended section's start, else the file's end.
    fn section_end(&mut self) -> u64 {
        self.appended.retain(|&o| o > self.at);
        self.appended.first().map_or(self.len, |&o| o.min(self.len))
    }

    /// Reads exactly `buf.len()` bytes; false when the file ends first.
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<bool> {
        match self.input.read_exact(buf) {
            Ok(()) => {
                self.at += buf.len() as u64;
                Ok(true)
            }
            Err(e) if e.kind() == ErrorKind::UnexpectedEof => Ok(false),
            Err(e) => Err(e),
        }
    }

    fn skip_to(&mut self, offset: u64) -> std::io::Result<()> {
        let n = offset.saturating_sub(self.at);
        std::io::copy(&mut self.input.by_ref().take(n), &mut std::io::sink())?;
        self.at = offset;
        Ok(())
    }

    fn cut(&self, start: u64, what: &str) -> Damage {
        damage(
            start,
            &format!("the file ends at byte {}, inside {what}: the log was cut", self.len),
        )
    }

    /// Checks one message's shape; why it is damaged, if it is.
    fn message(&mut self, kind: u8, p: &[u8], first: bool) -> Result<(), String> {
        match kind {
            b'B' if first => self.flag_bits(p),
            b'B' => Err("a second flag-bits message (only the first message may be one)".into()),
            b'F' => text_with(p, b':', "format"),
            b'I' => keyed(p, 0, "info"),
            b'M' => keyed(p, 1, "multi-info"),
            b'P' => keyed(p, 0, "parameter"),
            b'Q' => keyed(p, 1, "parameter default"),
            b'A' => self.add(p),
            b'R' => self.remove(p),
            b'D' => self.data(p),
            b'L' => logged(p, 9),
            b'C' => logged(p, 11),
            b'S' if p == SYNC_MAGIC => Ok(()),
            b'S' => Err("a sync message without the sync bytes".into()),
            b'O' if p.len() == 2 => Ok(()),
            b'O' => Err(format!("a dropout message of {} bytes (2 expected)", p.len())),
            other => Err(format!("unknown message type 0x{other:02x}")),
        }
    }

    fn flag_bits(&mut self, p: &[u8]) -> Result<(), String> {
        if p.len() < FLAG_BITS_BYTES {
            return Err(format!(
                "a flag-bits message of {} bytes ({FLAG_BITS_BYTES} expected)",
                p.len()
            ));
        }
        if p[8] & DATA_APPENDED != 0 {
            let offsets = p[16..40]
                .chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default()));
            self.appended = offsets.filter(|&o| o > 0).collect();
            self.appended.sort_unstable();
        }
        Ok(())
    }

    fn add(&mut self, p: &[u8]) -> Result<(), String> {
        if p.len() < 4 {
            return Err(format!("an add-logged message of {} bytes", p.len()));
        }
        let id = u16::from_le_bytes([p[1], p[2]]);
        name(&p[3..], "add-logged message name")?;
        if !self.ids.insert(id) {
            return Err(format!("message id {id} added twice"));
        }
        Ok(())
    }

    fn remove(&mut self, p: &[u8]) -> Result<(), String> {
        let id = (p.len() == 2).then(|| u16::from_le_bytes([p[0], p[1]]));
        match id {
            Some(id) if self.ids.remove(&id) => Ok(()),
            Some(id) => Err(format!("removes message id {id}, which was never added")),
            None => Err(format!("a remove-logged message of {} bytes (2 expected)", p.len())),
        }
    }

    fn data(&self, p: &[u8]) -> Result<(), String> {
        if p.len() < 2 {
            return Err(format!("a data message of {} bytes", p.len()));
        }
        let id = u16::from_le_bytes([p[0], p[1]]);
        if self.ids.contains(&id) {
            Ok(())
        } else {
            Err(format!(
                "data for message id {id}, which no add-logged message declared"
            ))
        }
    }
}

fn damage(offset: u64, why: &str) -> Damage {
    Damage {
        offset,
        why: why.to_string(),
    }
}

fn printable(kind: u8) -> String {
    if kind.is_ascii_graphic() {
        char::from(kind).to_string()
    } else {
        format!("0x{kind:02x}")
    }
}

/// A key-value message (`I`, `M`, `P`, `Q`): `skip` leading bytes, the key's length, a key `type name`.
fn keyed(p: &[u8], skip: usize, what: &str) -> Result<(), String> {
    let len = p.get(skip).map(|&n| usize::from(n));
    let key = len.and_then(|n| p.get(skip + 1..skip + 1 + n));
    match key {
        Some(k) if k.contains(&b' ') => name(k, &format!("{what} key")),
        Some(k) => Err(format!(
            "a {what} key {:?} without its type",
            String::from_utf8_lossy(k)
        )),
        None => Err(format!("a {what} message whose key runs past its {} bytes", p.len())),
    }
}

/// A logged string (`L`, `C`): a log level '0' to '7' first, then `min` bytes at least.
fn logged(p: &[u8], min: usize) -> Result<(), String> {
    match p.first() {
        _ if p.len() < min => Err(format!("a logged string of {} bytes (at least {min})", p.len())),
        Some(b'0'..=b'7') => Ok(()),
        Some(&l) => Err(format!(
            "a logged string of log level 0x{l:02x} (levels are '0' to '7')"
        )),
        None => Err("an empty logged string".into()),
    }
}

/// Text holding `sep` (a format `name:fields`).
fn text_with(p: &[u8], sep: u8, what: &str) -> Result<(), String> {
    if !p.contains(&sep) {
        return Err(format!("a {what} message without '{}'", char::from(sep)));
    }
    name(p, what)
}

/// Printable ASCII, not empty: names, keys and formats.
fn name(p: &[u8], what: &str) -> Result<(), String> {
    if !p.is_empty() && p.iter().all(|b| b.is_ascii_graphic() || *b == b' ') {
        Ok(())
    } else {
        Err(format!("a {what} that is not text ({:?})", String::from_utf8_lossy(p)))
    }
}

#[cfg(test)]
#[path = "ulog_frames_tests.rs"]
mod tests;
