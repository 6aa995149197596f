//! A STATUSTEXT longer than the field's 50 characters arrives in chunks (MAVLink 2): they share a non-zero
//! `id`, are numbered by `chunk_seq` from 0, and every chunk but the last fills the field. PX4 sends its longer
//! refusals that way ("Arming denied: Resolve system health failures first"); read one message at a time, they
//! would be two warnings cut mid-word. This joins them back.

use mavlink::dialects::common::{MavSeverity, STATUSTEXT_DATA};

/// Characters of one STATUSTEXT's text field.
pub const FIELD_CHARS: usize = 50;
/// A text joined from chunks is cut here: a sender that never ends its chunks cannot grow it without bound.
const MAX_JOINED_CHARS: usize = 20 * FIELD_CHARS;

/// One chunk of a STATUSTEXT, as received.
#[derive(Debug, Clone, Copy)]
pub struct Chunk<'a> {
    /// Its severity.
    pub severity: MavSeverity,
    /// 0 for a text that came whole; else shared by the chunks of one text.
    pub id: u16,
    /// The chunk's number within its text.
    pub seq: u8,
    /// The text up to its first NUL.
    pub text: &'a str,
    /// Whether the text filled the field (no NUL): more chunks may follow.
    pub full: bool,
}

impl<'a> Chunk<'a> {
    /// The chunk a received STATUSTEXT carries; `None` when its text is not UTF-8.
    pub fn of(t: &'a STATUSTEXT_DATA) -> Option<Self> {
        let text = t.text.to_str().ok()?;
        Some(Chunk {
            severity: t.severity,
            id: t.id,
            seq: t.chunk_seq,
            text,
            full: text.len() == FIELD_CHARS,
        })
    }
}

/// A text being joined.
#[derive(Debug, Clone, PartialEq)]
struct Pending {
    id: u16,
    next: u8,
    severity: MavSeverity,
    text: String,
}

/// The chunks received so far of a text not yet whole.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Joiner {
    pending: Option<Pending>,
}

impl Joiner {
    /// Takes one STATUSTEXT; returns the texts it completes, oldest first: a pending text that `chunk` does
    /// not continue (its end was lost) comes out as it is, before `chunk`'s own.
    pub fn feed(&mut self, chunk: Chunk<'_>) -> Vec<(MavSeverity, String)> {
        let mut out = Vec::new();
        let continues = self
            .pending
            .as_ref()
            .is_some_and(|p| chunk.id != 0 && p.id == chunk.id && p.next == chunk.seq);
        if continues {
            if let Some(p) = self.pending.as_mut() {
                p.text.push_str(chunk.text);
                p.next = p.next.wrapping_add(1);
            }
        } else {
            out.extend(self.flush());
            self.pending = Some(Pending {
                id: chunk.id,
                next: chunk.seq.wrapping_add(1),
                severity: chunk.severity,
                text: chunk.text.to_string(),
            });
        }
        let open = chunk.id != 0 && chunk.full;
        if !open || self.pending.as_ref().is_some_and(|p| p.text.len() >= MAX_JOINED_CHARS) {
            out.extend(self.flush());
        }
        out
    }

    /// The text being joined, as far as it came, if any (called when no more chunk came in time).
    pub fn flush(&mut self) -> Option<(MavSeverity, String)> {
        self.pending.take().map(|p| (p.severity, p.text))
    }

    /// Whether a text waits for more chunks.
    pub fn waiting(&self) -> bool {
        self.pending.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: MavSeverity = MavSeverity::MAV_SEVERITY_WARNING;

    fn chunk(id: u16, seq: u8, text: &str) -> Chunk<'_> {
        Chunk {
            severity: W,
            id,
            seq,
            text,
            full: text.len() == FIELD_CHARS,
        }
    }

    fn texts(v: Vec<(MavSeverity, String)>) -> Vec<String> {
        v.into_iter().map(|(_, t)| t).collect()
    }

    #[test]
    fn chunks_of_one_id_are_joined_and_whole_texts_pass_at_once() {
        let mut j = Joiner::default();
        let first = "Arming denied: Resolve system health failures firs";
        assert_eq!(first.len(), FIELD_CHARS);
        assert!(j.feed(chunk(7, 0, first)).is_empty() && j.waiting());
        assert_eq!(
            texts(j.feed(chunk(7, 1, "t"))),
            ["Arming denied: Resolve system health failures first"]
        );
        assert!(!j.waiting());
        assert_eq!(texts(j.feed(chunk(0, 0, "Takeoff detected"))), ["Takeoff detected"]);
        // A full text without an id is whole: nothing can follow it.
        let full = "x".repeat(FIELD_CHARS);
        assert_eq!(texts(j.feed(chunk(0, 0, &full))), [full]);
    }

    #[test]
    fn a_text_whose_end_was_lost_still_comes_out() {
        let mut j = Joiner::default();
        let full = "y".repeat(FIELD_CHARS);
        assert!(j.feed(chunk(3, 0, &full)).is_empty());
        // Another text, or a chunk out of order, ends the first as it is.
        assert_eq!(texts(j.feed(chunk(0, 0, "next"))), [full.clone(), "next".into()]);
        assert!(j.feed(chunk(4, 0, &full)).is_empty());
        assert_eq!(texts(j.feed(chunk(4, 2, "z"))), [full.clone(), "z".into()]);
        assert!(j.feed(chunk(5, 0, &full)).is_empty());
        assert_eq!(j.flush().map(|(_, t)| t), Some(full.clone()));
        assert_eq!(j.flush(), None);
    }

    #[test]
    fn an_endless_text_is_cut() {
        let mut j = Joiner::default();
        let full = "w".repeat(FIELD_CHARS);
        let mut out = Vec::new();
        for seq in 0..=255u8 {
            out.extend(texts(j.feed(chunk(9, seq, &full))));
        }
        assert!(
            !out.is_empty() && out.iter().all(|t| t.len() <= MAX_JOINED_CHARS),
            "{out:?}"
        );
    }
}
