//! `generate --resume` on a journal a crash left damaged: a torn last line is dropped and flown again; damage
//! elsewhere stops the resume naming the line. A campaign path JSON cannot hold is refused up front.

use std::path::{Path, PathBuf};

use super::prgenuav;

/// A small mock campaign of 3 flights; returns its folder.
fn campaign(out: &Path) -> PathBuf {
    let args = [
        "generate",
        "missions/mission2.yaml",
        "3",
        "--seed",
        "0",
        "--candidates",
        "6",
        "--mode",
        "mission",
        "--mock-speed",
        "10",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    let (code, stdout, stderr) = prgenuav(&args);
    assert_eq!(code, 0, "{stderr}");
    folder_of(&stdout)
}

fn folder_of(stdout: &str) -> PathBuf {
    let last = stdout.lines().last().unwrap_or_default();
    PathBuf::from(last.trim_start_matches("output folder:").trim())
}

fn candidates(journal: &str) -> Vec<u64> {
    journal
        .lines()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).unwrap()["candidate"]
                .as_u64()
                .unwrap()
        })
        .collect()
}

#[test]
fn a_torn_last_line_is_dropped_on_resume_and_that_flight_flown_again() {
    let out = tempfile::tempdir().unwrap();
    let folder = campaign(out.path());
    let path = folder.join("journal.jsonl");
    let whole = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = whole.lines().collect();
    assert_eq!(lines.len(), 3, "{whole}");
    let kept = format!("{}\n{}\n", lines[0], lines[1]);
    std::fs::write(&path, format!("{kept}{}", &lines[2][..lines[2].len() / 2])).unwrap();

    let (code, _, stderr) = prgenuav(&["generate", "--resume", folder.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("journal.jsonl:3: dropped a torn last line"), "{stderr}");
    let healed = std::fs::read_to_string(&path).unwrap();
    assert!(healed.starts_with(&kept), "the whole records stay as they were");
    assert_eq!(candidates(&healed).len(), 3, "one flight flown again: {healed}");
    assert!(healed.ends_with('\n'));
    // A resume re-plans from the journal, so the slot may go to another candidate than the torn one; it
    // must be the one a campaign killed just before that write would fly.
    std::fs::write(&path, &kept).unwrap();
    let (code, _, stderr) = prgenuav(&["generate", "--resume", folder.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("dropped"), "{stderr}");
    assert_eq!(
        candidates(&std::fs::read_to_string(&path).unwrap()),
        candidates(&healed)
    );
}

#[test]
fn a_damaged_middle_line_or_a_candidate_twice_stops_the_resume_naming_the_lines() {
    let out = tempfile::tempdir().unwrap();
    let folder = campaign(out.path());
    let path = folder.join("journal.jsonl");
    let whole = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = whole.lines().collect();
    for (text, needles) in [
        (
            format!("{}\n{{\"cand\n{}\n", lines[0], lines[2]),
            vec!["journal.jsonl:2", "not a journal record", "delete this line"],
        ),
        (
            format!("{}\n{}\n{}\n", lines[0], lines[1], lines[0]),
            vec!["journal.jsonl:3", "lines 1 and 3", "journaled twice"],
        ),
    ] {
        std::fs::write(&path, &text).unwrap();
        let (code, _, stderr) = prgenuav(&["generate", "--resume", folder.to_str().unwrap(), "--quiet"]);
        assert_eq!(code, 2, "{stderr}");
        for n in needles {
            assert!(stderr.contains(n), "{n}: {stderr}");
        }
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            text,
            "the journal is left as it was"
        );
    }
}

#[cfg(unix)]
#[test]
fn a_case_path_that_is_not_utf8_is_refused_before_any_file_is_written() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join(std::ffi::OsStr::from_bytes(b"mission\xff.yaml"));
    std::fs::copy(super::repo().join("missions/mission2.yaml"), &case).unwrap();
    let out = dir.path().join("out");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .arg("generate")
        .arg(&case)
        .args(["1", "--quiet", "--out"])
        .arg(&out)
        .current_dir(super::repo())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("mission") && stderr.contains("not UTF-8"), "{stderr}");
    let written = walk(&out);
    assert!(written.iter().all(|p| !p.ends_with("campaign.json")), "{written:?}");
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .flatten()
        .flat_map(|e| {
            let p = e.path();
            if p.is_dir() { walk(&p) } else { vec![p] }
        })
        .collect()
}
