//! The first step of a flight, before anything is uploaded or armed: where the vehicle stands against the
//! test's home ([`super::placement`]), re-anchoring the test at the vehicle's home if asked, and the test's
//! frame (the EKF origin's offset, [`crate::bridge::companion::frame`]).

use std::sync::OnceLock;
use std::time::Duration;

use mavlink::dialects::common::MavCmd;
use tokio::sync::broadcast;

use super::context::{Session, Stop};
use super::placement::{LatLonAlt, MIS_DIST_1WP_DEFAULT_M, VehiclePlacement, too_far, too_far_reason};
use super::report::Status;
use crate::bridge::companion::frame::TestFrame;
use crate::bridge::wire::vehicle::VehicleView;
use crate::model::{LocalProjection, TestCase};

/// How long to wait for GPS_GLOBAL_ORIGIN after asking (vehicle time).
const ORIGIN_WAIT: Duration = Duration::from_secs(3);
/// How long to wait for the GLOBAL_POSITION_INT fallback after that (vehicle time).
const FIX_WAIT: Duration = Duration::from_secs(3);
/// MAVLink id of GPS_GLOBAL_ORIGIN.
const GPS_GLOBAL_ORIGIN_ID: f32 = 49.0;

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
        self.placement = Some(VehiclePlacement {
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
        let otherwise = format!("assuming PX4's default {MIS_DIST_1WP_DEFAULT_M} m");
        self.read_param("MIS_DIST_1WP", &otherwise).await
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
