//! Before anything is uploaded or armed: where the vehicle stands against the test's home, and the test's frame.
//!
//! 1. HOME_POSITION (asked for once). 2. PX4 refuses a mission whose first waypoint is farther than MIS_DIST_1WP
//!    from the vehicle (PX4 v1.14 `src/modules/navigator/MissionFeasibility/FeasibilityChecker.cpp` line 608,
//!    default 900 m in `src/modules/navigator/mission_params.c` line 89): a vehicle whose home is farther than
//!    that from the test's home is refused here, before the upload, unless the test is re-anchored at the
//!    vehicle's home ([`ANCHOR_OPTION`], [`crate::model::TestCase::anchored_at`]). 3. The offset of the EKF
//!    origin in the test's frame ([`super::frame`]): GPS_GLOBAL_ORIGIN (asked for with MAV_CMD_REQUEST_MESSAGE
//!    49, since PX4 sends it only once and on change), or a GLOBAL_POSITION_INT as a fallback.
#![allow(deprecated)]

use std::sync::OnceLock;
use std::time::Duration;

use mavlink::dialects::common::MavCmd;
use serde::Serialize;
use tokio::sync::broadcast;

use super::exchange::{ProtocolError, Retry};
use super::frame::TestFrame;
use super::param_read::ParamRead;
use super::report::Status;
use super::session::{Session, Stop};
use super::vehicle::VehicleView;
use crate::model::{GeoPoint, LocalProjection, TestCase};

/// The option that re-anchors a test at the vehicle's home (named in refusals).
pub const ANCHOR_OPTION: &str = "--anchor-at-vehicle-home";
/// PX4 v1.14's MIS_DIST_1WP default, metres (`mission_params.c` line 89), used if the vehicle has no such
/// parameter.
pub const MIS_DIST_1WP_DEFAULT_M: f64 = 900.0;
/// How long to wait for GPS_GLOBAL_ORIGIN after asking (vehicle time).
const ORIGIN_WAIT: Duration = Duration::from_secs(3);
/// How long to wait for the GLOBAL_POSITION_INT fallback after that (vehicle time).
const FIX_WAIT: Duration = Duration::from_secs(3);
/// MAVLink id of GPS_GLOBAL_ORIGIN.
const GPS_GLOBAL_ORIGIN_ID: f32 = 49.0;

/// A latitude/longitude/altitude as reported.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LatLonAlt {
    /// Degrees North.
    pub lat_deg: f64,
    /// Degrees East.
    pub lon_deg: f64,
    /// Metres AMSL (0 for box centres, which are on the ground of the test's home).
    pub alt_m: f64,
}

impl From<GeoPoint> for LatLonAlt {
    fn from(g: GeoPoint) -> Self {
        Self {
            lat_deg: g.lat_deg,
            lon_deg: g.lon_deg,
            alt_m: g.alt_m,
        }
    }
}

/// Where the vehicle stood against the test's home.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Placement {
    /// The vehicle's HOME_POSITION.
    pub vehicle_home: LatLonAlt,
    /// The test's home it was compared with (after re-anchoring: the vehicle's home).
    pub test_home: LatLonAlt,
    /// Horizontal distance from the test's (original) home to the vehicle's, metres.
    pub distance_m: f64,
    /// The vehicle's MIS_DIST_1WP, metres (`None`: not readable, PX4's default assumed).
    pub mis_dist_1wp_m: Option<f64>,
    /// The test was re-anchored at the vehicle's home.
    pub anchored: bool,
    /// Refused: farther than MIS_DIST_1WP without re-anchoring.
    pub too_far: bool,
    /// Where the boxes' centres are (latitude, longitude about the flown test's home).
    pub obstacle_centres: Vec<LatLonAlt>,
}

/// Whether a vehicle `distance_m` from the test's home may fly it unanchored: `limit_m` <= 0 disables PX4's
/// check, as in PX4.
pub fn too_far(distance_m: f64, limit_m: f64) -> bool {
    limit_m > 0.0 && distance_m > limit_m
}

/// The refusal's words.
pub fn too_far_reason(distance_m: f64, limit_m: f64) -> String {
    format!(
        "the vehicle's home is {distance_m:.0} m from the test's home, farther than MIS_DIST_1WP ({limit_m:.0} m): PX4 \
         would refuse the mission; fly with {ANCHOR_OPTION} to re-anchor the test (mission, obstacles, fence) where \
         the vehicle stands"
    )
}

impl<'a> Session<'a> {
    /// Home, the MIS_DIST_1WP check or re-anchoring (then `self.test` is the anchored test, kept in `slot`), and
    /// the test's frame. Nothing is uploaded or armed here.
    pub async fn place(&mut self, slot: &'a OnceLock<TestCase>) -> Result<(), Stop> {
        self.wait_home().await?;
        let home = self
            .view
            .geo
            .home
            .ok_or_else(|| Stop::new(Status::Rejected, "HOME_POSITION without a position"))?;
        let limit = self.read_mis_dist_1wp().await?;
        let (n, e) = LocalProjection::new(self.test.home).project(home.lat_deg, home.lon_deg);
        let distance_m = n.hypot(e);
        let anchored = self.opts.anchor_at_vehicle_home;
        let refused = !anchored && too_far(distance_m, limit.unwrap_or(MIS_DIST_1WP_DEFAULT_M));
        if anchored {
            let t = self.test.anchored_at(home);
            self.test = slot.get_or_init(|| t);
        }
        self.placement = Some(Placement {
            vehicle_home: home.into(),
            test_home: self.test.home.into(),
            distance_m,
            mis_dist_1wp_m: limit,
            anchored,
            too_far: refused,
            obstacle_centres: self
                .test
                .obstacle_centres_deg()
                .into_iter()
                .map(|(lat_deg, lon_deg)| LatLonAlt {
                    lat_deg,
                    lon_deg,
                    alt_m: 0.0,
                })
                .collect(),
        });
        if refused {
            let reason = too_far_reason(distance_m, limit.unwrap_or(MIS_DIST_1WP_DEFAULT_M));
            return Err(Stop::new(Status::Rejected, reason));
        }
        self.frame = Some(self.locate_frame().await?);
        Ok(())
    }

    /// MIS_DIST_1WP; a vehicle without it (not PX4) gets PX4's default and a warning.
    async fn read_mis_dist_1wp(&mut self) -> Result<Option<f64>, Stop> {
        let quick = Retry {
            timeout: Duration::from_secs(1),
            max_retries: 3,
        };
        match self
            .link
            .exchange(ParamRead::new(self.target, "MIS_DIST_1WP", quick), &self.cancel)
            .await
        {
            Ok(v) => Ok(Some(v)),
            Err(ProtocolError::Cancelled) => Err(Stop::new(Status::Aborted, "cancelled")),
            Err(e) => {
                self.warnings.push(format!(
                    "MIS_DIST_1WP not readable ({e}); assuming PX4's default {MIS_DIST_1WP_DEFAULT_M} m"
                ));
                Ok(None)
            }
        }
    }

    /// The EKF origin's offset in the test's frame, from GPS_GLOBAL_ORIGIN or else GLOBAL_POSITION_INT.
    async fn locate_frame(&mut self) -> Result<TestFrame, Stop> {
        self.drain();
        if self.view.geo.ekf_origin.is_none() {
            let p = [GPS_GLOBAL_ORIGIN_ID, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
            if let Err(e) = self.command(MavCmd::MAV_CMD_REQUEST_MESSAGE, p).await {
                self.warnings.push(format!("requesting GPS_GLOBAL_ORIGIN: {e}"));
            }
            self.wait_for(ORIGIN_WAIT, |v| v.geo.ekf_origin.is_some()).await?;
        }
        let projection = LocalProjection::new(self.test.home);
        if let Some(o) = self.view.geo.ekf_origin {
            return Ok(TestFrame::from_ekf_origin(&projection, o.lat_deg, o.lon_deg));
        }
        self.wait_for(FIX_WAIT, |v| v.geo.fix.is_some()).await?;
        match self.view.geo.fix {
            Some(f) => {
                self.warnings.push(
                    "no GPS_GLOBAL_ORIGIN from the vehicle; the test's frame comes from GLOBAL_POSITION_INT".into(),
                );
                Ok(TestFrame::from_global_position(
                    &projection,
                    f.global.lat_deg,
                    f.global.lon_deg,
                    f.local_ne,
                ))
            }
            None => Err(Stop::new(
                Status::Rejected,
                "cannot place the vehicle in the test's frame: neither GPS_GLOBAL_ORIGIN nor GLOBAL_POSITION_INT \
                 with LOCAL_POSITION_NED arrived (no GPS?)",
            )),
        }
    }

    /// Folds messages in until `done` holds or `wait` (vehicle time) passes; Ctrl-C aborts.
    async fn wait_for(&mut self, wait: Duration, done: impl Fn(&VehicleView) -> bool) -> Result<(), Stop> {
        let clock = self.link.clock();
        let deadline = clock.now() + wait;
        self.drain();
        while !done(&self.view) && clock.now() < deadline {
            let sleep = clock.wall_until(deadline);
            tokio::select! {
                biased;
                _ = self.cancel.cancelled() => return Err(Stop::new(Status::Aborted, "cancelled before the flight")),
                r = self.rx.recv() => match r {
                    Ok(inb) => self.view.update(&inb.msg, clock.now()),
                    Err(broadcast::error::RecvError::Lagged(_)) => {}
                    Err(broadcast::error::RecvError::Closed) => tokio::time::sleep(sleep).await,
                },
                _ = tokio::time::sleep(sleep) => {}
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px4s_first_waypoint_rule() {
        assert!(!too_far(899.0, 900.0));
        assert!(too_far(901.0, 900.0));
        assert!(!too_far(1e6, 0.0), "0 disables the check, as in PX4");
        assert!(!too_far(1e6, -1.0));
        let r = too_far_reason(1234.4, 900.0);
        assert!(
            r.contains(ANCHOR_OPTION) && r.contains("1234 m") && r.contains("900 m"),
            "{r}"
        );
    }
}
