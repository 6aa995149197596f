//! Runs the steering (CPU work: render + plan) off the async threads, one computation at a time, so the
//! 10-20 Hz message streams keep their rate even when the planner is slower than that (a debug build, a fast
//! time scale): senders always use the latest finished result.

use std::time::{Duration, Instant};

use tokio::task::JoinHandle;

use super::steer::{Steer, SteerInput, SteerOutput};

type Job = JoinHandle<(Box<dyn Steer>, Option<SteerOutput>, Duration)>;

/// A finished computation: its result, the vehicle time and wall instant its input was taken at.
#[derive(Clone, Copy)]
struct Finished {
    out: Option<SteerOutput>,
    at: Duration,
    wall: Instant,
}

/// Runs one computation on the calling thread, timed (wall).
fn timed(steer: &mut Box<dyn Steer>, input: &SteerInput) -> (Option<SteerOutput>, Duration) {
    let t0 = Instant::now();
    let out = steer.steer(input);
    (out, t0.elapsed())
}

/// The steering and its one computation in flight.
pub struct SteerWorker {
    idle: Option<Box<dyn Steer>>,
    running: Option<(Job, Duration, Instant)>,
    latest: Option<Finished>,
    /// Computations finished.
    pub finished: u64,
    /// Wall time of each computation finished since the last [`SteerWorker::take_plan_times`].
    plan_times: Vec<Duration>,
}

impl SteerWorker {
    /// A worker for `steer`.
    pub fn new(steer: Box<dyn Steer>) -> Self {
        Self {
            idle: Some(steer),
            running: None,
            latest: None,
            finished: 0,
            plan_times: Vec::new(),
        }
    }

    /// Collects a finished computation and, when idle, starts one on `input` (vehicle time `now`).
    /// Returns false if the steering was lost (its task panicked or the runtime is stopping).
    pub async fn poll(&mut self, input: Option<SteerInput>, now: Duration) -> bool {
        if let Some((job, at, wall)) = self.running.take() {
            if !job.is_finished() {
                self.running = Some((job, at, wall));
                return true;
            }
            match job.await {
                Ok((steer, out, took)) => {
                    self.idle = Some(steer);
                    self.latest = Some(Finished { out, at, wall });
                    self.finished += 1;
                    self.plan_times.push(took);
                }
                Err(_) => return false,
            }
        }
        let Some(input) = input else { return true };
        if let Some(mut steer) = self.idle.take() {
            let wall = Instant::now();
            let job = tokio::task::spawn_blocking(move || {
                let (out, took) = timed(&mut steer, &input);
                (steer, out, took)
            });
            self.running = Some((job, now, wall));
        }
        true
    }

    /// Steers on `input` now and waits for the result (lockstep: the vehicle's clock stands still meanwhile).
    /// `None` if the steering was lost.
    pub async fn compute(&mut self, input: SteerInput, now: Duration) -> Option<Option<SteerOutput>> {
        if let Some((job, _, _)) = self.running.take() {
            let (steer, _, _) = job.await.ok()?;
            self.idle = Some(steer);
        }
        let mut steer = self.idle.take()?;
        let wall = Instant::now();
        let (steer, out, took) = tokio::task::spawn_blocking(move || {
            let (out, took) = timed(&mut steer, &input);
            (steer, out, took)
        })
        .await
        .ok()?;
        self.idle = Some(steer);
        self.latest = Some(Finished { out, at: now, wall });
        self.finished += 1;
        self.plan_times.push(took);
        Some(out)
    }

    /// The latest result whose input is at most `max_age` old: `Some(None)` means "cannot plan".
    pub fn latest(&self, now: Duration, max_age: Duration) -> Option<Option<SteerOutput>> {
        self.latest
            .filter(|f| now.saturating_sub(f.at) <= max_age)
            .map(|f| f.out)
    }

    /// The wall instant the latest result's input was taken at.
    pub fn latest_input_wall(&self) -> Option<Instant> {
        self.latest.map(|f| f.wall)
    }

    /// The wall time of each computation finished since the last call.
    pub fn take_plan_times(&mut self) -> Vec<Duration> {
        std::mem::take(&mut self.plan_times)
    }
}

impl Drop for SteerWorker {
    fn drop(&mut self) {
        if let Some((job, _, _)) = &self.running {
            job.abort();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::companion::steer::{Nav, Straight};

    #[tokio::test]
    async fn results_arrive_without_blocking() {
        let mut w = SteerWorker::new(Box::new(Straight));
        let input = SteerInput {
            now_s: 0.0,
            pos_ned: [0.0; 3],
            vel_ned: [0.0; 3],
            yaw_rad: 0.0,
            goal_ned: [5.0, 0.0, -2.0],
            prev_goal_ned: [0.0; 3],
            desired_vel_ned: None,
            nav: Nav::Mission,
            airborne: true,
        };
        let t = Duration::from_secs(1);
        assert!(
            w.poll(None, t).await,
            "no question: nothing to do, the steering is kept"
        );
        assert!(w.poll(Some(input), t).await);
        assert_eq!(w.latest(t, Duration::from_secs(1)), None, "nothing finished yet");
        for _ in 0..1000 {
            assert!(w.poll(Some(input), t).await);
            if w.finished > 0 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
        let got = w
            .latest(t, Duration::from_millis(500))
            .expect("finished")
            .expect("planned");
        assert_eq!(got.pos_ned, [5.0, 0.0, -2.0]);
        let now = w.compute(input, t).await.expect("steering kept").expect("planned");
        assert_eq!(now.pos_ned, [5.0, 0.0, -2.0], "computed on demand");
        assert_eq!(
            w.latest(t + Duration::from_secs(2), Duration::from_millis(500)),
            None,
            "too old"
        );
    }
}
