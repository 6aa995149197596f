//! Telemetry streams at PX4 onboard-link rates, adjustable with SET_MESSAGE_INTERVAL.
//!
//! Intervals are in simulated time, so a faster speed factor sends more messages per wall second.

use std::time::Duration;

/// Message ids of the streams.
pub mod ids {
    /// HEARTBEAT.
    pub const HEARTBEAT: u32 = 0;
    /// SYS_STATUS.
    pub const SYS_STATUS: u32 = 1;
    /// GPS_RAW_INT.
    pub const GPS_RAW_INT: u32 = 24;
    /// ATTITUDE.
    pub const ATTITUDE: u32 = 30;
    /// LOCAL_POSITION_NED.
    pub const LOCAL_POSITION_NED: u32 = 32;
    /// GLOBAL_POSITION_INT.
    pub const GLOBAL_POSITION_INT: u32 = 33;
    /// GPS_GLOBAL_ORIGIN (the EKF origin; sent once per boot and when it changes, or on request).
    pub const GPS_GLOBAL_ORIGIN: u32 = 49;
    /// MISSION_CURRENT.
    pub const MISSION_CURRENT: u32 = 42;
    /// VFR_HUD.
    pub const VFR_HUD: u32 = 74;
    /// AUTOPILOT_VERSION (on request only).
    pub const AUTOPILOT_VERSION: u32 = 148;
    /// HOME_POSITION.
    pub const HOME_POSITION: u32 = 242;
    /// EXTENDED_SYS_STATE.
    pub const EXTENDED_SYS_STATE: u32 = 245;
}

/// Default rates (Hz) of PX4's onboard MAVLink mode for the streams the mock produces.
const DEFAULT_RATES_HZ: &[(u32, f64)] = &[
    (ids::HEARTBEAT, 1.0),
    (ids::SYS_STATUS, 5.0),
    (ids::GPS_RAW_INT, 5.0),
    (ids::ATTITUDE, 50.0),
    (ids::LOCAL_POSITION_NED, 30.0),
    (ids::GLOBAL_POSITION_INT, 50.0),
    (ids::MISSION_CURRENT, 1.0),
    (ids::VFR_HUD, 10.0),
    (ids::HOME_POSITION, 0.5),
    (ids::EXTENDED_SYS_STATE, 5.0),
    // PX4 v1.14 src/modules/mavlink/mavlink_main.cpp line 1474 (onboard mode): 1 Hz, but the stream
    // (streams/GPS_GLOBAL_ORIGIN.hpp) only sends when the origin is new or changed, or on request.
    (ids::GPS_GLOBAL_ORIGIN, 1.0),
];

/// Streams that PX4 sends only when their content changes: once per boot here (the mock's EKF origin is fixed
/// where it booted), and again on request.
const ON_CHANGE: &[u32] = &[ids::GPS_GLOBAL_ORIGIN];

#[derive(Debug, Clone)]
struct Stream {
    id: u32,
    default: Duration,
    interval: Option<Duration>,
    next_due: Duration,
    /// An on-change stream whose content was sent since boot.
    sent: bool,
}

/// The stream table.
#[derive(Debug, Clone)]
pub struct Streams {
    entries: Vec<Stream>,
}

impl Default for Streams {
    fn default() -> Self {
        Self {
            entries: DEFAULT_RATES_HZ
                .iter()
                .map(|&(id, hz)| {
                    let d = Duration::from_secs_f64(1.0 / hz);
                    Stream {
                        id,
                        default: d,
                        interval: Some(d),
                        next_due: Duration::ZERO,
                        sent: false,
                    }
                })
                .collect(),
        }
    }
}

/// Whether SET_MESSAGE_INTERVAL was accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntervalResult {
    /// Applied.
    Accepted,
    /// Not a message the mock can stream.
    UnknownMessage,
    /// Interval below -1.
    BadInterval,
}

impl Streams {
    /// True when `id` is one of the streams.
    pub fn knows(&self, id: u32) -> bool {
        self.entries.iter().any(|s| s.id == id)
    }

    /// Append the ids of streams due at `now` and schedule their next send.
    pub fn due(&mut self, now: Duration, out: &mut Vec<u32>) {
        for s in &mut self.entries {
            if let Some(iv) = s.interval
                && now >= s.next_due
            {
                if ON_CHANGE.contains(&s.id) {
                    if s.sent {
                        continue;
                    }
                    s.sent = true;
                }
                out.push(s.id);
                // Catch up without bursts if a step was longer than the interval.
                s.next_due = (s.next_due + iv).max(now);
            }
        }
    }

    /// Every enabled stream is next due at `now` (their phase follows `now`, not boot).
    pub fn rephase(&mut self, now: Duration) {
        for s in &mut self.entries {
            s.next_due = now;
        }
    }

    /// SET_MESSAGE_INTERVAL semantics: -1 disables, 0 restores the default, >0 is µs.
    pub fn set_interval(&mut self, id: u32, interval_us: f32, now: Duration) -> IntervalResult {
        let Some(s) = self.entries.iter_mut().find(|s| s.id == id) else {
            return IntervalResult::UnknownMessage;
        };
        s.interval = match interval_us {
            -1.0 => None,
            0.0 => Some(s.default),
            v if v > 0.0 && v.is_finite() => {
                Some(Duration::from_secs_f64(f64::from(v) * 1e-6).max(Duration::from_micros(1000)))
            }
            _ => return IntervalResult::BadInterval,
        };
        s.next_due = now;
        IntervalResult::Accepted
    }

    /// Interval in µs for MESSAGE_INTERVAL (-1 disabled, 0 unknown message).
    pub fn interval_us(&self, id: u32) -> i32 {
        match self.entries.iter().find(|s| s.id == id) {
            Some(Stream { interval: Some(iv), .. }) => iv.as_micros().min(i32::MAX as u128) as i32,
            Some(_) => -1,
            None => 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(streams: &mut Streams, id: u32, secs: u64) -> usize {
        let mut n = 0;
        let mut out = Vec::new();
        for ms in 0..secs * 1000 {
            out.clear();
            streams.due(Duration::from_millis(ms), &mut out);
            n += out.iter().filter(|&&i| i == id).count();
        }
        n
    }

    #[test]
    fn default_rates_and_interval_changes() {
        let mut s = Streams::default();
        assert!((29..=31).contains(&count(&mut s.clone(), ids::LOCAL_POSITION_NED, 1)));
        assert_eq!(count(&mut s.clone(), ids::HEARTBEAT, 3), 3);
        assert_eq!(
            s.set_interval(ids::LOCAL_POSITION_NED, 10_000.0, Duration::ZERO),
            IntervalResult::Accepted
        );
        assert_eq!(s.interval_us(ids::LOCAL_POSITION_NED), 10_000);
        assert!((99..=101).contains(&count(&mut s.clone(), ids::LOCAL_POSITION_NED, 1)));
        assert_eq!(
            s.set_interval(ids::ATTITUDE, -1.0, Duration::ZERO),
            IntervalResult::Accepted
        );
        assert_eq!(count(&mut s.clone(), ids::ATTITUDE, 1), 0);
        assert_eq!(s.interval_us(ids::ATTITUDE), -1);
        assert_eq!(
            s.set_interval(ids::ATTITUDE, 0.0, Duration::ZERO),
            IntervalResult::Accepted
        );
        assert_eq!(s.interval_us(ids::ATTITUDE), 20_000);
        assert_eq!(
            s.set_interval(9999, 1.0, Duration::ZERO),
            IntervalResult::UnknownMessage
        );
        assert_eq!(
            s.set_interval(ids::ATTITUDE, -5.0, Duration::ZERO),
            IntervalResult::BadInterval
        );
        assert_eq!(
            s.set_interval(ids::ATTITUDE, f32::NAN, Duration::ZERO),
            IntervalResult::BadInterval
        );
    }
}
