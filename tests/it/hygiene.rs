//! The repository speaks of itself only: no work-log numbering (a session or an issue followed by its
//! number) in any source, document or test name.

use std::path::{Path, PathBuf};

/// Folders that hold no prose or code of ours.
const SKIPPED: &[&str] = &["target", ".git", "proptest-regressions"];

/// Text files of the repository that people read: sources, docs, manifests, scripts.
fn text_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read dir").flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if p.is_dir() {
            if !SKIPPED.contains(&name.as_str()) {
                text_files(&p, out);
            }
        } else if ["rs", "md", "toml", "yml", "yaml", "sh", "py"]
            .iter()
            .any(|x| name.ends_with(&format!(".{x}")))
            || name == "run"
        {
            out.push(p);
        }
    }
}

/// Where `text` names a numbered session or issue (either word, any case, plural, then an optional `#` and
/// a digit), as byte offsets.
fn numbered_refs(text: &str) -> Vec<usize> {
    let lower = text.to_ascii_lowercase();
    let bytes = lower.as_bytes();
    let mut out = Vec::new();
    for word in ["session", "issue"] {
        for (i, _) in lower.match_indices(word) {
            if i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_') {
                continue;
            }
            let mut j = i + word.len();
            if bytes.get(j) == Some(&b's') {
                j += 1;
            }
            while bytes.get(j).is_some_and(|b| *b == b' ' || *b == b'_' || *b == b'-') {
                j += 1;
            }
            if bytes.get(j) == Some(&b'#') {
                j += 1;
            }
            if bytes.get(j).is_some_and(u8::is_ascii_digit) {
                out.push(i);
            }
        }
    }
    out
}

#[test]
fn no_file_names_a_numbered_session_or_issue() {
    let root = super::repo();
    let mut files = Vec::new();
    text_files(&root, &mut files);
    assert!(files.len() > 100, "read too few files: {}", files.len());
    let mut hits = Vec::new();
    for f in files {
        let Ok(text) = std::fs::read_to_string(&f) else {
            continue;
        };
        for at in numbered_refs(&text) {
            let line = text[..at].matches('\n').count() + 1;
            let rel = f.strip_prefix(&root).unwrap_or(&f).display().to_string();
            hits.push(format!(
                "{rel}:{line}: {}",
                text.lines().nth(line - 1).unwrap_or("").trim()
            ));
        }
    }
    assert!(hits.is_empty(), "numbered sessions or issues:\n{}", hits.join("\n"));
}

#[test]
fn the_check_finds_numbered_references_and_nothing_else() {
    // Built at run time so that this file does not match itself.
    let (s, i) = ("Session", "issue");
    assert_eq!(numbered_refs(&format!("as {s} 4 found")).len(), 1);
    assert_eq!(numbered_refs(&format!("{i} #13, {i}s 12-13")).len(), 2);
    assert_eq!(numbered_refs(&format!("fn {}_11_table()", s.to_lowercase())).len(), 1);
    assert!(numbered_refs("bridge::session::flight, the session 's link, issue a command").is_empty());
    assert!(numbered_refs("subsession 3, tissue 4").is_empty());
}
