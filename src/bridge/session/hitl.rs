//! A board in the loop (`--hitl`) must be in HITL mode before anything is set, uploaded or armed: with
//! `SYS_HITL` 0 it flies on its own sensors and drives its real outputs, so the simulated flight is not the
//! one it flies, and arming it could spin real motors.

use std::time::Duration;

use super::context::{Session, Stop};
use super::report::Status;
use crate::bridge::wire::exchange::{ProtocolError, RetryPolicy};
use crate::bridge::wire::param_read::ParamRead;

/// The parameter and the value of PX4's HITL mode (sensors over MAVLink).
pub const SYS_HITL: (&str, f64) = ("SYS_HITL", 1.0);

/// The refusal of a board that is not in HITL mode, saying `what` was found and what to do.
pub fn hitl_refusal(what: &str) -> String {
    format!(
        "not a board in HITL mode ({what}): set SYS_HITL 1 (airframe 1001 \"HIL Quadcopter X\" sets it) on a \
         firmware with pwm_out_sim (CONFIG_MODULES_SIMULATION_PWM_OUT_SIM=y), reboot the board, then fly again; \
         nothing was set or armed"
    )
}

impl Session<'_> {
    /// With [`crate::bridge::FlyOptions::require_hitl`]: `SYS_HITL` must read 1, or the flight is refused.
    pub async fn check_hitl(&mut self) -> Result<(), Stop> {
        if !self.opts.require_hitl {
            return Ok(());
        }
        let retry = RetryPolicy {
            timeout: Duration::from_secs(1),
            max_retries: 3,
        };
        let read = ParamRead::new(self.target, SYS_HITL.0, retry);
        match self.link.exchange(read, &self.cancel).await {
            Ok(v) if v == SYS_HITL.1 => Ok(()),
            Ok(v) => Err(Stop::new(Status::Rejected, hitl_refusal(&format!("SYS_HITL is {v}")))),
            Err(ProtocolError::Cancelled) => Err(Stop::new(Status::Aborted, "cancelled")),
            Err(e) => Err(Stop::new(
                Status::Rejected,
                hitl_refusal(&format!("SYS_HITL could not be read: {e}")),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_refusal_names_the_parameter_the_airframe_and_the_firmware() {
        let r = hitl_refusal("SYS_HITL is 0");
        for part in [
            "SYS_HITL is 0",
            "SYS_HITL 1",
            "airframe 1001",
            "HIL Quadcopter X",
            "pwm_out_sim",
        ] {
            assert!(r.contains(part), "{part}: {r}");
        }
    }
}
