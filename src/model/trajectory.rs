//! A flown or simulated path: timed positions in Aerialist's trajectory frame, and its CSV format.

use std::fmt::Write as _;
use std::path::Path;

use super::error::{ModelError, Result};
use super::files::read_text;

/// One position: `x` North, `y` East (metres, local NED), `z` **height up** (metres), `r` heading (radians, as
/// PX4's `heading`: clockwise from North), `t_s` seconds from the first sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Seconds since the start of the trajectory.
    pub t_s: f64,
    /// North, metres.
    pub x: f64,
    /// East, metres.
    pub y: f64,
    /// Height above the ground, metres, positive up.
    pub z: f64,
    /// Heading, radians clockwise from North, if known.
    pub r: Option<f64>,
}

/// A time-ordered list of samples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trajectory {
    /// The samples, in time order.
    pub samples: Vec<Sample>,
}

impl Trajectory {
    /// A trajectory of `samples`.
    pub fn new(samples: Vec<Sample>) -> Self {
        Self { samples }
    }

    /// Shifts time, position and heading so the first sample is the origin (Aerialist's `ALLIGN_ORIGIN`).
    pub fn origin_aligned(&self) -> Self {
        let Some(first) = self.samples.first().copied() else {
            return self.clone();
        };
        let samples = self
            .samples
            .iter()
            .map(|s| Sample {
                t_s: s.t_s - first.t_s,
                x: s.x - first.x,
                y: s.y - first.y,
                z: s.z - first.z,
                r: match (s.r, first.r) {
                    (Some(r), Some(r0)) => Some(r - r0),
                    (r, _) => r,
                },
            })
            .collect();
        Self { samples }
    }

    /// Aerialist's `downsample_time`: consecutive bins of `period_s` from the first sample, each bin
    /// `(start, start + period]` (the first also holds its start) replaced by the mean of its samples;
    /// empty bins are skipped. Linear in the samples: a long empty stretch is jumped in one step.
    pub fn binned(&self, period_s: f64) -> Self {
        let Some(first) = self.samples.first() else {
            return self.clone();
        };
        let t = |i: usize| self.samples[i].t_s;
        let n = self.samples.len();
        let mut out = Vec::new();
        let mut start = first.t_s;
        let mut i = 0;
        while i < n {
            let from = i;
            let mut end = start + period_s;
            if end.partial_cmp(&start) != Some(std::cmp::Ordering::Greater) {
                // The period is lost to rounding (or not positive): one last bin keeps the loop finite.
                end = f64::INFINITY;
            }
            while i < n && (t(i) <= end || t(i).is_nan()) {
                i += 1;
            }
            if i > from {
                out.push(mean(&self.samples[from..i]));
            }
            // Accumulating `start` is Aerialist's arithmetic, kept bit for bit over short gaps.
            start += period_s;
            if i < n && t(i) > start + period_s * JUMP_BINS {
                start = jump_to(start, t(i), period_s);
            }
        }
        Self { samples: out }
    }

    /// Flight time in seconds (last minus first timestamp).
    pub fn duration_s(&self) -> f64 {
        match (self.samples.first(), self.samples.last()) {
            (Some(a), Some(b)) => b.t_s - a.t_s,
            _ => 0.0,
        }
    }

    /// Reads an Aerialist trajectory CSV (`timestamp,x,y,z,r`, timestamp in microseconds; `r` may be empty).
    pub fn load_csv(path: &Path) -> Result<Self> {
        Self::parse_csv(&read_text(path)?, path)
    }

    /// Parses the CSV text; `path` names the file in errors. A UTF-8 byte-order mark before the header is
    /// skipped (spreadsheets write one). A last row without its newline is refused: the file was cut mid-row,
    /// and its last value may be cut short, as a damaged ULog is refused.
    pub fn parse_csv(text: &str, path: &Path) -> Result<Self> {
        let syntax = |line: usize, message: String| ModelError::Syntax {
            path: path.to_path_buf(),
            line: Some(line),
            column: None,
            message,
        };
        let text = whole_rows(text).map_err(|(line, why)| syntax(line, why))?;
        let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(syntax(
                1,
                "empty trajectory (expected the header timestamp,x,y,z,r)".into(),
            ));
        };
        let cols: Vec<String> = header.split(',').map(|c| c.trim().to_ascii_lowercase()).collect();
        let Some(([ti, xi, yi, zi], ri)) = csv_columns(&cols) else {
            let message = format!("expected the columns timestamp,x,y,z[,r], got {header:?}");
            return Err(syntax(1, message));
        };
        let mut samples = Vec::new();
        for (n, line) in lines {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells.len() != cols.len() {
                return Err(syntax(
                    n + 1,
                    format!("expected {} values, got {}", cols.len(), cells.len()),
                ));
            }
            let num = |i: usize| -> Result<f64> {
                cells[i]
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| syntax(n + 1, format!("{}: {:?} is not a finite number", cols[i], cells[i])))
            };
            let r = match ri.map(|i| cells[i]) {
                None | Some("") => None,
                Some(c) => c.parse::<f64>().ok().filter(|v| v.is_finite()),
            };
            let t_s = num(ti)? / 1e6;
            if let Some(prev) = samples.last().map(|s: &Sample| s.t_s)
                && let Err(why) = check_step(prev, t_s)
            {
                return Err(syntax(n + 1, format!("timestamp {}: {why}", cells[ti])));
            }
            samples.push(Sample {
                t_s,
                x: num(xi)?,
                y: num(yi)?,
                z: num(zi)?,
                r,
            });
        }
        if samples.is_empty() {
            return Err(syntax(1, "no samples after the header".into()));
        }
        Ok(Self { samples })
    }

    /// The CSV text in Aerialist's columns (`timestamp` in whole microseconds).
    pub fn to_csv(&self) -> String {
        let mut out = String::from("timestamp,x,y,z,r\n");
        for s in &self.samples {
            let r = s.r.map(|r| format!("{r:.6}")).unwrap_or_default();
            let _ = writeln!(
                out,
                "{},{:.4},{:.4},{:.4},{r}",
                (s.t_s * 1e6).round() as i64,
                s.x,
                s.y,
                s.z
            );
        }
        out
    }
}

/// The CSV `text` without a byte-order mark; or, when its last row has no newline, that line and why it is
/// refused (the file was cut mid-row).
fn whole_rows(text: &str) -> std::result::Result<&str, (usize, String)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let Some(last) = text.rsplit('\n').next().filter(|l| !l.trim().is_empty()) else {
        return Ok(text);
    };
    Err((
        text.lines().count(),
        format!(
            "the last row ({:?}) has no newline at its end: the file was cut mid-row; refused rather than read as \
             a shorter flight (if the row is whole, end it with a newline)",
            last.chars().take(40).collect::<String>()
        ),
    ))
}

/// The longest pause between consecutive samples of one flight, seconds.
pub const MAX_GAP_S: f64 = 3600.0;

/// Why a sample at `t_s` cannot follow one at `prev_s`: time going back, or a pause over [`MAX_GAP_S`]
/// (mixed clocks, such as a first row at 0 and the rest in epoch microseconds).
pub(crate) fn check_step(prev_s: f64, t_s: f64) -> std::result::Result<(), String> {
    if t_s < prev_s {
        Err(format!("goes back in time ({:.6} s after {:.6} s)", t_s, prev_s))
    } else if t_s - prev_s > MAX_GAP_S {
        Err(format!(
            "comes {:.0} s after the previous row (at most {MAX_GAP_S:.0} s between rows of one flight)",
            t_s - prev_s
        ))
    } else {
        Ok(())
    }
}

/// Empty bins beyond which [`Trajectory::binned`] jumps instead of stepping (far longer than any pause
/// in a real flight, so real logs bin exactly as Aerialist does).
const JUMP_BINS: f64 = 1024.0;

/// The start of the bin holding `t`, a whole number of periods after `start`.
fn jump_to(start: f64, t: f64, period_s: f64) -> f64 {
    let skip = ((t - start) / period_s).ceil() - 1.0;
    let jumped = start + skip.max(0.0) * period_s;
    // Rounding may land a bin late; never start past the sample.
    if jumped < t { jumped } else { start.max(t - period_s) }
}

fn mean(s: &[Sample]) -> Sample {
    let n = s.len() as f64;
    let avg = |f: fn(&Sample) -> f64| s.iter().map(f).sum::<f64>() / n;
    let r = if s.iter().all(|p| p.r.is_some()) {
        Some(s.iter().filter_map(|p| p.r).sum::<f64>() / n)
    } else {
        None
    };
    Sample {
        t_s: avg(|p| p.t_s),
        x: avg(|p| p.x),
        y: avg(|p| p.y),
        z: avg(|p| p.z),
        r,
    }
}

/// The positions of `timestamp`, `x`, `y`, `z` and of the optional `r` among a CSV header's lower-cased columns.
fn csv_columns(cols: &[String]) -> Option<([usize; 4], Option<usize>)> {
    let find = |name: &str| cols.iter().position(|c| c == name);
    Some(([find("timestamp")?, find("x")?, find("y")?, find("z")?], find("r")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(t: f64, x: f64) -> Sample {
        Sample {
            t_s: t,
            x,
            y: 0.0,
            z: 1.0,
            r: None,
        }
    }

    #[test]
    fn binning_by_hand() {
        // 10 Hz samples 0.0 .. 1.2 s with x = 10 t. Bins: [0, 0.5], (0.5, 1.0], (1.0, 1.5].
        let t = Trajectory::new((0..=12).map(|i| s(i as f64 / 10.0, i as f64)).collect());
        let b = t.binned(0.5);
        assert_eq!(b.samples.len(), 3);
        assert!((b.samples[0].x - 2.5).abs() < 1e-12, "mean of 0..=5");
        assert!((b.samples[0].t_s - 0.25).abs() < 1e-12);
        assert!((b.samples[1].x - 8.0).abs() < 1e-12, "mean of 6..=10");
        assert!((b.samples[2].x - 11.5).abs() < 1e-12, "mean of 11, 12");
    }

    #[test]
    fn binning_skips_empty_bins() {
        let t = Trajectory::new(vec![s(0.0, 0.0), s(2.1, 4.0), s(2.3, 6.0)]);
        let b = t.binned(0.5);
        assert_eq!(b.samples.iter().map(|p| p.x).collect::<Vec<_>>(), vec![0.0, 5.0]);
    }

    #[test]
    fn origin_alignment() {
        let t = Trajectory::new(vec![
            Sample {
                t_s: 5.0,
                x: 1.0,
                y: 2.0,
                z: 0.5,
                r: Some(0.1),
            },
            Sample {
                t_s: 6.0,
                x: 2.0,
                y: 4.0,
                z: 3.5,
                r: Some(0.3),
            },
        ]);
        let a = t.origin_aligned();
        assert_eq!(
            a.samples[0],
            Sample {
                t_s: 0.0,
                x: 0.0,
                y: 0.0,
                z: 0.0,
                r: Some(0.0)
            }
        );
        assert_eq!(
            (a.samples[1].t_s, a.samples[1].x, a.samples[1].y, a.samples[1].z),
            (1.0, 1.0, 2.0, 3.0)
        );
    }

    #[test]
    fn csv_round_trip_and_errors() {
        let text = "timestamp,x,y,z,r\n0,0,0,0,\n500000,1.5,2.5,3,0.25\n";
        let t = Trajectory::parse_csv(text, Path::new("f.csv")).unwrap();
        assert_eq!(
            t.samples[1],
            Sample {
                t_s: 0.5,
                x: 1.5,
                y: 2.5,
                z: 3.0,
                r: Some(0.25)
            }
        );
        let back = Trajectory::parse_csv(&t.to_csv(), Path::new("g.csv")).unwrap();
        assert_eq!(back, t);
        let e = Trajectory::parse_csv("timestamp,x,y,z,r\n0,a,0,0,0\n", Path::new("f.csv")).unwrap_err();
        assert!(e.to_string().contains("f.csv:2"), "{e}");
        assert!(Trajectory::parse_csv("", Path::new("f.csv")).is_err());
        assert!(Trajectory::parse_csv("timestamp,x,y,z\n1,0,0,0\n0,0,0,0\n", Path::new("f.csv")).is_err());
    }

    #[test]
    fn a_byte_order_mark_is_skipped_and_a_row_cut_mid_way_is_refused() {
        let text = "timestamp,x,y,z,r\n0,0,0,0,\n500000,1.5,2.5,3,0.25\n";
        let plain = Trajectory::parse_csv(text, Path::new("f.csv")).unwrap();
        let marked = Trajectory::parse_csv(&format!("\u{feff}{text}"), Path::new("f.csv")).unwrap();
        assert_eq!(marked, plain);
        // Cut inside its last value: 0.25 read as 0.2 had it been taken.
        let e = Trajectory::parse_csv(&text[..text.len() - 2], Path::new("f.csv")).unwrap_err();
        let e = e.to_string();
        assert!(
            e.starts_with("f.csv:3:") && e.contains("no newline") && e.contains("cut mid-row"),
            "{e}"
        );
    }
}

#[cfg(test)]
#[path = "trajectory_tests.rs"]
mod trajectory_tests;
