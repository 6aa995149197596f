//! One flight from connection to report, in steps that share a [`context::Session`]: [`run`] (connect, lock
//! on, hand over), [`anchor`] (where the vehicle stands, the test's frame), [`setup`] (parameters, mission,
//! fence, streams), [`ready`] (readiness and arming), [`flight`] (the commands table, following the flight,
//! landing on faults), then the [`report`].

pub mod anchor;
pub mod capability;
pub mod clock_watch;
pub mod context;
pub mod cp_setup;
pub mod flight;
pub mod gazebo;
pub mod held_start;
pub mod hitl;
pub mod identify;
pub mod placement;
pub mod ready;
pub mod recorder;
pub mod report;
pub mod run;
pub mod schedule;
pub mod setup;
pub mod tasks;
