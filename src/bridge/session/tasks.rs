//! Background tasks that end with the flight.

use tokio::task::JoinHandle;

/// Aborts its tasks when dropped, so no task outlives the flight.
#[derive(Default)]
pub struct Tasks(Vec<JoinHandle<()>>);

impl Tasks {
    /// Keeps `t` until the end of the flight.
    pub fn push(&mut self, t: JoinHandle<()>) {
        self.0.push(t);
    }

    /// Aborts every task and waits until each has ended (and dropped what it held, such as the link).
    pub async fn shutdown(&mut self) {
        for t in &self.0 {
            t.abort();
        }
        for t in self.0.drain(..) {
            let _ = t.await; // cancelled: nothing to report
        }
    }
}

impl Drop for Tasks {
    fn drop(&mut self) {
        for t in &self.0 {
            t.abort();
        }
    }
}
