use std::time::{Duration, Instant};

use super::*;
use crate::model::write_atomic;

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo(3) on a path we own; no memory is shared.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

#[test]
fn a_link_where_a_file_is_written_is_replaced_and_its_target_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim");
    std::fs::write(&victim, "precious").unwrap();
    let atomic = dir.path().join("report.json");
    std::os::unix::fs::symlink(&victim, &atomic).unwrap();
    write_atomic(&atomic, b"{}").unwrap();
    let live = dir.path().join("candidate_1.csv");
    std::os::unix::fs::symlink(&victim, &live).unwrap();
    create_replacing(&live).unwrap();
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert_eq!(std::fs::read_to_string(&atomic).unwrap(), "{}");
    assert!(!std::fs::symlink_metadata(&live).unwrap().file_type().is_symlink());
    let journal = dir.path().join("journal.jsonl");
    std::os::unix::fs::symlink(&victim, &journal).unwrap();
    assert!(
        open_append_no_follow(&journal).is_err(),
        "appending through a link is refused"
    );
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
}

#[test]
fn links_planted_at_temporary_names_are_never_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim");
    std::fs::write(&victim, "precious").unwrap();
    let pid = std::process::id();
    // Every name a simple scheme could pick: the process id with any suffix the writer tries first.
    std::os::unix::fs::symlink(&victim, dir.path().join(format!(".out.json.tmp.{pid}"))).unwrap();
    for _ in 0..3 {
        write_atomic(&dir.path().join("out.json"), b"new").unwrap();
    }
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert_eq!(std::fs::read_to_string(dir.path().join("out.json")).unwrap(), "new");
}

#[test]
fn a_fifo_a_device_a_folder_and_a_big_file_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("t.csv");
    mkfifo(&fifo);
    let t0 = Instant::now();
    let e = read_capped(&fifo, MAX_READ_BYTES).unwrap_err().to_string();
    assert!(e.contains("a FIFO") && e.contains("t.csv"), "{e}");
    let e = read_capped(Path::new("/dev/zero"), MAX_READ_BYTES)
        .unwrap_err()
        .to_string();
    assert!(e.contains("a device"), "{e}");
    let e = read_capped(dir.path(), MAX_READ_BYTES).unwrap_err().to_string();
    assert!(e.contains("a folder"), "{e}");
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    let big = dir.path().join("big");
    std::fs::write(&big, vec![b'x'; 2048]).unwrap();
    let e = read_capped(&big, 1024).unwrap_err().to_string();
    assert!(e.contains("2048 bytes") && e.contains("at most 1024 bytes"), "{e}");
    assert_eq!(read_capped(&big, 4096).unwrap().len(), 2048);
    assert_eq!(read_tail(&big, 10).unwrap(), vec![b'x'; 10]);
}

#[test]
fn a_link_is_read_through_only_when_allowed() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("real"), "r").unwrap();
    std::os::unix::fs::symlink(dir.path().join("real"), dir.path().join("link")).unwrap();
    assert_eq!(read_capped(&dir.path().join("link"), 10).unwrap(), b"r");
    assert!(read_capped_no_follow(&dir.path().join("link"), 10).is_err());
}
