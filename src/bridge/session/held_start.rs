//! The start on simulated time: with prgenuav's simulator in lockstep and the avoidance companion holding
//! PX4's clock, ARM and MISSION_START go out together during the companion's hold at the next mark of a
//! simulated-time grid, so PX4 takes them at the same simulated instant in every run with the same seed,
//! however long the bridge took (wall time) to get there.

use std::time::Duration;

use mavlink::dialects::common::MavCmd;
use simulator::SimTime;

use super::context::Session;
use crate::bridge::options::FlyMode;
use crate::bridge::wire::command::AckedCommand;
use crate::bridge::wire::command_batch::AckedBatch;
use crate::bridge::wire::exchange::RetryPolicy;

/// The grid of simulated time the start is put on: coarse against the vehicle's readiness jitter (tenths of
/// a second), so two runs land on the same mark unless readiness straddles one.
pub const START_GRID: Duration = Duration::from_secs(5);
/// The longest wall wait for the hold (a grid period at the slowest pace PX4 keeps, and more).
const TURN_WAIT: Duration = Duration::from_secs(30);

/// The first mark of the grid after `now` (simulated time).
pub fn next_mark(now: SimTime) -> SimTime {
    let grid = START_GRID.as_micros() as u64;
    SimTime::from_micros((now.as_micros() / grid + 1) * grid)
}

/// Arms and starts the mission at a hold on the grid; `false` (nothing accepted, or not on simulated time):
/// start as usual. A refusal is a warning; the usual start then asks again.
pub async fn start_at_a_hold(s: &mut Session<'_>) -> bool {
    let Some(gate) = s.opts.sim_gate.clone() else {
        return false;
    };
    if s.opts.mode != FlyMode::Avoidance {
        return false;
    }
    let Some(turn) = gate.turn_at(next_mark(gate.clock().now()), TURN_WAIT).await else {
        return false;
    };
    let last = s.test.mission.items.len().saturating_sub(1) as f32;
    let batch = AckedBatch::new(vec![
        AckedCommand::new(
            s.target,
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            RetryPolicy::COMMAND,
        ),
        AckedCommand::new(
            s.target,
            MavCmd::MAV_CMD_MISSION_START,
            [0.0, last, 0.0, 0.0, 0.0, 0.0, 0.0],
            RetryPolicy::COMMAND,
        ),
    ]);
    let exchange = s.link.exchange(batch, &s.cancel);
    tokio::pin!(exchange);
    // Its first poll subscribes and sends both commands (UDP sends complete at once); then time may go on.
    let first = tokio::select! {
        biased;
        r = &mut exchange => Some(r),
        () = tokio::task::yield_now() => None,
    };
    drop(turn);
    let outcome = match first {
        Some(r) => r,
        None => exchange.await,
    };
    match outcome {
        Ok(()) => true,
        Err(e) => {
            s.warnings
                .push(format!("starting at a hold of simulated time: {e}; starting as usual"));
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_start_mark_is_the_next_multiple_of_the_grid() {
        assert_eq!(next_mark(SimTime::ZERO), SimTime::from_millis(5000));
        assert_eq!(next_mark(SimTime::from_millis(4999)), SimTime::from_millis(5000));
        assert_eq!(next_mark(SimTime::from_millis(5000)), SimTime::from_millis(10_000));
        assert_eq!(
            next_mark(SimTime::from_millis(12_290)),
            next_mark(SimTime::from_millis(12_640))
        );
    }
}
