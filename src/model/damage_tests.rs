//! Every reader of a flight treats damage alike: a cut or corrupted ULog or CSV is refused naming the file
//! and where, or read whole; never read as a shorter flight. A file cut exactly between two messages (ULog)
//! or after a row's newline (CSV) is the one cut nothing can tell from a shorter file.

use std::path::{Path, PathBuf};

use proptest::prelude::*;

use super::ulog_frames::check_frames;
use super::{Sample, Trajectory, load_flight};

fn standin_ulog() -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/aerialist-standin/flight.ulg");
    std::fs::read(path).unwrap()
}

fn flight_csv() -> Vec<u8> {
    let samples = (0..300)
        .map(|i| Sample {
            t_s: f64::from(i) * 0.1,
            x: f64::from(i) * 0.17,
            y: 3.25,
            z: 10.0,
            r: Some(0.125),
        })
        .collect();
    Trajectory::new(samples).to_csv().into_bytes()
}

/// `bytes` as a file named `name`: (its folder, kept alive, and its path).
fn file(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

/// What reading `bytes` as `name` gives: the number of samples, or the error.
fn read(name: &str, bytes: &[u8]) -> Result<usize, String> {
    let (_dir, path) = file(name, bytes);
    load_flight(&path).map(|t| t.samples.len()).map_err(|e| e.to_string())
}

/// Where `bytes` may be cut without damage showing: a ULog's message starts, a CSV's line starts.
fn boundaries(name: &str, bytes: &[u8]) -> Vec<usize> {
    if name.ends_with(".ulg") {
        let (_dir, path) = file(name, bytes);
        let frames = check_frames(&path).unwrap().unwrap();
        frames.starts.iter().map(|&s| s as usize).collect()
    } else {
        (0..bytes.len()).filter(|&i| i > 0 && bytes[i - 1] == b'\n').collect()
    }
}

fn check_cut(name: &str, bytes: &[u8], at: usize, whole: usize) -> Result<(), TestCaseError> {
    match read(name, &bytes[..at]) {
        Err(e) => prop_assert!(e.contains(name), "{e}"),
        Ok(n) => {
            let between = boundaries(name, bytes).contains(&at);
            prop_assert!(
                between || n == whole,
                "cut at {at} of {}: {n} of {whole} samples",
                bytes.len()
            );
        }
    }
    Ok(())
}

fn check_flip(name: &str, bytes: &[u8], at: usize, to: u8, whole: usize) -> Result<(), TestCaseError> {
    let mut damaged = bytes.to_vec();
    prop_assume!(damaged[at] != to);
    damaged[at] = to;
    match read(name, &damaged) {
        Err(e) => prop_assert!(e.contains(name), "{e}"),
        Ok(n) => prop_assert_eq!(n, whole, "byte {} set to {}: a shorter flight", at, to),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn a_cut_ulog_is_refused_or_read_whole(frac in 0.0..1.0f64) {
        let bytes = standin_ulog();
        let whole = read("f.ulg", &bytes).unwrap();
        check_cut("f.ulg", &bytes, ((bytes.len() - 1) as f64 * frac) as usize + 1, whole)?;
    }

    #[test]
    fn a_corrupted_ulog_is_refused_or_read_whole(frac in 0.0..1.0f64, to in any::<u8>()) {
        let bytes = standin_ulog();
        let whole = read("f.ulg", &bytes).unwrap();
        check_flip("f.ulg", &bytes, ((bytes.len() - 1) as f64 * frac) as usize, to, whole)?;
    }

    #[test]
    fn a_cut_csv_is_refused_or_read_whole(frac in 0.0..1.0f64) {
        let bytes = flight_csv();
        check_cut("f.csv", &bytes, ((bytes.len() - 1) as f64 * frac) as usize + 1, 300)?;
    }

    #[test]
    fn a_corrupted_csv_is_refused_or_read_whole(frac in 0.0..1.0f64, to in any::<u8>()) {
        let bytes = flight_csv();
        check_flip("f.csv", &bytes, ((bytes.len() - 1) as f64 * frac) as usize, to, 300)?;
    }
}

#[test]
fn a_ulog_cut_to_50_kb_is_refused_naming_the_byte() {
    let bytes = standin_ulog();
    let e = read("flight.ulg", &bytes[..50_000]).unwrap_err();
    assert!(
        e.contains("flight.ulg") && e.contains("damaged ULog at byte") && e.contains("cut"),
        "{e}"
    );
}
