//! The library and binary stay readable: no source file in `src/` over 450 lines and no function over 60,
//! tests aside (`*_tests.rs`, `tests.rs`, and everything from a file's first `#[cfg(test)]` on).

use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 450;
const MAX_FN_LINES: usize = 60;

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read src").flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if p.is_dir() {
            sources(&p, out);
        } else if name.ends_with(".rs") && !name.ends_with("_tests.rs") && name != "tests.rs" {
            out.push(p);
        }
    }
}

/// The lines before the first `#[cfg(test)]` at the start of a line (the file's test module, if any).
fn code_lines(text: &str) -> Vec<&str> {
    text.lines().take_while(|l| !l.starts_with("#[cfg(test)]")).collect()
}

/// Whether `line` opens a function: optional `pub(...)`, `async`, `const`, `unsafe`, then `fn name`.
fn opens_fn(line: &str) -> Option<&str> {
    let mut rest = line.trim_start();
    if let Some(r) = rest.strip_prefix("pub(in ") {
        rest = r.split_once(") ").map_or(r, |(_, after)| after);
    }
    for prefix in ["pub(crate) ", "pub(super) ", "pub ", "async ", "const ", "unsafe "] {
        rest = rest.strip_prefix(prefix).unwrap_or(rest);
    }
    let name = rest.strip_prefix("fn ")?;
    Some(name.split(['(', '<']).next().unwrap_or(name))
}

/// Every function longer than [`MAX_FN_LINES`] in `lines`: from its `fn` line to the `}` at its indentation.
fn long_functions(lines: &[&str]) -> Vec<(usize, String, usize)> {
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(name) = opens_fn(line) else { continue };
        if line.trim_end().ends_with(';') || line.trim_end().ends_with('}') {
            continue; // a trait method without a body, or a one-line function
        }
        let indent = line.len() - line.trim_start().len();
        let close = format!("{}}}", " ".repeat(indent));
        if let Some(len) = lines[i..].iter().position(|l| l.trim_end() == close).map(|k| k + 1)
            && len > MAX_FN_LINES
        {
            out.push((i + 1, name.to_string(), len));
        }
    }
    out
}

#[test]
fn no_source_file_or_function_is_too_long() {
    let mut files = Vec::new();
    sources(&super::repo().join("src"), &mut files);
    let mut problems = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(&path).expect("read source");
        let lines = code_lines(&text);
        let shown = path.strip_prefix(super::repo()).unwrap_or(&path).display().to_string();
        if lines.len() > MAX_FILE_LINES {
            problems.push(format!("{shown}: {} lines (at most {MAX_FILE_LINES})", lines.len()));
        }
        for (line, name, len) in long_functions(&lines) {
            problems.push(format!(
                "{shown}:{line}: fn {name} has {len} lines (at most {MAX_FN_LINES})"
            ));
        }
    }
    assert!(problems.is_empty(), "split these:\n{}", problems.join("\n"));
}

#[test]
fn the_counter_finds_a_long_function_and_stops_at_its_own_brace() {
    let mut long = vec!["    pub(in crate::x) async fn big(a: u8) {"];
    long.extend(std::iter::repeat_n("        step();", MAX_FN_LINES));
    long.push("    }");
    long.push("    fn small() {}");
    let found = long_functions(&long);
    assert_eq!(found, vec![(1, "big".to_string(), MAX_FN_LINES + 2)]);
    assert_eq!(opens_fn("fn f<T>(x: T)"), Some("f"));
    assert_eq!(opens_fn("let fn_name = 3;"), None);
    assert_eq!(code_lines("a\n#[cfg(test)]\nmod tests {}\n"), vec!["a"]);
}
