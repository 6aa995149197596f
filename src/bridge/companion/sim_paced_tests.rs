use super::*;
use crate::bridge::companion::frame::FrameSource;
use crate::bridge::companion::steer::{SteerInput, SteerOutput};
use crate::bridge::companion::trajectory_points::empty_trajectory;
use crate::bridge::wire::link::memory::{self, MemoryTransport};
use crate::bridge::wire::link::{AVOIDANCE_COMPONENT_ID, Transport};
use crate::model::SIM_HOME;
use mavlink::MavHeader;
use mavlink::dialects::common::{HEARTBEAT_DATA, MavAutopilot, MavModeFlag, MavType};
use simulator::hil::gate::{Gate, GateConfig, Passage, gate};
use simulator::{SimClock, SimConfig, Simulation};
use std::sync::Mutex;

#[test]
fn holds_fall_on_the_period_grid() {
    let p = Duration::from_millis(100);
    assert_eq!(next_instant(SimTime::ZERO, p), SimTime::from_millis(100));
    assert_eq!(next_instant(SimTime::from_millis(100), p), SimTime::from_millis(200));
    assert_eq!(
        next_instant(SimTime::from_millis(4_236), p),
        SimTime::from_millis(4_300)
    );
}

#[test]
fn the_truth_is_reported_in_px4s_frame_with_its_heading() {
    let mut sim = Simulation::new(SimConfig::default());
    sim.vehicle_mut().body.position_ned_m = nalgebra::Vector3::new(12.0, -3.0, -10.0);
    sim.vehicle_mut().body.attitude = nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, 0.5);
    let truth = sim.truth();
    let frame = TestFrame {
        source: FrameSource::GpsGlobalOrigin,
        origin_offset_m: [2.0, 1.0],
    };
    let p = truth_pose(&truth, &LocalProjection::new(SIM_HOME), Some(frame));
    assert!(
        (p.pos_ned[0] - 10.0).abs() < 1e-6 && (p.pos_ned[1] + 4.0).abs() < 1e-6,
        "{p:?}"
    );
    assert_eq!(p.pos_ned[2], -10.0);
    assert!((p.yaw_rad.unwrap() - 0.5).abs() < 1e-9);
}

/// Records the pose it was asked to plan from and steers to the goal.
struct Probe(Arc<Mutex<Vec<SteerInput>>>);

impl Steer for Probe {
    fn steer(&mut self, input: &SteerInput) -> Option<SteerOutput> {
        self.0.lock().unwrap().push(*input);
        Some(SteerOutput::position(input.goal_ned, None))
    }
}

fn px4() -> MavHeader {
    MavHeader {
        system_id: 1,
        component_id: 1,
        sequence: 0,
    }
}

/// PX4's request at PX4 time `ms`: point 1 a plain waypoint 30 m North at 10 m.
async fn ask(vehicle: &MemoryTransport, ms: u64) {
    let mut t = empty_trajectory(ms * 1000, 2);
    (t.pos_x[0], t.pos_y[0], t.pos_z[0]) = (1.0, 0.0, -10.0);
    (t.pos_x[1], t.pos_y[1], t.pos_z[1]) = (30.0, 0.0, -10.0);
    t.command[1] = u16::MAX;
    vehicle
        .send(px4(), &MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(t))
        .await
        .unwrap();
}

struct Bench {
    gate: Gate,
    vehicle: Arc<MemoryTransport>,
    asked: Arc<Mutex<Vec<SteerInput>>>,
    sim: Simulation,
}

async fn bench() -> Bench {
    let (ours, vehicle) = memory::pair();
    let link = Arc::new(Link::new(Arc::new(ours), VehicleClock::new(1.0)));
    let (gate, handle) = gate(GateConfig {
        period: None,
        max_hold: Duration::from_secs(2),
    });
    let paced = SimPaced {
        gate: SimGate::new(handle, SimClock::default(), SIM_HOME),
        frame: None,
        test_home: SIM_HOME,
        period: Duration::from_millis(100),
    };
    let asked = Arc::default();
    let target = Target {
        system: 1,
        component: 1,
    };
    let steer = Box::new(Probe(Arc::clone(&asked)));
    tokio::spawn(run(link, target, steer, Arc::default(), paced));
    let vehicle = Arc::new(vehicle);
    let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
        base_mode: MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
        ..HEARTBEAT_DATA::DEFAULT
    });
    vehicle.send(px4(), &hb).await.unwrap();
    Bench {
        gate,
        vehicle,
        asked,
        sim: Simulation::new(SimConfig::default()),
    }
}

impl Bench {
    /// The simulator at `ms` of simulated time, the vehicle 5 m North at 10 m.
    async fn pass(&mut self, ms: u64) -> Passage {
        self.sim.vehicle_mut().body.position_ned_m = nalgebra::Vector3::new(5.0, 0.0, -10.0);
        let truth = GroundTruth {
            time: SimTime::from_millis(ms),
            ..self.sim.truth()
        };
        tokio::time::timeout(Duration::from_secs(5), self.gate.pass(&truth))
            .await
            .expect("a hold ends")
    }

    /// The companion's answers the vehicle has received so far.
    async fn answers(&self) -> Vec<f32> {
        let mut got = Vec::new();
        while let Ok(Ok((h, m))) = tokio::time::timeout(Duration::from_millis(50), self.vehicle.recv()).await {
            if let (AVOIDANCE_COMPONENT_ID, MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(a)) = (h.component_id, m) {
                got.push(a.pos_x[0]);
            }
        }
        got
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn simulated_time_waits_at_each_period_for_the_answer_planned_on_the_true_pose() {
    let mut b = bench().await;
    // Give the companion a moment to register its first instant.
    tokio::time::sleep(Duration::from_millis(100)).await;
    ask(&b.vehicle, 40).await;
    tokio::time::sleep(Duration::from_millis(50)).await;
    assert_eq!(b.pass(96).await, Passage::Open, "before the first instant");
    assert_eq!(b.pass(100).await, Passage::Released);
    // The answer is out before the simulator went on: planned towards the waypoint, from the true pose.
    assert_eq!(b.answers().await, vec![30.0]);
    let asked = b.asked.lock().unwrap().clone();
    assert_eq!(asked.len(), 1);
    let p = asked[0].pos_ned;
    assert!((p[0] - 5.0).abs() < 1e-6 && p[1].abs() < 1e-6 && p[2] == -10.0, "{p:?}");
    assert_eq!(asked[0].now_s, 0.1, "planned for the hold's instant");
    assert_eq!(b.pass(104).await, Passage::Open);
    assert_eq!(b.pass(200).await, Passage::Released, "one period on");
    assert_eq!(b.answers().await, vec![30.0]);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_overdue_request_is_waited_for_briefly_and_a_stale_one_gets_no_answer() {
    let mut b = bench().await;
    tokio::time::sleep(Duration::from_millis(100)).await;
    ask(&b.vehicle, 0).await;
    tokio::time::sleep(Duration::from_millis(50)).await;
    assert_eq!(b.pass(100).await, Passage::Released);
    assert_eq!(b.answers().await.len(), 1);
    // At 300 ms the request of 200 ms is overdue: the hold waits for it (bounded), then answers anyway.
    let t = Instant::now();
    assert_eq!(b.pass(300).await, Passage::Released);
    assert!(t.elapsed() >= OVERDUE_WAIT, "waited {:?}", t.elapsed());
    assert_eq!(b.answers().await.len(), 1, "the old request is still fresh");
    // A second later PX4 has stopped asking: no answer, no wait.
    let t = Instant::now();
    assert_eq!(b.pass(1400).await, Passage::Released);
    assert!(t.elapsed() < Duration::from_secs(1));
    assert!(b.answers().await.is_empty());
}
