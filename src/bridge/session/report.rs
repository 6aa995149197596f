//! The outcome of one flight: status, the true minimum distance judged from the recorded positions (the
//! competition's binned value, the raw one, per obstacle, the closest approach), the LFS prediction beside it,
//! and link statistics. Serialises to the CLI's JSON.

use serde::Serialize;

use crate::judge::{AboveTop, ClosestApproach, Judge, ObstacleDistance, judge_in_frame};
use crate::model::{Obstacle, Trajectory};

use super::clock_watch::ClockReport;
use super::identify::VehicleIdentity;
use super::placement::VehiclePlacement;
use crate::bridge::companion::frame::{FRAME_NAME, FrameSource, TestFrame};
use crate::bridge::companion::timing::TimingReport;
use crate::bridge::options::FlyMode;
use crate::bridge::wire::link::LinkStats;
use crate::bridge::wire::notices::VehicleMessage;

/// How a flight ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Flown to the end, landed and disarmed.
    Landed,
    /// The vehicle entered an obstacle.
    Collision,
    /// Still flying at the timeout (LAND commanded).
    Timeout,
    /// The vehicle went silent or rebooted.
    LinkLost,
    /// Cancelled (Ctrl-C) mid-flight (LAND commanded).
    Aborted,
    /// The vehicle refused the mission, a parameter, a mode or arming.
    Rejected,
}

impl Status {
    /// Every status.
    pub const ALL: [Status; 6] = [
        Status::Landed,
        Status::Collision,
        Status::Timeout,
        Status::LinkLost,
        Status::Aborted,
        Status::Rejected,
    ];

    /// The JSON spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Landed => "landed",
            Status::Collision => "collision",
            Status::Timeout => "timeout",
            Status::LinkLost => "link_lost",
            Status::Aborted => "aborted",
            Status::Rejected => "rejected",
        }
    }

    /// True when the flight ran to its end (a measurement exists).
    pub fn completed(self) -> bool {
        matches!(self, Status::Landed | Status::Collision)
    }
}

/// Link numbers as reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct LinkReport {
    /// Messages received from the vehicle.
    pub packets_received: u64,
    /// Protocol retries.
    pub retries: u64,
    /// Messages from other systems, ignored.
    pub packets_ignored: u64,
}

impl From<LinkStats> for LinkReport {
    fn from(s: LinkStats) -> Self {
        Self {
            packets_received: s.packets_received,
            retries: s.retries,
            packets_ignored: s.packets_ignored,
        }
    }
}

/// One flight's report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlightReport {
    /// The judge edition of every distance here.
    pub judge: Judge,
    /// Its definition in one line.
    pub judge_definition: &'static str,
    /// The frame of the trajectory and the closest approach: `test_home_ned` (local NED about the test's home).
    pub frame: &'static str,
    /// How the vehicle's local frame was placed in it (`null` if the flight stopped before).
    pub frame_source: Option<FrameSource>,
    /// Where the vehicle's EKF origin lies in the test's frame, (North, East) metres.
    pub frame_origin_offset_m: Option<[f64; 2]>,
    /// Where the vehicle stood against the test's home (and the boxes' latitude/longitude).
    pub placement: Option<VehiclePlacement>,
    /// The competition's minimum distance (0.5 s bins), metres; `null` without obstacles or positions.
    pub min_distance: Option<f64>,
    /// The continuous minimum distance, metres.
    pub min_distance_raw: Option<f64>,
    /// Per obstacle.
    pub per_obstacle: Vec<ObstacleDistance>,
    /// Where the raw path came closest (the test's frame, x North, y East, z up).
    pub closest_approach: Option<ClosestApproach>,
    /// Set when the vehicle was above the box's top there: the judged distance is not the vehicle's.
    pub above_top: Option<AboveTop>,
    /// How the flight ended.
    pub status: Status,
    /// Why, in words, when not `landed`.
    pub reason: Option<String>,
    /// Seconds of recorded flight (vehicle time).
    pub flight_time_s: f64,
    /// The low-fidelity simulator's prediction for the same test, metres.
    pub lfs_min_distance: Option<f64>,
    /// Link statistics.
    pub link: LinkReport,
    /// The mode flown.
    pub mode: FlyMode,
    /// Whether the obstacles were on the vehicle as a geofence.
    pub fence_uploaded: bool,
    /// The vehicle's warnings (STATUSTEXT) and the bridge's own.
    pub warnings: Vec<String>,
    /// Vehicle seconds waited for the vehicle to become ready to arm (`null` if it never was).
    pub ready_wait_s: Option<f64>,
    /// Every STATUSTEXT of severity WARNING or worse, with its time and severity.
    pub vehicle_messages: Vec<VehicleMessage>,
    /// The vehicle's clock rate against the time scale.
    pub clock: Option<ClockReport>,
    /// How fast the avoidance companion answered (wall milliseconds; avoidance mode only).
    pub companion_timing: Option<TimingReport>,
    /// The vehicle's MPC_XY_CRUISE the planner used, m/s (`null`: not read, PX4's default 5 m/s).
    pub planner_cruise_m_s: Option<f64>,
    /// Collision Prevention flights: `CP_DIST` and whether the vehicle came inside it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collision_prevention: Option<crate::judge::cp_verdict::CpVerdict>,
    /// Avoidance flights: the companion's answers, planned and mirrored (a starved flight mirrored more than
    /// 1 %).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub companion_answers: Option<crate::bridge::companion::answers::AnswerCounts>,
    /// The vehicle that flew, as it identified itself (`null`: none answered).
    pub vehicle: Option<VehicleIdentity>,
    /// Positions recorded.
    pub samples: usize,
    /// The recorded trajectory (not in the JSON; see the CSV).
    #[serde(skip)]
    pub trajectory: Trajectory,
}

/// Inputs of [`FlightReport::judge`] besides the trajectory.
#[derive(Debug, Clone)]
pub struct Ending {
    /// Status before judging (collision may override landed or timeout).
    pub status: Status,
    /// Why.
    pub reason: Option<String>,
    /// Mode flown.
    pub mode: FlyMode,
    /// Fence on the vehicle.
    pub fence_uploaded: bool,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Link counters.
    pub link: LinkStats,
    /// LFS prediction.
    pub lfs_min_distance: Option<f64>,
    /// The judge edition.
    pub judge: Judge,
    /// The test's frame, if it was measured (the trajectory is in it).
    pub frame: Option<TestFrame>,
    /// The vehicle against the test's home.
    pub placement: Option<VehiclePlacement>,
    /// Readiness wait, vehicle seconds.
    pub ready_wait_s: Option<f64>,
    /// The vehicle's messages.
    pub vehicle_messages: Vec<VehicleMessage>,
    /// The clock.
    pub clock: Option<ClockReport>,
    /// The companion's answer timing.
    pub companion_timing: Option<TimingReport>,
    /// The planner's cruise speed as read from the vehicle.
    pub planner_cruise_m_s: Option<f64>,
    /// Who flew.
    pub vehicle: Option<VehicleIdentity>,
}

impl FlightReport {
    /// Judges `trajectory` (in the test's frame) against `obstacles` and assembles the report.
    pub fn judge(trajectory: Trajectory, obstacles: &[Obstacle], end: Ending) -> Self {
        let judged = judge_in_frame(&trajectory, obstacles, end.judge);
        let mut status = end.status;
        let mut reason = end.reason;
        if let Some(j) = &judged
            && j.collision
            && matches!(status, Status::Landed | Status::Timeout)
        {
            status = Status::Collision;
            let c = j.closest;
            reason = Some(format!(
                "entered obstacle {} at t = {:.1} s, ({:.2}, {:.2}, {:.2}) m",
                c.obstacle, c.t_s, c.x, c.y, c.z
            ));
        }
        Self {
            judge: end.judge,
            judge_definition: end.judge.description(),
            frame: FRAME_NAME,
            frame_source: end.frame.map(|f| f.source),
            frame_origin_offset_m: end.frame.map(|f| f.origin_offset_m),
            placement: end.placement,
            min_distance: judged.as_ref().map(|j| j.min_distance),
            min_distance_raw: judged.as_ref().map(|j| j.min_distance_raw),
            per_obstacle: judged.as_ref().map(|j| j.per_obstacle.clone()).unwrap_or_default(),
            closest_approach: judged.as_ref().map(|j| j.closest),
            above_top: judged.as_ref().and_then(|j| j.above_top),
            status,
            reason,
            flight_time_s: trajectory.duration_s(),
            lfs_min_distance: end.lfs_min_distance,
            link: end.link.into(),
            mode: end.mode,
            fence_uploaded: end.fence_uploaded,
            warnings: collapse(end.warnings),
            ready_wait_s: end.ready_wait_s,
            vehicle_messages: end.vehicle_messages,
            clock: end.clock,
            companion_timing: end.companion_timing,
            planner_cruise_m_s: end.planner_cruise_m_s,
            collision_prevention: None,
            companion_answers: None,
            vehicle: end.vehicle,
            samples: trajectory.samples.len(),
            trajectory,
        }
    }
}

/// Each distinct warning once, in order of first appearance, with a count when repeated.
pub fn collapse(warnings: Vec<String>) -> Vec<String> {
    let mut seen: Vec<(String, usize)> = Vec::new();
    for w in warnings {
        match seen.iter_mut().find(|(s, _)| *s == w) {
            Some((_, n)) => *n += 1,
            None => seen.push((w, 1)),
        }
    }
    seen.into_iter()
        .map(|(w, n)| if n == 1 { w } else { format!("{w} (x{n})") })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Sample;

    fn ending(status: Status) -> Ending {
        Ending {
            status,
            reason: None,
            mode: FlyMode::Mission,
            fence_uploaded: false,
            warnings: vec![],
            link: LinkStats::default(),
            lfs_min_distance: Some(1.0),
            judge: Judge::E2025,
            frame: None,
            placement: None,
            ready_wait_s: None,
            vehicle_messages: vec![],
            clock: None,
            companion_timing: None,
            planner_cruise_m_s: None,
            vehicle: None,
        }
    }

    fn line(y: f64) -> Trajectory {
        Trajectory::new(
            (0..=20)
                .map(|i| Sample {
                    t_s: f64::from(i) * 0.1,
                    x: f64::from(i),
                    y,
                    z: 5.0,
                    r: None,
                })
                .collect(),
        )
    }

    #[test]
    fn judged_and_serialised() {
        let o = Obstacle::new(2.0, 2.0, 10.0, 10.0, 3.0, 0.0);
        let r = FlightReport::judge(line(0.0), &[o], ending(Status::Landed));
        assert_eq!(r.status, Status::Landed);
        assert!((r.min_distance.unwrap() - 2.0).abs() < 1e-9);
        assert!((r.flight_time_s - 2.0).abs() < 1e-9);
        let json = serde_json::to_value(&r).unwrap();
        for key in [
            "min_distance",
            "min_distance_raw",
            "per_obstacle",
            "status",
            "flight_time_s",
            "lfs_min_distance",
            "link",
            "closest_approach",
            "judge",
            "judge_definition",
            "frame",
        ] {
            assert!(json.get(key).is_some(), "{key} missing in {json}");
        }
        assert_eq!(json["status"], "landed");
        assert_eq!(
            (&json["judge"], &json["frame"]),
            (&"2025".into(), &"test_home_ned".into())
        );
        assert!(json["link"].get("packets_received").is_some() && json["link"].get("retries").is_some());
        assert!(json.get("trajectory").is_none());
    }

    #[test]
    fn collision_overrides_landed_but_not_aborted() {
        let o = Obstacle::new(2.0, 2.0, 10.0, 10.0, 0.0, 0.0);
        let r = FlightReport::judge(line(0.0), &[o], ending(Status::Landed));
        assert_eq!(r.status, Status::Collision);
        assert!(r.reason.unwrap().contains("entered obstacle 0"));
        let r = FlightReport::judge(line(0.0), &[o], ending(Status::Aborted));
        assert_eq!(r.status, Status::Aborted);
        assert_eq!(serde_json::to_value(Status::LinkLost).unwrap(), "link_lost");
        assert_eq!(
            collapse(vec!["a".into(), "b".into(), "a".into()]),
            vec!["a (x2)".to_string(), "b".into()]
        );
        let empty = FlightReport::judge(Trajectory::default(), &[o], ending(Status::Rejected));
        assert_eq!(empty.min_distance, None);
    }

    #[test]
    fn a_flight_over_a_low_box_lands_named_with_its_height_above_the_top() {
        // The path at 5 m crosses a 3 m box: no collision, 2 m above its top.
        let o = Obstacle::new(2.0, 2.0, 3.0, 10.0, 0.0, 0.0);
        let r = FlightReport::judge(line(0.0), &[o], ending(Status::Landed));
        assert_eq!(r.status, Status::Landed);
        let a = r.above_top.expect("above the top");
        assert!(a.obstacle == 0 && (a.height_m - 2.0).abs() < 1e-9, "{a:?}");
        let json = serde_json::to_value(&r).unwrap();
        assert_eq!(json["above_top"]["obstacle"], 0);
        let beside = Obstacle::new(2.0, 2.0, 10.0, 10.0, 3.0, 0.0);
        assert!(
            FlightReport::judge(line(0.0), &[beside], ending(Status::Landed))
                .above_top
                .is_none()
        );
    }
}
