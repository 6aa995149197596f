//! Opening files so that a file planted by someone else cannot turn a read or a write against the user: writes
//! never follow a symbolic link (a link where a file is written is replaced, not written through), and reads
//! take regular files only, of a bounded size, without ever blocking (a FIFO or a device is refused at once).

use std::fs::{File, OpenOptions};
use std::io::{ErrorKind, Read, Seek, SeekFrom};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

use super::error::{ModelError, Result};

/// The largest file read back (test YAML, plan, trajectory CSV, journal, JSON, log): far above any real one (a
/// ten-minute flight at 100 Hz is about 2 MB), far below what exhausts memory.
pub const MAX_READ_BYTES: u64 = 64 << 20;

/// The largest PX4 flight log read (logs hold every topic, so they are far larger than trajectories).
pub const MAX_ULOG_BYTES: u64 = 512 << 20;

/// How many temporary names [`create_temp_beside`] tries before giving up (each is taken only if new).
const TEMP_TRIES: u32 = 64;

/// Reads `path` whole: a regular file (symbolic links to one are followed) of at most `cap` bytes. A FIFO,
/// socket, device or folder is refused without blocking, as is a larger file, naming the file and the rule.
pub fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>> {
    read_with(path, cap, 0)
}

/// [`read_capped`], but a symbolic link at `path` is refused rather than followed: for files of a folder that
/// must not lead out of it.
pub fn read_capped_no_follow(path: &Path, cap: u64) -> Result<Vec<u8>> {
    read_with(path, cap, libc::O_NOFOLLOW)
}

fn read_with(path: &Path, cap: u64, flags: libc::c_int) -> Result<Vec<u8>> {
    let io = |source| ModelError::Io {
        path: path.to_path_buf(),
        action: "cannot read",
        source,
    };
    // O_NONBLOCK: opening a FIFO with no writer would otherwise wait forever.
    let mut file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY | flags)
        .open(path)
        .map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    let kind = meta.file_type();
    if !kind.is_file() {
        let what = if kind.is_dir() {
            "a folder"
        } else if kind.is_fifo() {
            "a FIFO"
        } else if kind.is_char_device() || kind.is_block_device() {
            "a device"
        } else {
            "not a regular file"
        };
        return Err(io(std::io::Error::other(format!(
            "it is {what}; only regular files are read"
        ))));
    }
    if meta.len() > cap {
        return Err(io(too_big(meta.len(), cap)));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // The file may grow while read: never past the cap.
    file.by_ref().take(cap + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > cap {
        return Err(io(too_big(bytes.len() as u64, cap)));
    }
    Ok(bytes)
}

/// The last `n` bytes (or fewer) of the regular file `path`, without reading the rest; refused as
/// [`read_capped`] refuses what is not a regular file.
pub fn read_tail(path: &Path, n: u64) -> Result<Vec<u8>> {
    let io = |source| ModelError::Io {
        path: path.to_path_buf(),
        action: "cannot read",
        source,
    };
    let mut file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(io(std::io::Error::other(
            "not a regular file; only regular files are read",
        )));
    }
    file.seek(SeekFrom::Start(meta.len().saturating_sub(n))).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(n).read_to_end(&mut bytes).map_err(io)?;
    Ok(bytes)
}

fn too_big(len: u64, cap: u64) -> std::io::Error {
    std::io::Error::other(format!(
        "it is {len} bytes or more; files read are at most {cap} bytes ({} MiB)",
        cap >> 20
    ))
}

/// Creates `path` afresh for writing: whatever is there that is not a folder (a file, or a symbolic link
/// planted there) is removed first, and the new file is created exclusively, so a link put back in between is
/// refused rather than followed.
pub fn create_replacing(path: &Path) -> std::io::Result<File> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => {
            return Err(std::io::Error::other(format!(
                "{} is a folder, not a file",
                path.display()
            )));
        }
        Ok(_) => std::fs::remove_file(path)?,
        Err(e) if e.kind() == ErrorKind::NotFound => {}
        Err(e) => return Err(e),
    }
    create_new_no_follow(path)
}

/// Opens `path` for appending, creating it if missing; a symbolic link there is refused, not followed.
pub fn open_append_no_follow(path: &Path) -> std::io::Result<File> {
    OpenOptions::new()
        .create(true)
        .append(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)
}

/// A new file beside `path` (same folder, so a rename over `path` is atomic), named after it, never one that
/// existed: the name is taken only by creating it.
pub(crate) fn create_temp_beside(path: &Path) -> std::io::Result<(PathBuf, File)> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let pid = std::process::id();
    let salt = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    for k in 0..TEMP_TRIES {
        let tmp = dir.join(format!(".{name}.tmp.{pid}.{:x}", salt.wrapping_add(k)));
        match create_new_no_follow(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::other(format!(
        "{}: {TEMP_TRIES} temporary names beside it are all taken",
        path.display()
    )))
}

fn create_new_no_follow(path: &Path) -> std::io::Result<File> {
    OpenOptions::new()
        .write(true)
        .create_new(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)
}

#[cfg(test)]
#[path = "safe_files_tests.rs"]
mod tests;
