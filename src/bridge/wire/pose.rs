//! The vehicle's pose as PX4 reports it, in PX4's own local frame (before any shift into the test's frame).

/// Pose from LOCAL_POSITION_NED and ATTITUDE: local NED metres and m/s, yaw radians clockwise from North.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PoseNed {
    /// Vehicle boot time of the position, milliseconds.
    pub time_boot_ms: u32,
    /// North, East, Down position, metres.
    pub pos_ned: [f64; 3],
    /// North, East, Down velocity, m/s.
    pub vel_ned: [f64; 3],
    /// Yaw (heading), radians clockwise from North; `None` before the first ATTITUDE.
    pub yaw_rad: Option<f64>,
}
