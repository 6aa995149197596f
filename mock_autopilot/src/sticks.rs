//! MANUAL_CONTROL sticks as PX4 reads them (mavlink_receiver.cpp `handle_message_manual_control`, Sticks.cpp).
//!
//! Wire ranges: `x` (pitch, forward +) and `y` (roll, right +) and `r` (yaw, clockwise +) in -1000..=1000, `z`
//! (throttle) in 0..=1000 with 500 centred. A field outside its range reads as centred (0), as in PX4, which
//! leaves the field of its zero-initialised setpoint untouched.

use std::time::Duration;

use mavlink::dialects::common::MANUAL_CONTROL_DATA;

/// Normalised stick deflections, each in -1..=1.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sticks {
    /// Forward (+) / back, from `x`.
    pub pitch: f64,
    /// Right (+) / left, from `y`.
    pub roll: f64,
    /// Up (+) / down, from `z`: 500 is 0, 1000 is +1, 0 is -1.
    pub throttle: f64,
    /// Clockwise (+) / counter-clockwise, from `r`.
    pub yaw: f64,
}

impl Sticks {
    /// The sticks of a MANUAL_CONTROL message.
    pub fn from_message(m: &MANUAL_CONTROL_DATA) -> Self {
        let sym = |v: i16| {
            if (-1000..=1000).contains(&v) {
                f64::from(v) / 1000.0
            } else {
                0.0
            }
        };
        let throttle = if (0..=1000).contains(&m.z) {
            f64::from(m.z) / 500.0 - 1.0
        } else {
            0.0
        };
        Self {
            pitch: sym(m.x),
            roll: sym(m.y),
            throttle,
            yaw: sym(m.r),
        }
    }
}

/// PX4's stick shaping: a dead zone around the centre (`MPC_HOLD_DZ`), then the linear/cubic blend of `expo`.
pub fn expo_deadzone(value: f64, expo: f64, deadzone: f64) -> f64 {
    let x = value.clamp(-1.0, 1.0);
    let dz = deadzone.clamp(0.0, 0.99);
    let out = if x.abs() > dz {
        (x - x.signum() * dz) / (1.0 - dz)
    } else {
        0.0
    };
    let e = expo.clamp(0.0, 1.0);
    (1.0 - e) * out + e * out * out * out
}

/// The latest sticks and when they came (vehicle time), for the position mode and the RC-loss failsafe.
#[derive(Debug, Clone, Copy, Default)]
pub struct StickInput {
    latest: Option<(Sticks, Duration)>,
}

impl StickInput {
    /// Records a MANUAL_CONTROL received at `now`.
    pub fn on_message(&mut self, m: &MANUAL_CONTROL_DATA, now: Duration) {
        self.latest = Some((Sticks::from_message(m), now));
    }

    /// The sticks if the last message is at most `timeout` old (PX4's `COM_RC_LOSS_T`); None when lost.
    pub fn fresh(&self, now: Duration, timeout: Duration) -> Option<Sticks> {
        self.latest
            .filter(|(_, at)| now.saturating_sub(*at) <= timeout)
            .map(|(s, _)| s)
    }

    /// When the latest sticks came (vehicle time).
    pub fn received_at(&self) -> Option<Duration> {
        self.latest.map(|(_, at)| at)
    }

    /// Forgets every stick input (reboot).
    pub fn clear(&mut self) {
        self.latest = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(x: i16, y: i16, z: i16, r: i16) -> MANUAL_CONTROL_DATA {
        MANUAL_CONTROL_DATA {
            x,
            y,
            z,
            r,
            target: 1,
            ..Default::default()
        }
    }

    #[test]
    fn wire_ranges_map_like_px4() {
        let s = Sticks::from_message(&msg(1000, -500, 500, 250));
        assert_eq!((s.pitch, s.roll, s.throttle, s.yaw), (1.0, -0.5, 0.0, 0.25));
        assert_eq!(Sticks::from_message(&msg(0, 0, 1000, 0)).throttle, 1.0);
        assert_eq!(Sticks::from_message(&msg(0, 0, 0, 0)).throttle, -1.0);
        // Out of range reads as centred, the throttle included (-1 is below 0).
        let s = Sticks::from_message(&msg(i16::MAX, -1001, -1, 1001));
        assert_eq!(s, Sticks::default());
    }

    #[test]
    fn dead_zone_and_expo() {
        assert_eq!(expo_deadzone(0.05, 0.6, 0.1), 0.0);
        assert!((expo_deadzone(1.0, 0.6, 0.1) - 1.0).abs() < 1e-12);
        assert!((expo_deadzone(-1.0, 0.6, 0.1) + 1.0).abs() < 1e-12);
        // Halfway out of the dead zone: 0.4 * 0.5 + 0.6 * 0.125.
        assert!((expo_deadzone(0.55, 0.6, 0.1) - 0.275).abs() < 1e-12);
        assert!((expo_deadzone(0.5, 0.0, 0.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn sticks_go_stale_after_the_timeout() {
        let mut s = StickInput::default();
        assert_eq!(s.fresh(Duration::ZERO, Duration::from_millis(500)), None);
        s.on_message(&msg(100, 0, 500, 0), Duration::from_secs(1));
        let t = Duration::from_millis(500);
        assert!(s.fresh(Duration::from_millis(1500), t).is_some());
        assert!(s.fresh(Duration::from_millis(1501), t).is_none());
        s.clear();
        assert!(s.fresh(Duration::from_secs(1), t).is_none());
    }
}
