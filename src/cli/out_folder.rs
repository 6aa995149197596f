//! A folder a command writes its tests into: it must be new or empty, so no test of an earlier run is
//! mistaken for one of this run; `--force` replaces the earlier run's tests instead.

use std::path::Path;

use anyhow::{Context, bail};

/// Refuses `dir` if it holds anything, unless `force`, which removes the `test_N.yaml` files in it.
pub fn claim(dir: &Path, force: bool) -> anyhow::Result<()> {
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => bail!("--out {}: cannot read the folder ({e})", dir.display()),
    };
    let names: Vec<String> = entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    if names.is_empty() {
        return Ok(());
    }
    if !force {
        bail!(
            "--out {}: the folder already holds {} (e.g. {}); give a new or empty folder, or --force to replace \
             its test_N.yaml files",
            dir.display(),
            prgenuav::campaign::report::user_report::plural(names.len(), "file"),
            names.iter().min().map_or("", String::as_str)
        );
    }
    for name in names.iter().filter(|n| is_test_file(n)) {
        let path = dir.join(name);
        std::fs::remove_file(&path).with_context(|| format!("cannot remove {}", path.display()))?;
    }
    Ok(())
}

/// `test_<digits>.yaml`, the name `sample` writes.
fn is_test_file(name: &str) -> bool {
    (name.strip_prefix("test_").and_then(|r| r.strip_suffix(".yaml")))
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_with_files_is_refused_unless_forced_and_force_removes_only_tests() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("o");
        claim(&out, false).unwrap();
        std::fs::create_dir(&out).unwrap();
        claim(&out, false).unwrap();
        for f in ["test_0.yaml", "test_12.yaml", "notes.txt", "test_x.yaml"] {
            std::fs::write(out.join(f), b"x").unwrap();
        }
        let e = claim(&out, false).unwrap_err().to_string();
        assert!(e.contains("already holds 4 files") && e.contains("--force"), "{e}");
        claim(&out, true).unwrap();
        let mut left: Vec<String> = (std::fs::read_dir(&out).unwrap().flatten())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["notes.txt", "test_x.yaml"]);
    }
}
