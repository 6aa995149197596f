//! The vehicle's clock against wall time: every LOCAL_POSITION_NED, ATTITUDE and GLOBAL_POSITION_INT carries
//! `time_boot_ms`, so the rate at which the vehicle's time runs is measured over a sliding window of wall time
//! and compared with the time scale the bridge's timers assume ([`crate::bridge::wire::clock`]). A disagreement of more than
//! 20 % is said at once (a simulator at 10x flown with time scale 1 would otherwise wait 10x too long).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use mavlink::dialects::common::MavMessage;
use serde::Serialize;
use tokio::sync::broadcast;
use tokio::task::JoinHandle;

use super::tasks::Tasks;
use crate::bridge::options::FlyOptions;
use crate::bridge::wire::link::{Inbound, Link};
use crate::bridge::wire::notices::{Notice, NoticeSink, tell};

/// Wall time the rate is measured over (the newest samples).
pub const WINDOW: Duration = Duration::from_secs(5);
/// No estimate before the samples span this much wall time (arrival jitter is a few ms).
pub const MIN_SPAN: Duration = Duration::from_millis(1000);
/// Tolerated relative disagreement between the measured rate and the time scale.
pub const TOLERANCE: f64 = 0.2;

/// The vehicle's `time_boot_ms`, if the message carries it.
pub fn boot_ms(msg: &MavMessage) -> Option<u32> {
    match msg {
        MavMessage::LOCAL_POSITION_NED(m) => Some(m.time_boot_ms),
        MavMessage::ATTITUDE(m) => Some(m.time_boot_ms),
        MavMessage::GLOBAL_POSITION_INT(m) => Some(m.time_boot_ms),
        _ => None,
    }
}

/// Vehicle seconds per wall second over a sliding window.
#[derive(Debug, Clone, Default)]
pub struct RateEstimator {
    samples: VecDeque<(Instant, u32)>,
}

impl RateEstimator {
    /// Adds a sample; a boot clock going back (reboot) starts afresh.
    pub fn push(&mut self, wall: Instant, boot_ms: u32) {
        if self
            .samples
            .back()
            .is_some_and(|&(_, b)| boot_ms.saturating_add(1000) < b)
        {
            self.samples.clear();
        }
        self.samples.push_back((wall, boot_ms));
        while self
            .samples
            .front()
            .is_some_and(|&(w, _)| wall.saturating_duration_since(w) > WINDOW)
        {
            self.samples.pop_front();
        }
    }

    /// The rate over the window, once it spans [`MIN_SPAN`] of wall time.
    pub fn rate(&self) -> Option<f64> {
        let (&(w0, b0), &(w1, b1)) = (self.samples.front()?, self.samples.back()?);
        let wall = w1.saturating_duration_since(w0);
        (wall >= MIN_SPAN && b1 >= b0).then(|| f64::from(b1 - b0) / 1000.0 / wall.as_secs_f64())
    }
}

/// A rate rounded the way speed factors are given: whole numbers from 2 up, tenths below.
pub fn nice(rate: f64) -> f64 {
    if rate >= 2.0 {
        rate.round()
    } else {
        (rate * 10.0).round() / 10.0
    }
}

/// The clock as reported.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClockReport {
    /// The vehicle's clock rate last measured, vehicle seconds per wall second.
    pub measured_rate: Option<f64>,
    /// The time scale the bridge's timers used.
    pub time_scale: f64,
    /// True when the time scale was measured at connection rather than given.
    pub detected: bool,
    /// Set when the measured rate disagreed with the time scale by more than 20 %.
    pub warning: Option<String>,
}

/// The warning for `rate` against `scale`, if they disagree; in lockstep the vehicle waits for the companion,
/// so only a faster clock is a disagreement there.
pub fn disagreement(rate: f64, scale: f64, lockstep: bool) -> Option<String> {
    let ratio = rate / scale;
    let off = if lockstep {
        ratio > 1.0 + TOLERANCE
    } else {
        (ratio - 1.0).abs() > TOLERANCE
    };
    off.then(|| {
        format!(
            "the vehicle's clock runs {rate:.1}x real time but the bridge's timers assume {scale}x: use --time-scale {}",
            nice(rate)
        )
    })
}

/// Measures from `rx` until the samples span `span` of wall time (bounded by `limit`); `None` without samples.
pub async fn measure(rx: &mut broadcast::Receiver<Arc<Inbound>>, span: Duration, limit: Duration) -> Option<f64> {
    let mut est = RateEstimator::default();
    let end = tokio::time::Instant::now() + limit;
    let mut first: Option<Instant> = None;
    loop {
        tokio::select! {
            r = rx.recv() => match r {
                Ok(inb) => if let Some(ms) = boot_ms(&inb.msg) {
                    let now = Instant::now();
                    est.push(now, ms);
                    if now.saturating_duration_since(*first.get_or_insert(now)) >= span {
                        return est.rate();
                    }
                },
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => return est.rate(),
            },
            _ = tokio::time::sleep_until(end) => return est.rate(),
        }
    }
}

/// Rate measured at connection before it is used as the time scale, wall time (bounded by twice that).
pub const DETECT_SPAN: Duration = Duration::from_millis(1500);

/// At connection: measures the vehicle's clock and adopts it when `opts.detect_time_scale`, then watches it for
/// the whole session (the task joins `tasks`). Returns the report the watch keeps up to date.
pub async fn start(link: &Link, opts: &FlyOptions, tasks: &mut Tasks) -> Arc<Mutex<ClockReport>> {
    let mut measured = None;
    if opts.detect_time_scale {
        // A fresh subscription: messages buffered meanwhile would arrive in a burst and fake a fast clock.
        measured = measure(&mut link.subscribe(), DETECT_SPAN, 2 * DETECT_SPAN).await;
        if let Some(r) = measured {
            link.set_time_scale(nice(r).max(0.1));
        }
    }
    let report = Arc::new(Mutex::new(ClockReport {
        measured_rate: measured.map(|r| (r * 100.0).round() / 100.0),
        time_scale: link.clock().scale(),
        detected: measured.is_some(),
        warning: None,
    }));
    tasks.push(spawn_watch(
        link.subscribe(),
        opts.lockstep.is_some(),
        report.clone(),
        opts.notices.clone(),
    ));
    report
}

/// Watches the clock for the whole session, updating `report` and telling `sink` the first disagreement.
pub fn spawn_watch(
    mut rx: broadcast::Receiver<Arc<Inbound>>,
    lockstep: bool,
    report: Arc<Mutex<ClockReport>>,
    sink: Option<NoticeSink>,
) -> JoinHandle<()> {
    tokio::spawn(async move {
        let mut est = RateEstimator::default();
        let mut checked = Instant::now();
        loop {
            let inb = match rx.recv().await {
                Ok(inb) => inb,
                Err(broadcast::error::RecvError::Lagged(_)) => continue,
                Err(broadcast::error::RecvError::Closed) => return,
            };
            let Some(ms) = boot_ms(&inb.msg) else { continue };
            let now = Instant::now();
            est.push(now, ms);
            if now.saturating_duration_since(checked) < Duration::from_millis(250) {
                continue;
            }
            checked = now;
            let Some(rate) = est.rate() else { continue };
            let mut r = report.lock().unwrap_or_else(|p| p.into_inner());
            r.measured_rate = Some((rate * 100.0).round() / 100.0);
            if r.warning.is_none()
                && let Some(w) = disagreement(rate, r.time_scale, lockstep)
            {
                tell(sink.as_ref(), &Notice::Clock(w.clone()));
                r.warning = Some(w);
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_over_a_sliding_window() {
        let t0 = Instant::now();
        let mut e = RateEstimator::default();
        // 10x: 100 ms of vehicle time per 10 ms of wall time.
        for i in 0..50u32 {
            e.push(t0 + Duration::from_millis(u64::from(i) * 10), 5_000 + i * 100);
        }
        assert_eq!(e.rate(), None, "0.49 s of wall time is too short");
        for i in 50..700u32 {
            e.push(t0 + Duration::from_millis(u64::from(i) * 10), 5_000 + i * 100);
        }
        assert!((e.rate().unwrap() - 10.0).abs() < 1e-9);
        // Then 1x: the window forgets the 10x rate.
        let t1 = t0 + Duration::from_millis(7000);
        for i in 0..700u32 {
            e.push(t1 + Duration::from_millis(u64::from(i) * 10), 75_000 + i * 10);
        }
        assert!((e.rate().unwrap() - 1.0).abs() < 1e-9);
        // A reboot starts afresh.
        e.push(t1 + Duration::from_secs(8), 10);
        assert_eq!(e.rate(), None);
    }

    #[test]
    fn disagreement_names_the_factor() {
        let w = disagreement(9.8, 1.0, false).unwrap();
        assert!(w.contains("9.8x") && w.ends_with("use --time-scale 10"), "{w}");
        assert_eq!(disagreement(1.1, 1.0, false), None);
        assert!(disagreement(0.5, 1.0, false).unwrap().ends_with("--time-scale 0.5"));
        assert_eq!(disagreement(20.0, 100.0, true), None, "lockstep waits: slower is fine");
        assert!(disagreement(150.0, 100.0, true).is_some());
        assert_eq!(nice(1.04), 1.0);
        assert_eq!(nice(19.6), 20.0);
    }
}
