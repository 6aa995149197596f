use std::time::{Duration, Instant};

use crate::campaign::ground::flight_status::FlightStatus;
use proptest::prelude::*;

use super::*;
use crate::model::Obstacle;

/// A ULog with `vehicle_local_position` samples (t µs, x, y, z down) from the ULog spec's message layout.
pub(crate) fn ulog(samples: &[(u64, f32, f32, f32)]) -> Vec<u8> {
    let mut b = b"ULog\x01\x12\x35\x01".to_vec();
    b.extend_from_slice(&0u64.to_le_bytes());
    let msg = |b: &mut Vec<u8>, kind: u8, payload: &[u8]| {
        b.extend_from_slice(&(payload.len() as u16).to_le_bytes());
        b.push(kind);
        b.extend_from_slice(payload);
    };
    msg(&mut b, b'B', &[0u8; 40]);
    msg(
        &mut b,
        b'F',
        b"vehicle_local_position:uint64_t timestamp;float x;float y;float z;float heading;",
    );
    let mut add = vec![0u8, 0, 0];
    add.extend_from_slice(b"vehicle_local_position");
    msg(&mut b, b'A', &add);
    for &(t, x, y, z) in samples {
        let mut d = 0u16.to_le_bytes().to_vec();
        d.extend_from_slice(&t.to_le_bytes());
        for v in [x, y, z, 0.0f32] {
            d.extend_from_slice(&v.to_le_bytes());
        }
        msg(&mut b, b'D', &d);
    }
    b
}

/// A straight pass North from home at 5 m, 3 m beside a box centred 20 m North.
fn pass() -> Vec<(u64, f32, f32, f32)> {
    (0..200)
        .map(|i| (1_000_000 + i * 100_000, i as f32 * 0.25, 0.0, -5.0))
        .collect()
}

fn obstacles() -> Vec<Obstacle> {
    vec![Obstacle::new(2.0, 2.0, 20.0, 20.0, 3.0, 0.0)]
}

fn read(dir: &Path, stdout: &[u8]) -> Result<Readback, String> {
    read_back(dir, &[], stdout, &obstacles(), Judge::E2026)
}

#[test]
fn an_aerialist_ulog_deep_in_the_folder_is_judged() {
    let tmp = tempfile::tempdir().unwrap();
    let logs = tmp.path().join("results/logs/01-02-03-04-05");
    std::fs::create_dir_all(&logs).unwrap();
    std::fs::write(logs.join("01-02-03-04-05_0123456789ab.ulg"), ulog(&pass())).unwrap();
    let b = read(tmp.path(), b"entry - INFO - LOG:results/logs/x.ulg\n").unwrap();
    assert_eq!(b.flown.status, FlightStatus::LANDED);
    assert!(!b.reported);
    let d = b.flown.min_distance.unwrap();
    // 3 m beside a 2 m wide box: 2 m to its side, less the 2026 edition's buffer.
    assert!((0.5..2.1).contains(&d), "{d}");
    assert!((b.flown.flight_time_s - 19.9).abs() < 1e-6);
    let t = b.trajectory.unwrap();
    assert_eq!(t.samples[0].x, 0.0, "origin-aligned");
}

#[test]
fn a_trajectory_csv_is_judged_and_a_collision_named() {
    let tmp = tempfile::tempdir().unwrap();
    let mut csv = String::from("timestamp,x,y,z,r\n");
    for i in 0..100 {
        csv += &format!(
            "{},{},{},5,\n",
            i * 100_000,
            i as f64 * 0.4,
            if i == 0 { 0.0 } else { 3.5 }
        );
    }
    std::fs::write(tmp.path().join("flight.csv"), csv).unwrap();
    std::fs::write(tmp.path().join("commands.csv"), "command,x\n1,2\n").unwrap();
    let b = read(tmp.path(), b"").unwrap();
    assert_eq!(b.flown.status, FlightStatus::COLLISION);
    assert!(b.flown.reason.unwrap().contains("entered obstacle 0"));
    assert_eq!(b.flown.min_distance, Some(0.0));
}

#[test]
fn a_fly_report_on_stdout_gives_the_ending() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("t.ulg"), ulog(&pass())).unwrap();
    let out = br#"waiting...
{
  "status": "timeout",
  "reason": "still flying at 500 s",
  "warnings": ["planner slow"],
  "flight_time_s": 500.0,
  "min_distance": 99.0
}
"#;
    let b = read(tmp.path(), out).unwrap();
    assert_eq!(b.flown.status, FlightStatus::TIMEOUT);
    assert!(b.reported);
    assert_eq!(b.flown.warnings, vec!["planner slow".to_string()]);
    assert_eq!(b.flown.flight_time_s, 500.0);
    assert!(b.flown.min_distance.unwrap() < 3.0, "judged here, not the report's 99");
}

#[test]
fn a_rejected_flight_without_a_trajectory_is_a_result() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("report.json"),
        r#"{"status": "rejected", "reason": "arming refused", "flight_time_s": 0}"#,
    )
    .unwrap();
    let b = read(tmp.path(), b"").unwrap();
    assert_eq!((b.flown.status.as_str(), b.flown.min_distance), ("rejected", None));
    // But a landed report alone cannot be judged.
    std::fs::write(tmp.path().join("report.json"), r#"{"status": "landed"}"#).unwrap();
    let e = read(tmp.path(), b"").unwrap_err();
    assert!(e.contains("no trajectory") && e.contains("landed"), "{e}");
}

#[test]
fn garbage_empty_and_truncated_outputs_are_errors_that_say_why() {
    let tmp = tempfile::tempdir().unwrap();
    let e = read(tmp.path(), b"").unwrap_err();
    assert!(e.contains("no flight log"), "{e}");
    std::fs::write(tmp.path().join("empty.ulg"), b"").unwrap();
    let e = read(tmp.path(), b"").unwrap_err();
    assert!(e.contains("empty.ulg"), "{e}");
    std::fs::remove_file(tmp.path().join("empty.ulg")).unwrap();
    std::fs::write(tmp.path().join("junk.ulg"), b"\x00\xffnot a log at all").unwrap();
    let e = read(tmp.path(), b"{garbage").unwrap_err();
    assert!(e.contains("junk.ulg"), "{e}");
    std::fs::remove_file(tmp.path().join("junk.ulg")).unwrap();
    let header_only = ulog(&[]);
    std::fs::write(tmp.path().join("nodata.ulg"), header_only).unwrap();
    assert!(read(tmp.path(), b"").is_err());
    std::fs::remove_file(tmp.path().join("nodata.ulg")).unwrap();
    std::fs::write(tmp.path().join("t.csv"), "timestamp,x,y,z,r\n0,1,2,3,\n100000,1.5,2").unwrap();
    let e = read(tmp.path(), b"").unwrap_err();
    assert!(e.contains("t.csv:3") && e.contains("cut mid-row"), "{e}");
}

#[test]
fn the_jobs_own_inputs_are_not_output() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("in.csv");
    std::fs::write(&input, "timestamp,x,y,z\n0,0,0,0\n").unwrap();
    let e = read_back(
        tmp.path(),
        std::slice::from_ref(&input),
        b"",
        &obstacles(),
        Judge::E2026,
    )
    .unwrap_err();
    assert!(e.contains("no flight log"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Whatever bytes a job leaves (as a ULog, a CSV, a JSON file and its stdout), reading back ends quickly
    /// with a flight or an error, never a panic.
    #[test]
    fn any_job_output_reads_back_without_panicking(
        bytes in proptest::collection::vec(any::<u8>(), 0..2048),
        prefix in 0usize..300,
        kind in 0usize..4,
    ) {
        let tmp = tempfile::tempdir().unwrap();
        // Also a real log cut anywhere, or with garbage after a valid start.
        let mut real = ulog(&pass());
        real.truncate(prefix.min(real.len()));
        real.extend_from_slice(&bytes);
        let (name, content) = match kind {
            0 => ("a.ulg", bytes.clone()),
            1 => ("b.ulg", real),
            2 => ("c.csv", [b"timestamp,x,y,z,r\n".as_slice(), &bytes].concat()),
            _ => ("d.json", bytes.clone()),
        };
        std::fs::write(tmp.path().join(name), &content).unwrap();
        let t0 = Instant::now();
        let _ = read(tmp.path(), &bytes);
        prop_assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    }
}

#[test]
fn a_flight_cut_in_the_air_or_without_a_time_span_is_refused_saying_why() {
    let tmp = tempfile::tempdir().unwrap();
    // Climbs from the ground to 10 m and the log stops there, at 49 s.
    let mut csv = String::from("timestamp,x,y,z,r\n");
    for i in 0..50u64 {
        csv += &format!("{},{},0,{},\n", i * 1_000_000, i as f64 * 0.5, (i as f64).min(10.0));
    }
    std::fs::write(tmp.path().join("flight.csv"), csv).unwrap();
    let e = read(tmp.path(), b"").unwrap_err();
    assert!(e.contains("ends 10.0 m above") && e.contains("cut short"), "{e}");
    // The same log with a timeout report is what a timeout looks like: a result.
    let b = read(tmp.path(), br#"{"status": "timeout"}"#).unwrap();
    assert_eq!(b.flown.status, FlightStatus::TIMEOUT);

    let flat = tempfile::tempdir().unwrap();
    let mut csv = String::from("timestamp,x,y,z,r\n");
    for i in 0..50 {
        csv += &format!("0,{},3.5,5,\n", i as f64 * 0.4);
    }
    std::fs::write(flat.path().join("flight.csv"), csv).unwrap();
    let e = read(flat.path(), b"").unwrap_err();
    assert!(e.contains("no time span") && e.contains("50 samples"), "{e}");
}

#[test]
fn links_fifos_and_huge_files_in_a_job_folder_are_not_read() {
    let tmp = tempfile::tempdir().unwrap();
    let outside = tempfile::tempdir().unwrap();
    let mut csv = String::from("timestamp,x,y,z,r\n");
    for i in 0..100 {
        csv += &format!("{},{},3.5,5,\n", i * 100_000, i as f64 * 0.4);
    }
    std::fs::write(outside.path().join("flight.csv"), csv).unwrap();
    std::os::unix::fs::symlink(outside.path().join("flight.csv"), tmp.path().join("flight.csv")).unwrap();
    let fifo = std::ffi::CString::new(tmp.path().join("f.csv").to_str().unwrap()).unwrap();
    // SAFETY: mkfifo(3) on a path we own; no memory is shared.
    assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) }, 0);
    let t0 = Instant::now();
    let e = read(tmp.path(), b"").unwrap_err();
    assert!(e.contains("no trajectory"), "a link leading out is not followed: {e}");
    assert!(t0.elapsed() < Duration::from_secs(5), "a FIFO never blocks");
}

#[test]
fn a_collision_prevention_report_gets_its_verdict_measured_here() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("t.ulg"), ulog(&pass())).unwrap();
    let report = |cp: &str| format!(r#"{{"status": "landed", "collision_prevention": {cp}}}"#);
    // The report's own numbers are not taken: the closest centre is measured on the trajectory read back.
    let said = report(r#"{"cp_dist_m": 2.5, "closest_centre_m": 99.0, "inside_cp_dist": false}"#);
    let cp = read(tmp.path(), said.as_bytes()).unwrap().flown;
    let centre = cp.closest_centre_m.unwrap();
    // The pass runs 3 m from the centre line of a 2 m wide box: 2 m from its side, inside a CP_DIST of 2.5 m.
    assert!((centre - 2.0).abs() < 0.01, "{cp:?}");
    assert_eq!(cp.inside_cp_dist, Some(true));
    let cp = read(tmp.path(), report(r#"{"cp_dist_m": 1.5}"#).as_bytes())
        .unwrap()
        .flown;
    assert_eq!(cp.inside_cp_dist, Some(false));
    // Another mode's report, or a block without a usable CP_DIST, has no verdict; the flight is still read.
    for said in [
        r#"{"status": "landed"}"#.to_string(),
        report("null"),
        report(r#"{"cp_dist_m": "two"}"#),
        report(r#"{"cp_dist_m": -1}"#),
    ] {
        let b = read(tmp.path(), said.as_bytes()).unwrap();
        let cp = (b.flown.closest_centre_m, b.flown.inside_cp_dist);
        assert!(b.reported && cp == (None, None), "{said}: {cp:?}");
    }
    // A rejected CP flight has no closest centre.
    let rejected = r#"{"status": "rejected", "collision_prevention": {"cp_dist_m": 2.0}}"#;
    let empty = tempfile::tempdir().unwrap();
    let f = read(empty.path(), rejected.as_bytes()).unwrap().flown;
    assert_eq!(
        (f.status, f.closest_centre_m, f.inside_cp_dist),
        (FlightStatus::REJECTED, None, None)
    );
}
