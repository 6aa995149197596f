//! The flown trajectory, kept in memory for judging and appended to an Aerialist CSV (`timestamp,x,y,z,r`,
//! microseconds, x North, y East, z **up**, r heading in radians) as each position arrives, flushed per line, so
//! a crash or Ctrl-C loses nothing once airborne. (A live log cannot be written atomically; it is the one
//! exception.)
//!
//! The recording starts [`GROUND_LEAD_S`] before liftoff, as PX4's log (Aerialist's source) starts at arming.
//! Anchoring it at a vehicle event rather than at the first position after setup makes the judge's 0.5 s bins,
//! and so the competition distance, repeatable: setup takes a varying wall (and so vehicle) time, which would
//! shift the bins' phase and a flight's score by millimetres between identical runs on the lockstep mock.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::model::safe_files::create_replacing;
use crate::model::{Sample, Trajectory};

use crate::bridge::wire::pose::PoseNed;

/// A rise above the lowest altitude so far that means the vehicle has lifted off (well above the estimator's
/// noise on the ground, a few centimetres).
pub const LIFTOFF_RISE_M: f64 = 0.3;
/// Ground time kept before the liftoff sample: PX4 spins up and lifts off within about a second of arming.
pub const GROUND_LEAD_S: f64 = 1.0;

/// Records positions as they arrive.
#[derive(Debug)]
pub struct Recorder {
    out: Option<(PathBuf, BufWriter<File>)>,
    /// Positions on the ground, kept until liftoff says which of them the recording starts at.
    ground: Vec<PoseNed>,
    /// Lowest altitude (m, up) on the ground so far.
    ground_up_m: f64,
    airborne: bool,
    samples: Vec<Sample>,
    first_ms: Option<u32>,
    last_ms: Option<u32>,
    write_error: Option<String>,
}

impl Recorder {
    /// A recorder writing to `csv` (created or truncated, header written) or only in memory.
    pub fn create(csv: Option<&Path>) -> io::Result<Self> {
        let out = match csv {
            None => None,
            Some(path) => {
                if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir)?;
                }
                // A link planted at the path is replaced, never written through.
                let mut w = BufWriter::new(create_replacing(path)?);
                w.write_all(b"timestamp,x,y,z,r\n")?;
                w.flush()?;
                Some((path.to_path_buf(), w))
            }
        };
        Ok(Self {
            out,
            ground: Vec::new(),
            ground_up_m: f64::INFINITY,
            airborne: false,
            samples: Vec::new(),
            first_ms: None,
            last_ms: None,
            write_error: None,
        })
    }

    /// Records `pose` unless it is not newer than the last one (duplicates, reordered datagrams).
    pub fn push(&mut self, pose: &PoseNed) {
        if self.last_ms.is_some_and(|t| pose.time_boot_ms <= t) {
            return;
        }
        self.last_ms = Some(pose.time_boot_ms);
        if self.airborne {
            self.record(pose);
            return;
        }
        let up = -pose.pos_ned[2];
        self.ground_up_m = self.ground_up_m.min(up);
        self.ground.push(*pose);
        if up - self.ground_up_m > LIFTOFF_RISE_M {
            self.airborne = true;
            let from = u64::from(pose.time_boot_ms).saturating_sub((GROUND_LEAD_S * 1000.0) as u64);
            let ground = std::mem::take(&mut self.ground);
            for p in ground.iter().filter(|p| u64::from(p.time_boot_ms) >= from) {
                self.record(p);
            }
        }
    }

    /// Appends `pose` to the recording.
    fn record(&mut self, pose: &PoseNed) {
        let first = *self.first_ms.get_or_insert(pose.time_boot_ms);
        let s = Sample {
            t_s: f64::from(pose.time_boot_ms - first) / 1000.0,
            x: pose.pos_ned[0],
            y: pose.pos_ned[1],
            z: -pose.pos_ned[2],
            r: pose.yaw_rad,
        };
        self.samples.push(s);
        if let Some((path, w)) = self.out.as_mut() {
            let r = s.r.map(|r| format!("{r:.6}")).unwrap_or_default();
            let line = format!(
                "{},{:.4},{:.4},{:.4},{r}\n",
                (s.t_s * 1e6).round() as i64,
                s.x,
                s.y,
                s.z
            );
            if let Err(e) = w.write_all(line.as_bytes()).and_then(|_| w.flush()) {
                // Keep flying and recording in memory; report the problem once at the end.
                if self.write_error.is_none() {
                    self.write_error = Some(format!("{}: {e}", path.display()));
                }
            }
        }
    }

    /// Samples so far (on the ground before liftoff, then the recording).
    pub fn len(&self) -> usize {
        self.samples.len() + self.ground.len()
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Ends the recording: a vehicle that never lifted off is recorded whole (a refused takeoff shows where it
    /// stood). Returns the trajectory.
    pub fn finish(&mut self) -> Trajectory {
        for p in std::mem::take(&mut self.ground) {
            self.record(&p);
        }
        self.trajectory()
    }

    /// The first error writing the CSV, if any.
    pub fn write_error(&self) -> Option<&str> {
        self.write_error.as_deref()
    }

    /// The trajectory recorded so far (empty before liftoff; see [`Self::finish`]).
    pub fn trajectory(&self) -> Trajectory {
        Trajectory::new(self.samples.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(ms: u32, n: f64, down: f64) -> PoseNed {
        PoseNed {
            time_boot_ms: ms,
            pos_ned: [n, 1.0, down],
            vel_ned: [0.0; 3],
            yaw_rad: Some(0.5),
        }
    }

    #[test]
    fn csv_is_written_as_it_goes_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/t.csv");
        let mut r = Recorder::create(Some(&path)).unwrap();
        r.push(&pose(1000, 0.0, 0.0));
        r.push(&pose(1500, 2.0, -3.0));
        // Readable while recording: nothing is buffered.
        let now = Trajectory::load_csv(&path).unwrap();
        assert_eq!(now.samples.len(), 2);
        r.push(&pose(1500, 9.0, -9.0));
        r.push(&pose(1400, 9.0, -9.0));
        assert_eq!(r.len(), 2, "duplicates and older samples are skipped");
        let t = r.trajectory();
        assert_eq!(t, Trajectory::load_csv(&path).unwrap());
        assert_eq!((t.samples[1].t_s, t.samples[1].x, t.samples[1].z), (0.5, 2.0, 3.0));
        assert_eq!(t.samples[1].r, Some(0.5));
        assert!(r.write_error().is_none());
    }

    #[test]
    fn memory_only() {
        let mut r = Recorder::create(None).unwrap();
        assert!(r.is_empty());
        r.push(&pose(0, 0.0, 0.0));
        assert_eq!(r.len(), 1);
        assert_eq!(r.finish().samples.len(), 1);
    }

    /// A flight at 30 Hz that lifts off at `liftoff_ms` (boot time) after `ground_ms` on the ground, climbing
    /// 1 m/s.
    fn flight(r: &mut Recorder, liftoff_ms: u32, ground_ms: u32) {
        let start = liftoff_ms - ground_ms;
        // Samples on one 30 Hz grid from boot, to 8 s after liftoff.
        for ms in (0..liftoff_ms + 8000)
            .map(|k| k * 100 / 3)
            .filter(|ms| *ms >= start && *ms < liftoff_ms + 8000)
        {
            let up = f64::from(ms.saturating_sub(liftoff_ms)) / 1000.0;
            r.push(&pose(ms, 0.0, -up));
        }
    }

    #[test]
    fn the_recording_starts_a_second_before_liftoff_however_long_the_setup() {
        let (mut short, mut long) = (Recorder::create(None).unwrap(), Recorder::create(None).unwrap());
        flight(&mut short, 5000, 1500);
        flight(&mut long, 9000, 4500);
        let (a, b) = (short.finish(), long.finish());
        assert!(!a.samples.is_empty());
        // The liftoff sample (0.3 m up) is the first above 0.3; the recording starts 1 s before it.
        let rise = a.samples.iter().position(|s| s.z > LIFTOFF_RISE_M).unwrap();
        assert!(
            (a.samples[rise].t_s - GROUND_LEAD_S).abs() < 0.034,
            "{}",
            a.samples[rise].t_s
        );
        assert_eq!(a.samples[0].t_s, 0.0);
        // Same flight, longer setup: the same recording, so the same bins and the same judged distance.
        assert_eq!(a, b);
    }

    #[test]
    fn a_vehicle_that_never_lifts_off_is_recorded_whole_at_the_end() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let mut r = Recorder::create(Some(&path)).unwrap();
        for k in 0..50 {
            // Estimator noise on the ground stays below the liftoff rise.
            r.push(&pose(k * 100, 0.0, if k % 2 == 0 { 0.05 } else { -0.05 }));
        }
        assert!(r.trajectory().samples.is_empty());
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "timestamp,x,y,z,r\n",
            "only the header so far"
        );
        let t = r.finish();
        assert_eq!(t.samples.len(), 50);
        assert_eq!(t, Trajectory::load_csv(&path).unwrap());
    }
}
