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
}

impl Drop for Tasks {
    fn drop(&mut self) {
        for t in &self.0 {
            t.abort();
        }
    }
}
