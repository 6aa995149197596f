//! Reading and writing the model's files: whole UTF-8 reads, and writes that a crash never leaves half done.
//! Both report [`ModelError`]s naming the file, so they live with the model rather than above it.

use std::io::Write;
use std::path::Path;

use super::error::{ModelError, Result};

/// Reads a whole file as UTF-8 text, naming the file on failure.
pub(crate) fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|source| ModelError::Io {
        path: path.to_path_buf(),
        action: "cannot read",
        source,
    })?;
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

/// Writes `bytes` to `path` through a temporary file in the same folder, synced, then renamed over `path`.
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
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{name}.tmp.{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}
