//! The ranges of `fly`'s numbers, and the ranges section of docs/cli.md: every campaign setting's range comes
//! from its declaration (`prgenuav::campaign::settings`), checked before anything is read, sampled, started or
//! flown (exit 2, naming the flag, the TOML key and the range).

use prgenuav::campaign::evaluation::flying::MAX_RUNS;
use prgenuav::campaign::settings::keys::MAX_TIME_SCALE;
use prgenuav::model::Limit;

/// A flag's accepted values, with the flag's name.
#[derive(Debug, Clone, Copy)]
pub struct Named {
    /// The flag, as the user types it.
    pub names: &'static str,
    /// Its accepted values.
    pub limit: Limit,
}

impl Named {
    /// `v`, or an error naming the flag and its range.
    pub fn check(&self, v: f64) -> anyhow::Result<f64> {
        self.limit.check(self.names, v).map_err(anyhow::Error::msg)
    }
}

pub const FLY_TIME_SCALE: Named = Named {
    names: "fly --time-scale",
    limit: Limit::above(0.0, MAX_TIME_SCALE, "x wall time"),
};
pub const FLY_READY_TIMEOUT: Named = Named {
    names: "fly --ready-timeout",
    limit: Limit::above(0.0, 3600.0, "s"),
};

/// DTW sums metres over the alignment: two different tests' averages lie some thousands of metres apart.
pub const SIMILAR_BELOW: Named = Named {
    names: "evaluate/score --similar-below",
    limit: Limit::within(0.0, 1e6, "m"),
};
pub const EVALUATE_RUNS: Named = Named {
    names: "evaluate --runs",
    limit: Limit::within(1.0, MAX_RUNS as f64, "flights per test"),
};

/// The ranges section of docs/cli.md.
#[cfg(test)]
pub fn render(s: &mut String) {
    use prgenuav::campaign::settings::all;
    use std::fmt::Write as _;
    let _ = writeln!(s, "## Ranges of the numeric settings\n");
    let _ = writeln!(
        s,
        "Every number is checked before anything is read, started or flown; one outside its range exits with \
         code 2 and names the flag, the TOML key and the range. Durations are checked before they become \
         timers. A range setting's two ends both lie within its range.\n"
    );
    let _ = writeln!(s, "| setting | range |\n|---|---|");
    for st in all() {
        if let Some(l) = &st.range {
            let _ = writeln!(s, "| {} | {} |", st.names(), l.range());
        }
    }
    let _ = writeln!(
        s,
        "| --jobs (with --runner) | {} |",
        prgenuav::campaign::settings::keys::RUNNER_JOBS.range()
    );
    for n in [FLY_TIME_SCALE, FLY_READY_TIMEOUT, SIMILAR_BELOW, EVALUATE_RUNS] {
        let _ = writeln!(s, "| {} | {} |", n.names, n.limit.range());
    }
    let _ = writeln!(
        s,
        "| files read back (tests, plans, CSVs, journal, JSON) | regular files of at most 64 MiB; PX4 logs at most \
         512 MiB |"
    );
    let _ = writeln!(
        s,
        "\n`mock-autopilot`: `--speed-factor` 0 < K <= {MAX_TIME_SCALE} (or `max`), `--latency` 0 to 10000 ms, \
         `--estimator-settle` 0 to 600 s, `--lockstep-wait` 0 to 60 s, `--reboot-after` and `--silence-after` 0 \
         to 86400 s, `--loss` and `--duplicate` 0 to 1, `--step-ms` 0 < S <= 100, `--instance` 0 to 50955 (its \
         ports 14580+N and 14540+N must exist).\n"
    );
}
