//! The test's commands table (Aerialist's `commands` CSV) as timed actions of the flight.

use std::collections::VecDeque;
use std::time::Duration;

use crate::bridge::wire::clock::secs;
use crate::model::Command as TestCommand;

/// What a row of the commands table asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Mode 3: arm and start the mission (offboard: switch to OFFBOARD and arm).
    Start,
    /// Mode 10: AUTO.TAKEOFF.
    Takeoff,
    /// Mode 11: AUTO.LAND.
    Land,
    /// Mode 20: arm.
    Arm,
    /// Mode 21: disarm.
    Disarm,
}

/// The commands table as timed actions (vehicle time after the flight starts); unsupported modes are warnings.
/// Without any command the mission starts at once.
pub fn schedule(commands: &[TestCommand], warnings: &mut Vec<String>) -> VecDeque<(Duration, Action)> {
    let mut out: Vec<(Duration, Action)> = Vec::new();
    for c in commands {
        let action = match c.mode {
            3 => Action::Start,
            10 => Action::Takeoff,
            11 => Action::Land,
            20 => Action::Arm,
            21 => Action::Disarm,
            m => {
                warnings.push(format!(
                    "command mode {m} at {} us is not supported by the bridge; skipped",
                    c.timestamp_us
                ));
                continue;
            }
        };
        out.push((secs(c.timestamp_us / 1e6), action));
    }
    if out.is_empty() {
        out.push((Duration::ZERO, Action::Start));
    }
    out.sort_by_key(|(t, _)| *t);
    out.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cmd(t_us: f64, mode: i64) -> TestCommand {
        TestCommand {
            timestamp_us: t_us,
            mode,
            x: 0.0,
            y: 0.0,
            z: 0.5,
            r: 0.0,
        }
    }

    #[test]
    fn commands_table_schedule() {
        let mut w = Vec::new();
        let s = schedule(&[cmd(2e6, 11), cmd(1.0, 3), cmd(5.0, 7)], &mut w);
        assert_eq!(
            s,
            VecDeque::from(vec![
                (Duration::from_micros(1), Action::Start),
                (Duration::from_secs(2), Action::Land)
            ])
        );
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("mode 7"));
        assert_eq!(
            schedule(&[], &mut w),
            VecDeque::from(vec![(Duration::ZERO, Action::Start)])
        );
    }
}
