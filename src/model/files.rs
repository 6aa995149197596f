//! Reading and writing the model's files: whole UTF-8 reads, and writes that a crash never leaves half done.
//! Both report [`ModelError`]s naming the file, so they live with the model rather than above it.

use std::io::Write;
use std::path::Path;

use super::error::{ModelError, Result};
use super::safe_files::{MAX_READ_BYTES, create_temp_beside, read_capped};

/// Reads a whole file as UTF-8 text, naming the file on failure: a regular file of at most
/// [`MAX_READ_BYTES`], never blocking ([`read_capped`]).
pub(crate) fn read_text(path: &Path) -> Result<String> {
    let bytes = read_capped(path, MAX_READ_BYTES)?;
    String::from_utf8(bytes).map_err(|e| ModelError::Syntax {
        path: path.to_path_buf(),
        line: None,
        column: None,
        message: format!(
            "not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ),
    })
}

/// Writes `bytes` to `path` through a new temporary file in the same folder, synced, then renamed over `path`:
/// a symbolic link at `path` is replaced, never written through, and so is one planted at a temporary name.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let io_err = |source| ModelError::Io {
        path: path.to_path_buf(),
        action: "cannot write",
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(io_err)?;
    let (tmp, mut f) = create_temp_beside(path).map_err(io_err)?;
    let result = (|| {
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}

/// Checks before any work that [`write_atomic`] will be able to write `path`: it is not a folder, and the
/// folder it goes in exists and takes a new file, or can be created under the nearest folder that does.
/// Leaves nothing behind.
pub fn check_writable(path: &Path) -> Result<()> {
    let refuse = |why: &str| ModelError::Io {
        path: path.to_path_buf(),
        action: "cannot write",
        source: std::io::Error::other(why.to_string()),
    };
    if path.is_dir() {
        return Err(refuse("it is a folder; give a file name"));
    }
    let mut dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    while !dir.exists() {
        dir = match dir.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
    }
    if !dir.is_dir() {
        return Err(refuse(&format!("{} is a file, not a folder", dir.display())));
    }
    let probe = dir.join(format!(".prgenuav-write-check.{}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => std::fs::remove_file(&probe).map_err(|source| ModelError::Io {
            path: probe.clone(),
            action: "cannot remove",
            source,
        }),
        Err(e) => Err(refuse(&format!("{} does not take new files ({e})", dir.display()))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_a_file_as_folder_and_a_read_only_folder_are_refused_and_nothing_is_left() {
        let dir = tempfile::tempdir().unwrap();
        check_writable(&dir.path().join("plot.svg")).unwrap();
        check_writable(&dir.path().join("new/deeper/plot.svg")).unwrap();
        assert!(!dir.path().join("new").exists(), "the check creates no folder");
        let e = check_writable(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is a folder"), "{e}");
        std::fs::write(dir.path().join("f"), b"x").unwrap();
        let e = check_writable(&dir.path().join("f/plot.svg")).unwrap_err().to_string();
        assert!(e.contains("is a file, not a folder"), "{e}");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no probe left behind"
        );
    }
}
