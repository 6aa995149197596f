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

/// The public types (`pub struct`, `enum`, `trait`, `type`) declared in `text`, by name, and those a
/// settings section declares (`section! { Name, NameAsked, "section", ... }`); a macro's own template
/// (`pub struct $name`) names none.
fn public_types(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut in_section = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("section! {") {
            in_section = true;
        } else if in_section && !t.starts_with("///") {
            names.extend(
                t.split(',')
                    .take(2)
                    .map(|n| n.trim().to_string())
                    .filter(|n| !n.is_empty()),
            );
            in_section = false;
        }
        for kind in ["pub struct ", "pub enum ", "pub trait ", "pub type "] {
            if let Some(rest) = t.strip_prefix(kind) {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    names.push(name);
                }
            }
        }
    }
    names
}

/// Two public types of one name in one crate make a reader check the import to know which is meant.
#[test]
fn no_two_public_types_of_the_main_crate_share_a_name() {
    let mut files = Vec::new();
    text_files(&super::repo().join("src"), &mut files);
    let mut seen: std::collections::BTreeMap<String, Vec<PathBuf>> = Default::default();
    for f in files.iter().filter(|f| f.extension().is_some_and(|x| x == "rs")) {
        let text = std::fs::read_to_string(f).expect("read");
        for name in public_types(&text) {
            seen.entry(name).or_default().push(f.clone());
        }
    }
    let shared: Vec<_> = seen.iter().filter(|(_, at)| at.len() > 1).collect();
    assert!(shared.is_empty(), "public types sharing a name: {shared:#?}");
}

#[test]
fn the_type_scan_finds_declarations_and_not_their_uses() {
    let text = "pub struct A {\n    pub(crate) enum B,\n  pub enum C<T> {}\npub trait D: Send {}\nlet x: pub_struct;\n";
    assert_eq!(public_types(text), ["A", "C", "D"]);
}
