//! The flown trajectory, kept in memory for judging and appended to an Aerialist CSV (`timestamp,x,y,z,r`,
//! microseconds, x North, y East, z **up**, r heading in radians) as each position arrives, flushed per line, so
//! a crash or Ctrl-C loses nothing. (A live log cannot be written atomically; it is the one exception.)

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::model::{Sample, Trajectory};

use crate::bridge::wire::pose::PoseNed;

/// Records positions as they arrive.
#[derive(Debug)]
pub struct Recorder {
    out: Option<(PathBuf, BufWriter<File>)>,
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
                let mut w = BufWriter::new(File::create(path)?);
                w.write_all(b"timestamp,x,y,z,r\n")?;
                w.flush()?;
                Some((path.to_path_buf(), w))
            }
        };
        Ok(Self {
            out,
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

    /// Samples so far.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The first error writing the CSV, if any.
    pub fn write_error(&self) -> Option<&str> {
        self.write_error.as_deref()
    }

    /// The trajectory recorded.
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
        assert_eq!(r.trajectory().samples.len(), 1);
    }
}
