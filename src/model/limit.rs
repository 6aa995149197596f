//! A number's accepted values. A number outside its range is refused rather than clamped: 1e300 seconds is a
//! typo, not a wish. Durations go through [`Limit::seconds`], the one checked conversion to a [`Duration`].

use std::time::Duration;

/// Accepted values `min..=max` (`open_min`, `open_max`: that end excluded; `per_core`: `max` per core of the machine).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// The lowest value.
    pub min: f64,
    /// The highest value (per core with `per_core`).
    pub max: f64,
    /// `min` itself excluded.
    pub open_min: bool,
    /// `max` itself excluded.
    pub open_max: bool,
    /// A count: whole numbers, said as `1 to N`.
    pub whole: bool,
    /// `max` is per core of the machine.
    pub per_core: bool,
    /// The unit, as the range is said.
    pub unit: &'static str,
}

impl Limit {
    /// `min <= value <= max`.
    pub const fn within(min: f64, max: f64, unit: &'static str) -> Self {
        Self {
            min,
            max,
            open_min: false,
            open_max: false,
            whole: false,
            per_core: false,
            unit,
        }
    }

    /// `min < value <= max`.
    pub const fn above(min: f64, max: f64, unit: &'static str) -> Self {
        Self {
            open_min: true,
            ..Self::within(min, max, unit)
        }
    }

    /// `min < value < max`.
    pub const fn between(min: f64, max: f64, unit: &'static str) -> Self {
        Self {
            open_min: true,
            open_max: true,
            ..Self::within(min, max, unit)
        }
    }

    /// A count from `min` to `max`.
    pub const fn count(min: usize, max: usize, unit: &'static str) -> Self {
        Self {
            whole: true,
            ..Self::within(min as f64, max as f64, unit)
        }
    }

    /// A count from `min` to `max` per core of this machine.
    pub const fn count_per_core(min: usize, per_core: usize, unit: &'static str) -> Self {
        Self {
            per_core: true,
            ..Self::count(min, per_core, unit)
        }
    }

    /// The largest value on this machine.
    pub fn max_here(&self) -> f64 {
        if self.per_core {
            self.max * std::thread::available_parallelism().map_or(1, |n| n.get()) as f64
        } else {
            self.max
        }
    }

    /// Whether `v` is in range (never NaN or infinite).
    pub fn holds(&self, v: f64) -> bool {
        let low = if self.open_min { v > self.min } else { v >= self.min };
        let high = if self.open_max {
            v < self.max_here()
        } else {
            v <= self.max_here()
        };
        v.is_finite() && low && high && (!self.whole || v.fract() == 0.0)
    }

    /// The range in words: `0 < value <= 3600 s`, or `1 to 100000` for a count.
    pub fn range(&self) -> String {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        if self.whole && self.per_core {
            return format!("{} to {} per core of the machine{unit}", self.min, self.max);
        }
        if self.whole {
            return format!("{} to {}{unit}", self.min, self.max_here());
        }
        let low = if self.open_min { "<" } else { "<=" };
        let high = if self.open_max { "<" } else { "<=" };
        format!("{} {low} value {high} {}{unit}", self.min, self.max)
    }

    /// `v`, or an error naming the setting (`names`) and the range.
    pub fn check(&self, names: &str, v: f64) -> Result<f64, String> {
        if !self.holds(v) {
            let here = if self.per_core {
                format!(" ({} on this machine)", self.max_here())
            } else {
                String::new()
            };
            return Err(format!("{names} {} is out of range: {}{here}", number(v), self.range()));
        }
        Ok(v)
    }

    /// The one checked conversion of seconds to a [`Duration`]: `v` within the range, else an error naming it.
    pub fn seconds(&self, names: &str, v: f64) -> Result<Duration, String> {
        let v = self.check(names, v)?;
        Duration::try_from_secs_f64(v).map_err(|e| format!("{names} {v}: {e}"))
    }
}

/// A number as a user reads it: as written when ordinary, in scientific notation when huge or tiny (1e308, not
/// three hundred digits).
pub fn number(v: f64) -> String {
    if v.is_finite() && v != 0.0 && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_and_tiny_numbers_are_said_in_scientific_notation() {
        assert_eq!(number(1e308), "1e308");
        assert_eq!(number(75.0), "75");
        assert_eq!(number(2.5e-7), "2.5e-7");
        let e = Limit::within(0.0, 1e6, "m")
            .check("--similar-below", 1e308)
            .unwrap_err();
        assert!(
            e.len() < 100 && e.contains("--similar-below 1e308 is out of range"),
            "{e}"
        );
    }

    #[test]
    fn ends_are_taken_and_beyond_them_refused() {
        let l = Limit::above(0.0, 10.0, "s");
        assert!(l.holds(10.0) && !l.holds(0.0) && !l.holds(f64::NAN) && !l.holds(1e300));
        assert!(Limit::within(0.0, 1.0, "").holds(0.0));
        let c = Limit::count(1, 1024, "");
        assert!(c.holds(1.0) && !c.holds(1.5) && !c.holds(0.0));
        let e = c.check("--jobs", 1e8).unwrap_err();
        assert!(e.contains("--jobs") && e.contains("1 to 1024"), "{e}");
        assert!(Limit::above(0.0, 604_800.0, "s").seconds("t", 1e19).is_err());
        assert_eq!(
            Limit::above(0.0, 10.0, "s").seconds("t", 2.5),
            Ok(Duration::from_millis(2500))
        );
        let p = Limit::count_per_core(1, 8, "");
        assert!(p.holds(8.0) && !p.holds(1e6));
    }
}
