//! File helpers for the layers above the model. The atomic writer lives in the model (its errors are
//! [`crate::model::ModelError`]s, and the model writes tests with it); this path keeps it at hand for the rest.

use std::path::Path;

use serde::Serialize;

use crate::model::ModelError;
pub use crate::model::{check_writable, write_atomic};

/// Writes `value` as JSON (indented when `pretty`) through [`write_atomic`]. A value JSON cannot hold (such as
/// a path that is not UTF-8) is an error naming the file, and nothing is written.
pub fn write_json<T: Serialize>(path: &Path, value: &T, pretty: bool) -> Result<(), ModelError> {
    let json = if pretty {
        serde_json::to_string_pretty(value)
    } else {
        serde_json::to_string(value)
    };
    let json = json.map_err(|e| ModelError::Syntax {
        path: path.to_path_buf(),
        line: None,
        column: None,
        message: format!("cannot be written as JSON: {e}"),
    })?;
    write_atomic(path, json.as_bytes())
}

/// FNV-1a of `bytes` from an offset basis mixed with `seed` (seed 0: the standard FNV-1a): a hash that stays
/// the same across runs, platforms and Rust versions, as file names and fold assignments must (the std
/// hasher does not).
pub fn fnv1a(bytes: &[u8], seed: u64) -> u64 {
    let basis = 0xcbf2_9ce4_8422_2325_u64 ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    bytes
        .iter()
        .fold(basis, |h, b| (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3))
}

#[cfg(test)]
mod hash_tests {
    use super::fnv1a;

    #[test]
    fn seed_zero_is_the_standard_fnv1a() {
        assert_eq!(fnv1a(b"", 0), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a", 0), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar", 0), 0x8594_4171_f739_67e8);
        assert_ne!(fnv1a(b"a", 1), fnv1a(b"a", 0));
    }
}

#[cfg(all(test, unix))]
mod tests {
    use std::os::unix::ffi::OsStrExt;
    use std::path::PathBuf;

    use super::*;

    #[test]
    fn a_value_json_cannot_hold_is_an_error_and_no_file_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("campaign.json");
        let bad = PathBuf::from(std::ffi::OsStr::from_bytes(b"case\xff.yaml"));
        let e = write_json(&path, &bad, true).unwrap_err().to_string();
        assert!(
            e.contains("campaign.json") && e.contains("cannot be written as JSON"),
            "{e}"
        );
        assert!(
            std::fs::read_dir(dir.path()).unwrap().next().is_none(),
            "not even a temporary file"
        );
        write_json(&path, &PathBuf::from("case.yaml"), false).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "\"case.yaml\"");
    }
}
