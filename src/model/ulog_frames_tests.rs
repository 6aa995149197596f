use super::*;

/// A small ULog as PX4 lays it out: header, flag bits, a format, an info, an add-logged, data, a logged string,
/// a sync.
fn log(samples: u64) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    b.push(1);
    b.extend_from_slice(&0u64.to_le_bytes());
    let mut msg = |kind: u8, p: &[u8]| {
        b.extend_from_slice(&(p.len() as u16).to_le_bytes());
        b.push(kind);
        b.extend_from_slice(p);
    };
    msg(b'B', &[0u8; 40]);
    msg(b'F', b"pos:uint64_t timestamp;float x;");
    msg(b'I', b"\x0fchar[3] sys_namePX4");
    msg(b'A', b"\x00\x00\x00pos");
    for i in 0..samples {
        let mut d = vec![0u8, 0];
        d.extend_from_slice(&(i * 100_000).to_le_bytes());
        d.extend_from_slice(&1.5f32.to_le_bytes());
        msg(b'D', &d);
    }
    msg(b'L', b"6\x00\x00\x00\x00\x00\x00\x00\x00hello");
    msg(b'S', &SYNC_MAGIC);
    b
}

fn frames_of(bytes: &[u8]) -> Result<Frames, Damage> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.ulg");
    std::fs::write(&path, bytes).unwrap();
    check_frames(&path).unwrap()
}

#[test]
fn a_whole_log_passes_and_gives_its_message_boundaries() {
    let bytes = log(3);
    let f = frames_of(&bytes).unwrap();
    assert_eq!(f.starts.len(), 9);
    assert_eq!(f.starts[0], HEADER_BYTES);
    assert_eq!(f.len, bytes.len() as u64);
}

#[test]
fn a_cut_log_is_refused_naming_the_message_it_ends_in() {
    let bytes = log(3);
    let starts = frames_of(&bytes).unwrap().starts;
    let cut = starts[5] as usize + 4;
    let d = frames_of(&bytes[..cut]).unwrap_err();
    assert_eq!(d.offset, starts[5]);
    assert!(
        d.why.contains(&format!("ends at byte {cut}")) && d.why.contains("'D'"),
        "{}",
        d.why
    );
    // Cut between two messages: nothing tells it from a shorter log.
    assert!(frames_of(&bytes[..starts[5] as usize]).is_ok());
}

#[test]
fn a_flipped_type_size_or_id_is_refused_where_it_is() {
    let bytes = log(3);
    let starts = frames_of(&bytes).unwrap().starts;
    let at = |i: usize, off: usize| starts[i] as usize + off;
    for (pos, value, says) in [
        (at(4, 2), b'L', "log level"), // a data message read as a logged string
        (at(4, 2), b'Z', "unknown message type"),
        (at(4, 3), 7, "message id 7"), // data naming an id never added
        (at(8, 3), 0, "sync"),
        (at(2, 3), 0, "info key"),
    ] {
        let mut damaged = bytes.clone();
        damaged[pos] = value;
        match frames_of(&damaged) {
            Err(d) => assert!(d.offset <= pos as u64, "{pos}: {d:?}"),
            Ok(_) => panic!("a flip at byte {pos} to {value} ({says}) passed"),
        }
    }
    let mut long = bytes.clone();
    long[at(4, 0)] = 0xff; // a size past the end
    assert!(frames_of(&long).unwrap_err().why.contains("the log was cut"));
    assert!(frames_of(b"not a log at all").unwrap_err().why.contains("not a ULog"));
}
