//! The Collision Prevention flight's two streams: the pilot's `MANUAL_CONTROL` sticks (Position mode) at
//! 20 Hz and the virtual lidar's `OBSTACLE_DISTANCE` scans at the sensor's rate, both in vehicle time. The
//! boxes are in the test's frame and the vehicle flies in its own, so positions go through the frame.

use std::sync::Arc;
use std::time::Duration;

use mavlink::dialects::common::{MANUAL_CONTROL_DATA, MavDistanceSensor, MavFrame, MavMessage, OBSTACLE_DISTANCE_DATA};
use tokio::sync::watch;
use tokio::task::JoinHandle;

use super::frame::TestFrame;
use crate::bridge::wire::exchange::Target;
use crate::bridge::wire::link::{Link, Sender};
use crate::bridge::wire::pose::PoseNed;
use crate::bridge::wire::vehicle::VehicleView;
use crate::lfs::cp_pilot::{CpPilot, PilotStep, Sticks};
use crate::lfs::range_sensor::{RangeSensor, SECTORS, SensorScene};

/// Stick period (20 Hz; PX4 counts manual control as lost after COM_RC_LOSS_T, 0.5 s by default).
pub const STICK_PERIOD: Duration = Duration::from_millis(50);

/// What the session needs to know of the pilot.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CpProgress {
    /// Sticks and scans are going out (the switch to Position mode may follow).
    pub streaming: bool,
    /// Every waypoint reached (the session commands LAND).
    pub finished: bool,
    /// The pilot gave up on a waypoint: why (the session ends the flight as a timeout).
    pub stuck: Option<String>,
    /// Scans sent.
    pub scans: u64,
}

/// The streams' inputs.
pub struct CpFeed {
    /// The pilot over the goals in the vehicle's frame.
    pub pilot: CpPilot,
    /// The sensor.
    pub sensor: RangeSensor,
    /// The test's boxes.
    pub scene: SensorScene,
    /// The test's frame (`None`: the vehicle's frame is the test's).
    pub frame: Option<TestFrame>,
}

/// Streams sticks and scans until aborted; the progress tells the session when to switch modes and land.
pub fn spawn(link: Arc<Link>, target: Target, feed: CpFeed) -> (JoinHandle<()>, watch::Receiver<CpProgress>) {
    let (tx, rx) = watch::channel(CpProgress::default());
    (tokio::spawn(run(link, target, feed, tx)), rx)
}

async fn run(link: Arc<Link>, target: Target, mut feed: CpFeed, tx: watch::Sender<CpProgress>) {
    let clock = link.clock();
    let mut rx = link.subscribe();
    let mut view = VehicleView::default();
    let scan_period = Duration::from_secs_f64(feed.sensor.period_s());
    let (mut next_stick, mut next_scan) = (clock.now(), clock.now());
    loop {
        let now = clock.now();
        if let Some(pose) = view.pose {
            let yaw = pose.yaw_rad.unwrap_or(0.0);
            if now >= next_scan {
                next_scan = now + scan_period;
                let msg = scan_msg(&feed, &pose, yaw);
                let _ = link.send(Sender::Gcs, &msg).await;
                tx.send_modify(|p| p.scans += 1);
            }
            if now >= next_stick {
                next_stick = now + STICK_PERIOD;
                // The pilot's clock starts at arming: on the ground the sticks stay centred. It runs on the
                // pose's own time, which a lockstep vehicle holds while it waits for the sticks.
                let step = match view.armed {
                    true => feed
                        .pilot
                        .step(f64::from(pose.time_boot_ms) / 1000.0, pose.pos_ned, yaw),
                    false => PilotStep::Fly(Sticks::CENTRED),
                };
                let sticks = match step {
                    PilotStep::Fly(s) => s,
                    PilotStep::Finished => {
                        tx.send_if_modified(|p| !std::mem::replace(&mut p.finished, true));
                        Sticks::CENTRED
                    }
                    PilotStep::Stuck(why) => {
                        tx.send_if_modified(|p| p.stuck.replace(why).is_none());
                        Sticks::CENTRED
                    }
                };
                let _ = link.send(Sender::Gcs, &stick_msg(target, &sticks)).await;
                tx.send_if_modified(|p| !std::mem::replace(&mut p.streaming, true));
            }
        }
        let wake = clock
            .wall_until(next_stick.min(next_scan))
            .max(Duration::from_millis(1));
        view.update_within(&mut rx, &clock, wake).await;
    }
}

/// `MANUAL_CONTROL` for the sticks, addressed to the vehicle.
pub fn stick_msg(target: Target, s: &Sticks) -> MavMessage {
    let (x, y, z, r) = s.to_mavlink();
    MavMessage::MANUAL_CONTROL(MANUAL_CONTROL_DATA {
        target: target.system,
        x,
        y,
        z,
        r,
        ..MANUAL_CONTROL_DATA::DEFAULT
    })
}

/// One `OBSTACLE_DISTANCE` scan from the vehicle's pose (its own frame), ray cast in the test's frame.
fn scan_msg(feed: &CpFeed, pose: &PoseNed, yaw: f64) -> MavMessage {
    let pos = feed.frame.map_or(pose.pos_ned, |f| f.to_test(pose.pos_ned));
    let distances = feed.sensor.scan(&feed.scene, pos, yaw);
    scan_to_msg(&feed.sensor, distances, u64::from(pose.time_boot_ms) * 1000)
}

/// The message PX4 v1.16 reads: body FRD sectors, integer and float increment alike, centimetres.
pub fn scan_to_msg(sensor: &RangeSensor, distances: [u16; SECTORS], time_usec: u64) -> MavMessage {
    MavMessage::OBSTACLE_DISTANCE(OBSTACLE_DISTANCE_DATA {
        time_usec,
        sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
        distances,
        increment: sensor.increment_deg.round() as u8,
        increment_f: sensor.increment_deg as f32,
        min_distance: sensor.min_cm,
        max_distance: sensor.max_cm,
        angle_offset: 0.0,
        frame: MavFrame::MAV_FRAME_BODY_FRD,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_carry_px4s_conventions() {
        let s = RangeSensor::default();
        let mut d = [s.max_cm + 1; SECTORS];
        d[3] = 250;
        let MavMessage::OBSTACLE_DISTANCE(m) = scan_to_msg(&s, d, 7) else {
            panic!()
        };
        assert_eq!(
            (m.increment, m.increment_f, m.min_distance, m.max_distance),
            (5, 5.0, 20, 1200)
        );
        assert_eq!(m.frame, MavFrame::MAV_FRAME_BODY_FRD);
        assert_eq!((m.distances[3], m.distances[0]), (250, 1201));
        let t = Target {
            system: 1,
            component: 1,
        };
        let MavMessage::MANUAL_CONTROL(c) = stick_msg(t, &Sticks::CENTRED) else {
            panic!()
        };
        assert_eq!((c.target, c.x, c.y, c.z, c.r), (1, 0, 0, 500, 0));
    }
}
