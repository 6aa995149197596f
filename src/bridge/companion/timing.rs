//! How fast the avoidance companion answers PX4, in wall time: from a request's arrival to the next answer
//! sent, the planner's own computation (render + plan), and the age of the plan an answer carries (from the
//! moment its input was taken to the answer). PX4 drops answers older than 0.5 s of vehicle time, so on a
//! simulator K times faster than real time the budget in wall time is K times smaller.

use std::sync::Mutex;
use std::time::Duration;

use serde::Serialize;

/// Samples kept per series (at 10 Hz, over 16 minutes of vehicle time); later ones are dropped.
const MAX_SAMPLES: usize = 10_000;

/// Wall-time samples of one flight's companion, milliseconds.
#[derive(Debug, Default)]
pub struct AnswerTiming {
    series: Mutex<[Vec<f32>; 3]>,
}

const REQUEST_TO_ANSWER: usize = 0;
const PLAN: usize = 1;
const PLAN_AGE: usize = 2;

impl AnswerTiming {
    fn push(&self, series: usize, d: Duration) {
        if let Ok(mut s) = self.series.lock()
            && s[series].len() < MAX_SAMPLES
        {
            s[series].push(d.as_secs_f32() * 1e3);
        }
    }

    /// A request arrived `d` (wall) before the answer that followed it.
    pub fn request_to_answer(&self, d: Duration) {
        self.push(REQUEST_TO_ANSWER, d);
    }

    /// One planner computation took `d` (wall).
    pub fn plan(&self, d: Duration) {
        self.push(PLAN, d);
    }

    /// An answer carried a plan whose input was taken `d` (wall) before it was sent.
    pub fn plan_age(&self, d: Duration) {
        self.push(PLAN_AGE, d);
    }

    /// The three series as quantiles (`None` when the companion never answered).
    pub fn report(&self) -> Option<TimingReport> {
        let s = self.series.lock().ok()?;
        Some(TimingReport {
            request_to_answer_ms: Quantiles::of(&s[REQUEST_TO_ANSWER])?,
            plan_ms: Quantiles::of(&s[PLAN]),
            plan_age_ms: Quantiles::of(&s[PLAN_AGE]),
        })
    }
}

/// The companion's timing in a flight report (wall milliseconds).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimingReport {
    /// From a request's arrival to the next answer sent.
    pub request_to_answer_ms: Quantiles,
    /// One planner computation (render + cloud + plan).
    pub plan_ms: Option<Quantiles>,
    /// From the moment a plan's input was taken to the answer carrying it.
    pub plan_age_ms: Option<Quantiles>,
}

/// Median, 99th percentile and maximum of a series, and its size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quantiles {
    /// Samples.
    pub n: usize,
    /// Median (nearest rank).
    pub median: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    /// Largest.
    pub max: f64,
}

impl Quantiles {
    /// Nearest-rank quantiles; `None` for no samples.
    pub fn of(samples: &[f32]) -> Option<Self> {
        let mut v: Vec<f64> = samples
            .iter()
            .map(|&x| f64::from(x))
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
        Some(Self {
            n: v.len(),
            median: rank(0.5),
            p99: rank(0.99),
            max: v[v.len() - 1],
        })
    }
}

impl std::fmt::Display for Quantiles {
    /// `median/p99`, one decimal.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.1}/{:.1}", self.median, self.p99)
    }
}

impl std::fmt::Display for TimingReport {
    /// One line: request to answer, plan, plan age (median/p99 ms) and the number of answers.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let q = |q: Option<Quantiles>| q.map_or("-".to_string(), |q| q.to_string());
        write!(
            f,
            "request to answer {} ms, plan {} ms, plan age {} ms (median/p99, wall; {} answers)",
            self.request_to_answer_ms,
            q(self.plan_ms),
            q(self.plan_age_ms),
            self.request_to_answer_ms.n
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_quantiles() {
        let v: Vec<f32> = (1..=100).map(|x| x as f32).collect();
        let q = Quantiles::of(&v).expect("samples");
        assert_eq!((q.n, q.median, q.p99, q.max), (100, 50.0, 99.0, 100.0));
        let q = Quantiles::of(&[3.0]).expect("one sample");
        assert_eq!((q.median, q.p99, q.max), (3.0, 3.0, 3.0));
        assert!(Quantiles::of(&[]).is_none());
    }

    #[test]
    fn report_needs_answers() {
        let t = AnswerTiming::default();
        assert!(t.report().is_none());
        t.plan(Duration::from_millis(4));
        assert!(t.report().is_none(), "plans alone, no answer: nothing to report");
        t.request_to_answer(Duration::from_millis(7));
        let r = t.report().expect("an answer");
        assert!((r.request_to_answer_ms.median - 7.0).abs() < 1e-3);
        assert!((r.plan_ms.expect("a plan").max - 4.0).abs() < 1e-3);
        assert!(r.plan_age_ms.is_none());
        assert_eq!(
            r.to_string(),
            "request to answer 7.0/7.0 ms, plan 4.0/4.0 ms, plan age - ms (median/p99, wall; 1 answers)"
        );
    }
}
