//! The lockstep policy on a fake wall clock.

use std::time::{Duration, Instant};

use super::*;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

#[test]
fn it_freewheels_at_real_time_before_the_first_answer() {
    let t0 = Instant::now();
    let mut l = Lockstep::new(LockstepConfig::default(), t0);
    assert_eq!(l.decide(t0), Decision::Step { timed_out: false });
    l.stepped(t0, false);
    // The next step is due one step (4 ms) of wall time later at speed 1, whether PX4 answers or not.
    assert_eq!(l.decide(t0 + ms(1)), Decision::WaitUntil(t0 + STEP));
    assert_eq!(l.decide(t0 + ms(4)), Decision::Step { timed_out: false });
    l.stepped(t0 + ms(4), false);
    assert_eq!(l.stats().freewheel_steps, 2);
    assert!(!l.is_locked());
}

#[test]
fn once_answered_each_step_waits_for_the_answer() {
    let t0 = Instant::now();
    let mut l = Lockstep::new(LockstepConfig::default(), t0);
    l.stepped(t0, false);
    l.on_actuators(t0 + ms(1));
    assert!(l.is_locked());
    // Uncapped: the answer releases the next step at once.
    assert_eq!(l.decide(t0 + ms(1)), Decision::Step { timed_out: false });
    l.stepped(t0 + ms(1), false);
    // No answer yet: wait for it, at most actuator_wait.
    assert_eq!(l.decide(t0 + ms(2)), Decision::WaitUntil(t0 + ms(101)));
    l.on_actuators(t0 + ms(3));
    assert_eq!(l.decide(t0 + ms(3)), Decision::Step { timed_out: false });
}

#[test]
fn a_missing_answer_steps_anyway_after_the_bound_and_counts() {
    let t0 = Instant::now();
    let mut l = Lockstep::new(LockstepConfig::default(), t0);
    l.stepped(t0, false);
    l.on_actuators(t0);
    l.stepped(t0, false);
    assert_eq!(l.decide(t0 + ms(100)), Decision::Step { timed_out: true });
    l.stepped(t0 + ms(100), true);
    assert_eq!(l.stats().timeouts, 1);
    // Silence beyond link_lost_after: PX4 is lost.
    assert_eq!(l.decide(t0 + ms(5000)), Decision::LinkLost);
}

#[test]
fn the_speed_cap_paces_the_steps() {
    let t0 = Instant::now();
    let cfg = LockstepConfig {
        speed_cap: Some(2.0),
        ..LockstepConfig::default()
    };
    let mut l = Lockstep::new(cfg, t0);
    l.on_actuators(t0);
    l.stepped(t0, false);
    l.on_actuators(t0);
    // Twice real time: a 4 ms step every 2 ms of wall time.
    assert_eq!(l.decide(t0), Decision::WaitUntil(t0 + ms(2)));
    assert_eq!(l.decide(t0 + ms(2)), Decision::Step { timed_out: false });
}

#[test]
fn a_px4_that_never_answers_is_reported() {
    let t0 = Instant::now();
    let l = Lockstep::new(LockstepConfig::default(), t0);
    assert_eq!(l.decide(t0 + Duration::from_secs(120)), Decision::NeverAnswered);
}

#[test]
fn the_pace_holds_over_many_steps_and_restarts_after_a_stall() {
    let t0 = Instant::now();
    let cfg = LockstepConfig {
        speed_cap: Some(4.0),
        ..LockstepConfig::default()
    };
    let mut l = Lockstep::new(cfg, t0);
    l.on_actuators(t0);
    let mut now = t0;
    let mut steps = 0;
    // A PX4 answering at once: 1 s of wall time allows 4 s of simulated time, 1000 steps.
    while now < t0 + Duration::from_secs(1) {
        match l.decide(now) {
            Decision::Step { .. } => {
                l.stepped(now, false);
                l.on_actuators(now);
                steps += 1;
            }
            Decision::WaitUntil(t) => now = t,
            other => panic!("{other:?}"),
        }
    }
    assert!((999..=1001).contains(&steps), "{steps}");
    // After a 1 s stall, one step at once, then the pace again (no burst of 250 steps).
    now += Duration::from_secs(1);
    assert_eq!(l.decide(now), Decision::Step { timed_out: false });
    l.stepped(now, false);
    l.on_actuators(now);
    assert_eq!(l.decide(now), Decision::Step { timed_out: false });
    l.stepped(now, false);
    l.on_actuators(now);
    assert_eq!(l.decide(now), Decision::WaitUntil(now + ms(1)));
}
