//! One frame for the judge, the planner and the obstacles: the **test's frame**, local NED about the test's
//! home (`TestCase::home`, metres, x North, y East, z down), where the obstacles and the mission's local points
//! are.
//!
//! PX4 reports LOCAL_POSITION_NED about its EKF origin: where the estimator started (the boot place, off by the
//! GPS noise of its first fix), not where the test's home is nor where this flight took off (a second flight on
//! one instance starts where the first landed). The horizontal offset between the two origins is measured once
//! per flight, before arming, from the vehicle's own data, and every position is shifted into the test's frame
//! (recorder, judge, planners) and every setpoint back ([`TestFrame::to_test`], [`TestFrame::to_vehicle`],
//! [`FramedSteer`]). Heights stay the vehicle's own (down from the EKF origin's ground): an altitude difference
//! between the two origins is GPS altitude noise or terrain, not height above the boxes' ground.

use serde::Serialize;

use super::steer::{Steer, SteerInput, SteerOutput};
use crate::bridge::wire::pose::PoseNed;
use crate::model::LocalProjection;

/// The name of the frame every report and CSV uses.
pub const FRAME_NAME: &str = "test_home_ned";

/// How the offset between the EKF origin and the test's home was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameSource {
    /// GPS_GLOBAL_ORIGIN (the EKF origin), projected about the test's home.
    GpsGlobalOrigin,
    /// A GLOBAL_POSITION_INT projected about the test's home, minus the LOCAL_POSITION_NED of the same moment.
    GlobalPositionInt,
}

/// PX4's local frame -> the test's frame: a horizontal shift.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TestFrame {
    /// How the shift was measured.
    pub source: FrameSource,
    /// Where the EKF origin lies in the test's frame: (North, East) metres.
    pub origin_offset_m: [f64; 2],
}

impl TestFrame {
    /// The frame from the EKF origin's latitude/longitude (GPS_GLOBAL_ORIGIN), degrees.
    pub fn from_ekf_origin(test_home: &LocalProjection, lat_deg: f64, lon_deg: f64) -> Self {
        let (n, e) = test_home.project(lat_deg, lon_deg);
        Self {
            source: FrameSource::GpsGlobalOrigin,
            origin_offset_m: [n, e],
        }
    }

    /// The frame from a global position (GLOBAL_POSITION_INT, degrees) and the local position (North, East
    /// metres) the vehicle reported for the same moment.
    pub fn from_global_position(test_home: &LocalProjection, lat_deg: f64, lon_deg: f64, local_ne: [f64; 2]) -> Self {
        let (n, e) = test_home.project(lat_deg, lon_deg);
        Self {
            source: FrameSource::GlobalPositionInt,
            origin_offset_m: [n - local_ne[0], e - local_ne[1]],
        }
    }

    /// A vehicle-frame (PX4 local NED) position in the test's frame.
    pub fn to_test(&self, ned: [f64; 3]) -> [f64; 3] {
        [
            ned[0] + self.origin_offset_m[0],
            ned[1] + self.origin_offset_m[1],
            ned[2],
        ]
    }

    /// A test-frame position in the vehicle's frame (PX4 local NED), for setpoints.
    pub fn to_vehicle(&self, ned: [f64; 3]) -> [f64; 3] {
        [
            ned[0] - self.origin_offset_m[0],
            ned[1] - self.origin_offset_m[1],
            ned[2],
        ]
    }

    /// A pose in the test's frame (velocity and yaw are the same in both frames).
    pub fn pose_to_test(&self, pose: &PoseNed) -> PoseNed {
        PoseNed {
            pos_ned: self.to_test(pose.pos_ned),
            ..*pose
        }
    }

    /// The horizontal distance between the EKF origin and the test's home, metres.
    pub fn offset_norm_m(&self) -> f64 {
        self.origin_offset_m[0].hypot(self.origin_offset_m[1])
    }
}

/// A steering that plans in the test's frame (where the obstacles are) for a vehicle that flies in its own:
/// positions and goals go in shifted by the frame, setpoints come out shifted back.
pub struct FramedSteer {
    frame: TestFrame,
    inner: Box<dyn Steer>,
}

impl FramedSteer {
    /// `inner` sees everything in the test's frame.
    pub fn new(frame: TestFrame, inner: Box<dyn Steer>) -> Self {
        Self { frame, inner }
    }
}

impl Steer for FramedSteer {
    fn steer(&mut self, input: &SteerInput) -> Option<SteerOutput> {
        let f = &self.frame;
        let framed = SteerInput {
            pos_ned: f.to_test(input.pos_ned),
            goal_ned: f.to_test(input.goal_ned),
            prev_goal_ned: f.to_test(input.prev_goal_ned),
            ..*input
        };
        let out = self.inner.steer(&framed)?;
        Some(SteerOutput {
            pos_ned: f.to_vehicle(out.pos_ned),
            ..out
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::companion::steer::Nav;
    use crate::model::{GeoPoint, SIM_HOME};

    fn home() -> LocalProjection {
        LocalProjection::new(SIM_HOME)
    }

    #[test]
    fn ekf_origin_north_east_of_home_shifts_positions_and_back() {
        let (lat, lon) = home().unproject(3.0, -4.0);
        let f = TestFrame::from_ekf_origin(&home(), lat, lon);
        assert_eq!(f.source, FrameSource::GpsGlobalOrigin);
        assert!((f.origin_offset_m[0] - 3.0).abs() < 1e-6 && (f.origin_offset_m[1] + 4.0).abs() < 1e-6);
        assert!((f.offset_norm_m() - 5.0).abs() < 1e-6);
        let p = [10.0, 20.0, -5.0];
        let t = f.to_test(p);
        assert!((t[0] - 13.0).abs() < 1e-6 && (t[1] - 16.0).abs() < 1e-6 && t[2] == -5.0);
        let back = f.to_vehicle(t);
        assert!((0..3).all(|k| (back[k] - p[k]).abs() < 1e-9));
        let pose = PoseNed {
            time_boot_ms: 7,
            pos_ned: p,
            vel_ned: [1.0, 2.0, 3.0],
            yaw_rad: Some(0.3),
        };
        let q = f.pose_to_test(&pose);
        assert_eq!((q.time_boot_ms, q.vel_ned, q.yaw_rad), (7, pose.vel_ned, pose.yaw_rad));
        assert_eq!(q.pos_ned, t);
    }

    #[test]
    fn global_position_fallback_subtracts_the_local_position_of_the_same_moment() {
        // The vehicle stands 50 m North of the test's home and its local position says (20, 0): the EKF
        // origin is 30 m North of home.
        let (lat, lon) = home().unproject(50.0, 0.0);
        let f = TestFrame::from_global_position(&home(), lat, lon, [20.0, 0.0]);
        assert_eq!(f.source, FrameSource::GlobalPositionInt);
        assert!((f.origin_offset_m[0] - 30.0).abs() < 1e-6 && f.origin_offset_m[1].abs() < 1e-6);
        let far = LocalProjection::new(GeoPoint {
            lat_deg: SIM_HOME.lat_deg + 1.0,
            ..SIM_HOME
        });
        let f = TestFrame::from_ekf_origin(&far, SIM_HOME.lat_deg, SIM_HOME.lon_deg);
        assert!(
            (f.origin_offset_m[0] + 111_195.0).abs() < 1.0,
            "{:?}",
            f.origin_offset_m
        );
        let json = serde_json::to_value(f).unwrap();
        assert_eq!(json["source"], "gps_global_origin");
    }

    /// Records what it was asked and answers a fixed test-frame setpoint.
    struct Probe(std::sync::Arc<std::sync::Mutex<Option<SteerInput>>>);

    impl Steer for Probe {
        fn steer(&mut self, input: &SteerInput) -> Option<SteerOutput> {
            *self.0.lock().unwrap() = Some(*input);
            Some(SteerOutput::position([100.0, 0.0, -10.0], Some(1.0)))
        }
    }

    #[test]
    fn framed_steer_plans_in_the_test_frame_and_answers_in_the_vehicle_frame() {
        let f = TestFrame {
            source: FrameSource::GpsGlobalOrigin,
            origin_offset_m: [5.0, -2.0],
        };
        let seen = std::sync::Arc::default();
        let mut s = FramedSteer::new(f, Box::new(Probe(std::sync::Arc::clone(&seen))));
        let input = SteerInput {
            now_s: 1.0,
            pos_ned: [0.0, 0.0, -10.0],
            vel_ned: [1.0, 0.0, 0.0],
            yaw_rad: 0.0,
            goal_ned: [40.0, 2.0, -10.0],
            prev_goal_ned: [-5.0, 2.0, -10.0],
            desired_vel_ned: None,
            nav: Nav::Mission,
            airborne: true,
        };
        let out = s.steer(&input).unwrap();
        assert_eq!(out.pos_ned, [95.0, 2.0, -10.0]);
        assert_eq!(out.yaw_rad, Some(1.0));
        let got = seen.lock().unwrap().unwrap();
        assert_eq!(got.pos_ned, [5.0, -2.0, -10.0]);
        assert_eq!(got.goal_ned, [45.0, 0.0, -10.0]);
        assert_eq!(got.prev_goal_ned, [0.0, 0.0, -10.0]);
        assert_eq!(got.vel_ned, input.vel_ned);
    }
}
