//! The signals that ask a run to stop: Ctrl-C (SIGINT) from a terminal, SIGTERM from a scheduler (Slurm,
//! Kubernetes, systemd, `timeout`), SIGHUP from a closed terminal or SSH session. All three are handled alike:
//! the vehicles land and the finished flights are kept.

use tokio::runtime::Handle;
use tokio::signal::unix::{Signal, SignalKind, signal};

/// Handlers of the stop signals, registered when made: a signal that arrives from then on is caught, never
/// the default action (which would end the process at once).
pub struct StopSignals {
    interrupt: Signal,
    terminate: Signal,
    hangup: Signal,
}

impl StopSignals {
    /// Registers the handlers on `runtime`.
    pub fn register(runtime: &Handle) -> std::io::Result<Self> {
        let _inside = runtime.enter();
        Ok(Self {
            interrupt: signal(SignalKind::interrupt())?,
            terminate: signal(SignalKind::terminate())?,
            hangup: signal(SignalKind::hangup())?,
        })
    }

    /// Waits for the next stop signal and names it as a user knows it.
    pub async fn next(&mut self) -> &'static str {
        tokio::select! {
            _ = self.interrupt.recv() => "Ctrl-C",
            _ = self.terminate.recv() => "SIGTERM",
            _ = self.hangup.recv() => "SIGHUP",
        }
    }
}
