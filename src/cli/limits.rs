//! Every numeric setting's range, in one table: checked before anything is read, sampled, started or flown
//! (exit 2, naming the flag, the TOML key and the range), and rendered into docs/cli.md. A number outside its
//! range is refused rather than clamped: 1e300 seconds is a typo, not a wish. Durations go through
//! [`seconds`], the one checked conversion to a [`Duration`].

use std::time::Duration;

use anyhow::bail;
use prgenuav::campaign::evaluation::flying::MAX_RUNS;
use prgenuav::campaign::screen::parallel::available_threads;

/// One setting's accepted values, `min..=max` (`open_min`: `min` itself excluded).
#[derive(Debug, Clone, Copy)]
pub struct Limit {
    /// The flag(s) and TOML key naming it, as the user types them.
    pub names: &'static str,
    pub min: f64,
    pub max: f64,
    pub open_min: bool,
    pub unit: &'static str,
}

const fn limit(names: &'static str, min: f64, max: f64, unit: &'static str) -> Limit {
    Limit {
        names,
        min,
        max,
        open_min: false,
        unit,
    }
}

const fn above(names: &'static str, min: f64, max: f64, unit: &'static str) -> Limit {
    Limit {
        names,
        min,
        max,
        open_min: true,
        unit,
    }
}

/// Runner jobs at once, at most: each is a thread and a local process (`sh -c`, `srun`, `kubectl`, ...).
pub const MAX_JOBS: usize = 1024;
/// Embedded mock autopilots per core, at most: each simulates and judges a flight on the campaign's threads.
pub const MOCKS_PER_CORE: usize = 8;
/// The largest speed-up of simulated time: beyond it a vehicle's physics step outruns any link.
pub const MAX_TIME_SCALE: f64 = 1000.0;

pub const MOCK_SPEED: Limit = limit("--mock-speed (mock.speed)", 1.0, MAX_TIME_SCALE, "x wall time");
pub const MOCK_LATENCY: Limit = limit("--mock-latency (mock.latency_ms)", 0.0, 1000.0, "ms");
pub const THRESHOLD: Limit = above("--threshold (screening.threshold_m)", 0.0, 100.0, "m");
pub const FLIGHT_TIMEOUT: Limit = above("--timeout (flight.timeout_s)", 0.0, 86_400.0, "s");
pub const CONNECT_TIMEOUT: Limit = above("--connect-timeout (flight.connect_timeout_s)", 0.0, 3600.0, "s");
pub const CONNECT_TIME_SCALE: Limit = above(
    "--connect-time-scale (flight.connect_time_scale)",
    0.0,
    MAX_TIME_SCALE,
    "x wall time",
);
pub const JOB_TIMEOUT: Limit = above("--job-timeout", 0.0, 604_800.0, "s");
pub const PX4_SPEED_FACTOR: Limit = above("--speed-factor", 0.0, 100.0, "x wall time");
pub const CONFIRM: Limit = limit("--confirm (flight.confirm)", 1.0, 20.0, "flights per test");
pub const FLY_TIMEOUT: Limit = above("fly --timeout", 0.0, 86_400.0, "s");
pub const FLY_TIME_SCALE: Limit = above("fly --time-scale", 0.0, MAX_TIME_SCALE, "x wall time");
pub const FLY_READY_TIMEOUT: Limit = above("fly --ready-timeout", 0.0, 3600.0, "s");
/// DTW sums metres over the alignment: two different tests' averages lie some thousands of metres apart.
pub const SIMILAR_BELOW: Limit = limit("evaluate/score --similar-below", 0.0, 1e6, "m");
pub const EVALUATE_RUNS: Limit = limit("evaluate --runs", 1.0, MAX_RUNS as f64, "flights per test");

/// The table docs/cli.md shows, beside the counts and ranges checked elsewhere (listed in [`render`]).
#[cfg(test)]
pub const TABLE: &[Limit] = &[
    MOCK_SPEED,
    MOCK_LATENCY,
    THRESHOLD,
    FLIGHT_TIMEOUT,
    CONNECT_TIMEOUT,
    CONNECT_TIME_SCALE,
    JOB_TIMEOUT,
    PX4_SPEED_FACTOR,
    CONFIRM,
    FLY_TIMEOUT,
    FLY_TIME_SCALE,
    FLY_READY_TIMEOUT,
    SIMILAR_BELOW,
    EVALUATE_RUNS,
];

impl Limit {
    /// Whether `v` is in range (never NaN or infinite).
    pub fn holds(&self, v: f64) -> bool {
        let low = if self.open_min { v > self.min } else { v >= self.min };
        v.is_finite() && low && v <= self.max
    }

    /// The range in words: `0 < S <= 3600 s`.
    pub fn range(&self) -> String {
        let low = if self.open_min { "<" } else { "<=" };
        format!("{} {low} value <= {} {}", self.min, self.max, self.unit)
    }

    /// `v`, or an error naming the setting and its range.
    pub fn check(&self, v: f64) -> anyhow::Result<f64> {
        if !self.holds(v) {
            bail!("{} {v} is out of range: {}", self.names, self.range());
        }
        Ok(v)
    }
}

/// The one checked conversion of seconds to a [`Duration`]: `v` within `limit`, else an error naming it.
pub fn seconds(limit: &Limit, v: f64) -> anyhow::Result<Duration> {
    let v = limit.check(v)?;
    Duration::try_from_secs_f64(v).map_err(|e| anyhow::anyhow!("{} {v}: {e}", limit.names))
}

/// The most embedded mock autopilots this machine runs at once.
pub fn max_mock_vehicles() -> usize {
    available_threads() * MOCKS_PER_CORE
}

/// `n` things at once (`what`, named as the user typed it), from 1 to `max` (`why` says where the cap comes from).
pub fn count(what: &str, n: usize, max: usize, why: &str) -> anyhow::Result<usize> {
    if !(1..=max).contains(&n) {
        bail!("{what} {n} is out of range: 1 to {max} ({why})");
    }
    Ok(n)
}

/// The ranges section of docs/cli.md.
#[cfg(test)]
pub fn render(s: &mut String) {
    use std::fmt::Write as _;
    let _ = writeln!(s, "## Ranges of the numeric settings\n");
    let _ = writeln!(
        s,
        "Every number is checked before anything is read, started or flown; one outside its range exits with \
         code 2 and names the flag, the TOML key and the range. Durations are checked before they become \
         timers.\n"
    );
    let _ = writeln!(s, "| setting | range |\n|---|---|");
    for l in TABLE {
        let _ = writeln!(s, "| {} | {} |", l.names, l.range());
    }
    let others = [
        ("BUDGET", "1 to 10000 flights".to_string()),
        ("--candidates (screening.candidates)", "1 to 100000".to_string()),
        (
            "--ensemble (screening.ensemble)",
            "0 to the ensemble's members".to_string(),
        ),
        ("--max-iou, --child-max-iou, --min-diversity", "0 to 1".to_string()),
        (
            "--mock-vehicles (mock.vehicles)",
            format!("1 to {MOCKS_PER_CORE} per core of the machine"),
        ),
        (
            "--jobs",
            format!("1 to {MAX_JOBS} (each job is a thread and a local process)"),
        ),
        ("--instances", "1 to the PX4 instance slots (docs/px4.md)".to_string()),
        (
            "generator ranges (generator.*)",
            "within the competition's arena (docs/formats.md)".to_string(),
        ),
        (
            "files read back (tests, plans, CSVs, journal, JSON)",
            "regular files of at most 64 MiB; PX4 logs at most 512 MiB".to_string(),
        ),
    ];
    for (name, range) in others {
        let _ = writeln!(s, "| {name} | {range} |");
    }
    let _ = writeln!(
        s,
        "\n`mock-autopilot`: `--speed-factor` 0 < K <= {MAX_TIME_SCALE} (or `max`), `--latency` 0 to 10000 ms, \
         `--estimator-settle` 0 to 600 s, `--lockstep-wait` 0 to 60 s, `--reboot-after` and `--silence-after` 0 \
         to 86400 s, `--loss` and `--duplicate` 0 to 1, `--step-ms` 0 < S <= 100, `--instance` 0 to 50955 (its \
         ports 14580+N and 14540+N must exist).\n"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_limit_takes_its_ends_and_refuses_beyond_them_and_non_numbers() {
        for l in TABLE {
            assert!(l.holds(l.max), "{}", l.names);
            assert_eq!(l.holds(l.min), !l.open_min, "{}", l.names);
            for bad in [l.max * 1.01 + 1.0, l.min - 1.0, f64::NAN, f64::INFINITY, 1e300, -1e300] {
                let e = l.check(bad).unwrap_err().to_string();
                assert!(e.contains(l.names) && e.contains("out of range"), "{e}");
            }
        }
        assert!(seconds(&JOB_TIMEOUT, 1e19).is_err());
        assert_eq!(seconds(&JOB_TIMEOUT, 2.5).unwrap(), Duration::from_millis(2500));
        let e = count("--jobs", 100_000, MAX_JOBS, "a thread each")
            .unwrap_err()
            .to_string();
        assert!(e.contains("1 to 1024"), "{e}");
    }
}
