//! Where the vehicle is on Earth, from its own messages: HOME_POSITION, GPS_GLOBAL_ORIGIN (its EKF origin) and
//! GLOBAL_POSITION_INT paired with the LOCAL_POSITION_NED of the same moment. Feeds [`crate::bridge::companion::frame`].

use mavlink::dialects::common::MavMessage;

use super::pose::PoseNed;
use crate::model::GeoPoint;

/// A global and a local position reported for (about) the same moment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalFix {
    /// Latitude, longitude (degrees), altitude AMSL (metres) from GLOBAL_POSITION_INT.
    pub global: GeoPoint,
    /// The local (North, East) metres of the closest LOCAL_POSITION_NED in time.
    pub local_ne: [f64; 2],
    /// |time_boot_ms difference| of the two messages, milliseconds.
    pub skew_ms: u32,
}

/// The vehicle's placement as last heard.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GeoView {
    /// HOME_POSITION (latitude, longitude degrees; altitude AMSL metres).
    pub home: Option<GeoPoint>,
    /// GPS_GLOBAL_ORIGIN: the EKF's local origin.
    pub ekf_origin: Option<GeoPoint>,
    /// The best-paired GLOBAL_POSITION_INT so far (the latest with the smallest skew).
    pub fix: Option<GlobalFix>,
}

/// A GLOBAL_POSITION_INT this far in time from the last LOCAL_POSITION_NED is not paired with it.
pub const MAX_SKEW_MS: u32 = 100;

fn deg(e7: i32) -> f64 {
    f64::from(e7) / 1e7
}

impl GeoView {
    /// Folds one message in; `pose` is the latest local position before it.
    pub fn update(&mut self, msg: &MavMessage, pose: Option<&PoseNed>) {
        match msg {
            MavMessage::HOME_POSITION(h) => {
                self.home = Some(GeoPoint {
                    lat_deg: deg(h.latitude),
                    lon_deg: deg(h.longitude),
                    alt_m: f64::from(h.altitude) / 1000.0,
                });
            }
            MavMessage::GPS_GLOBAL_ORIGIN(o) => {
                self.ekf_origin = Some(GeoPoint {
                    lat_deg: deg(o.latitude),
                    lon_deg: deg(o.longitude),
                    alt_m: f64::from(o.altitude) / 1000.0,
                });
            }
            MavMessage::GLOBAL_POSITION_INT(g) if g.lat != 0 || g.lon != 0 => {
                let Some(p) = pose else { return };
                let skew_ms = g.time_boot_ms.abs_diff(p.time_boot_ms);
                if skew_ms > MAX_SKEW_MS || self.fix.is_some_and(|f| f.skew_ms < skew_ms) {
                    return;
                }
                self.fix = Some(GlobalFix {
                    global: GeoPoint {
                        lat_deg: deg(g.lat),
                        lon_deg: deg(g.lon),
                        alt_m: f64::from(g.alt) / 1000.0,
                    },
                    local_ne: [p.pos_ned[0], p.pos_ned[1]],
                    skew_ms,
                });
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::{GLOBAL_POSITION_INT_DATA, GPS_GLOBAL_ORIGIN_DATA, HOME_POSITION_DATA};

    fn pose(ms: u32, n: f64) -> PoseNed {
        PoseNed {
            time_boot_ms: ms,
            pos_ned: [n, 2.0, 0.0],
            ..PoseNed::default()
        }
    }

    fn global(ms: u32, lat_e7: i32) -> MavMessage {
        MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
            time_boot_ms: ms,
            lat: lat_e7,
            lon: 85_455_940,
            alt: 488_000,
            ..Default::default()
        })
    }

    #[test]
    fn home_origin_and_paired_fixes() {
        let mut g = GeoView::default();
        g.update(
            &MavMessage::HOME_POSITION(HOME_POSITION_DATA {
                latitude: 473_977_420,
                longitude: 85_455_940,
                altitude: 488_500,
                ..Default::default()
            }),
            None,
        );
        assert_eq!(g.home.map(|h| (h.lat_deg, h.alt_m)), Some((47.397742, 488.5)));
        g.update(
            &MavMessage::GPS_GLOBAL_ORIGIN(GPS_GLOBAL_ORIGIN_DATA {
                latitude: 473_977_000,
                longitude: 85_455_000,
                altitude: 487_000,
                time_usec: 0,
            }),
            None,
        );
        assert_eq!(g.ekf_origin.map(|o| o.lon_deg), Some(8.5455));
        g.update(&global(1000, 473_977_420), None);
        assert!(g.fix.is_none(), "no local position to pair with");
        g.update(&global(1500, 473_977_420), Some(&pose(1000, 1.0)));
        assert!(g.fix.is_none(), "500 ms apart");
        g.update(&global(1020, 473_977_420), Some(&pose(1000, 1.0)));
        assert_eq!(g.fix.map(|f| (f.local_ne, f.skew_ms)), Some(([1.0, 2.0], 20)));
        g.update(&global(1050, 473_977_430), Some(&pose(1050, 3.0)));
        assert_eq!(g.fix.map(|f| (f.local_ne[0], f.skew_ms)), Some((3.0, 0)));
        let no_fix = MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
            time_boot_ms: 1050,
            ..Default::default()
        });
        g.update(&no_fix, Some(&pose(1050, 9.0)));
        assert_eq!(g.fix.map(|f| f.local_ne[0]), Some(3.0), "no fix (0, 0) is ignored");
    }
}
