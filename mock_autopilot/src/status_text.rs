//! STATUSTEXT as PX4 sends it: a text longer than the field's 50 bytes goes out in chunks (MAVLink 2) that
//! share a non-zero `id` and are numbered by `chunk_seq`; every chunk but the last fills the field. A
//! shorter text goes out whole, with id 0.

use mavlink::dialects::common::{MavSeverity, STATUSTEXT_DATA};

/// Bytes of one STATUSTEXT's text field.
pub const FIELD_BYTES: usize = 50;
/// Chunks of one text at most (PX4's own messages need two or three).
pub const MAX_CHUNKS: usize = 8;

/// `text` as STATUSTEXT messages; `id` (non-zero) marks the chunks of a long one. Cut at a character
/// boundary, and after [`MAX_CHUNKS`] chunks.
pub fn chunks(severity: MavSeverity, text: &str, id: u16) -> Vec<STATUSTEXT_DATA> {
    let mut parts = Vec::new();
    let mut rest = text;
    while !rest.is_empty() && parts.len() < MAX_CHUNKS {
        let mut end = rest.len().min(FIELD_BYTES);
        while !rest.is_char_boundary(end) {
            end -= 1;
        }
        parts.push(&rest[..end]);
        rest = &rest[end..];
    }
    if parts.is_empty() {
        parts.push("");
    }
    // A text that ends exactly at a field's end gets an empty last chunk, so the receiver knows it ended.
    let exact = parts.len() > 1 && parts.last().is_some_and(|p| p.len() == FIELD_BYTES) && rest.is_empty();
    if exact && parts.len() < MAX_CHUNKS {
        parts.push("");
    }
    let id = if parts.len() > 1 { id.max(1) } else { 0 };
    parts
        .into_iter()
        .enumerate()
        .map(|(seq, part)| STATUSTEXT_DATA {
            severity,
            text: part.into(),
            id,
            chunk_seq: u8::try_from(seq).unwrap_or(u8::MAX),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: MavSeverity = MavSeverity::MAV_SEVERITY_WARNING;

    #[test]
    fn a_long_text_goes_out_in_chunks_of_one_id() {
        let text = "Arming denied: Resolve system health failures first";
        let c = chunks(W, text, 7);
        assert_eq!(c.len(), 2);
        assert_eq!((c[0].id, c[0].chunk_seq, c[1].id, c[1].chunk_seq), (7, 0, 7, 1));
        assert_eq!(c[0].text.to_str().unwrap().len(), FIELD_BYTES);
        let joined: String = c.iter().map(|m| m.text.to_str().unwrap()).collect();
        assert_eq!(joined, text);
    }

    #[test]
    fn a_short_text_goes_out_whole_and_an_exact_one_ends_with_an_empty_chunk() {
        let c = chunks(W, "Takeoff detected", 3);
        assert_eq!(
            (c.len(), c[0].id, c[0].text.to_str().unwrap()),
            (1, 0, "Takeoff detected")
        );
        let exact = "e".repeat(2 * FIELD_BYTES);
        let c = chunks(W, &exact, 0);
        assert_eq!(c.len(), 3);
        assert!(c.iter().all(|m| m.id == 1), "a chunked text never has id 0");
        assert_eq!(c[2].text.to_str().unwrap(), "");
        let huge = "é".repeat(1000);
        let c = chunks(W, &huge, 9);
        assert_eq!(c.len(), MAX_CHUNKS);
        assert!(c.iter().all(|m| m.text.to_str().is_ok()), "cut at character boundaries");
    }
}
