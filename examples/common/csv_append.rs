//! Appending an example's rows to a CSV that a later run extends: the header only when the file is new.

use std::fs::File;
use std::path::Path;

/// Opens `dir/name` for appending (creating `dir`), writing `header` first if the file is new.
pub fn append_csv(dir: &Path, name: &str, header: &str) -> std::io::Result<File> {
    use std::io::Write;
    std::fs::create_dir_all(dir)?;
    let path = dir.join(name);
    let fresh = !path.exists();
    let mut f = std::fs::OpenOptions::new().create(true).append(true).open(&path)?;
    if fresh {
        writeln!(f, "{header}")?;
    }
    Ok(f)
}
