//! A 360-degree planar scanning lidar over the test's boxes, reported as MAVLink `OBSTACLE_DISTANCE` sectors.
//!
//! It mimics a Slamtec RPLIDAR A2-class scanner mounted level on top of the vehicle: a full turn every
//! 0.1 s (10 Hz), 0.2-12 m range, about one reading per degree. The driver reduces each 5-degree sector to
//! its closest reading, so the 72 sectors match PX4 Collision Prevention's map (5-degree bins) one to one.
//!
//! Frame: `MAV_FRAME_BODY_FRD`, sector `j` centred `j x 5` degrees clockwise from the vehicle's nose
//! (angle_offset 0). World inputs are local NED about the test's home (`x` North, `y` East, metres) with
//! the yaw clockwise from North, radians. Distances are centimetres. PX4 v1.16 reads a sector as:
//! `UINT16_MAX` = no data (unknown: Collision Prevention does not move into it unless `CP_GO_NO_DATA`),
//! `max_distance + 1` = nothing within range (known free), anything below = an obstacle at that distance.
//! A full circle leaves no sector unknown, so only the last two ever appear here.

use parry3d::math::{Isometry, Point, Vector};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::Cuboid;

use crate::model::Obstacle;

/// What the sensor is: geometry, range and rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeSensor {
    /// Sector width, degrees (PX4's bin size is 5).
    pub increment_deg: f64,
    /// Rays cast per sector (the scanner's readings per sector).
    pub rays_per_sector: usize,
    /// Closest reading, centimetres.
    pub min_cm: u16,
    /// Farthest reading, centimetres.
    pub max_cm: u16,
    /// Scans per second (vehicle time).
    pub rate_hz: f64,
}

impl Default for RangeSensor {
    fn default() -> Self {
        Self {
            increment_deg: 5.0,
            rays_per_sector: 5,
            min_cm: 20,
            max_cm: 1200,
            rate_hz: 10.0,
        }
    }
}

/// Number of sectors in one message (`OBSTACLE_DISTANCE.distances`).
pub const SECTORS: usize = 72;

/// The boxes as the sensor sees them: solids from the ground up (`x` North, `y` East, `z` up, metres).
#[derive(Debug, Clone)]
pub struct SensorScene {
    boxes: Vec<(Cuboid, Isometry<f32>)>,
}

impl SensorScene {
    /// The solids of `obstacles` (the same boxes the judge measures against).
    pub fn new(obstacles: &[Obstacle]) -> Self {
        let boxes = obstacles
            .iter()
            .map(|o| {
                let f = o.footprint();
                let top = o.top_m();
                let half = Vector::new(f.length as f32 / 2.0, f.width as f32 / 2.0, top as f32 / 2.0);
                let pose = Isometry::new(
                    Vector::new(f.center.x as f32, f.center.y as f32, top as f32 / 2.0),
                    Vector::z() * f.yaw_rad as f32,
                );
                (Cuboid::new(half), pose)
            })
            .collect();
        Self { boxes }
    }

    /// Distance (metres) along the horizontal ray from `(x, y)` at height `z_up` on the bearing `bearing_rad`
    /// (clockwise from North) to the first box, if within `max_m`.
    pub fn ray(&self, x: f64, y: f64, z_up: f64, bearing_rad: f64, max_m: f64) -> Option<f64> {
        let ray = Ray::new(
            Point::new(x as f32, y as f32, z_up as f32),
            Vector::new(bearing_rad.cos() as f32, bearing_rad.sin() as f32, 0.0),
        );
        self.boxes
            .iter()
            .filter_map(|(c, iso)| c.cast_ray(iso, &ray, max_m as f32, true))
            .map(f64::from)
            .reduce(f64::min)
    }
}

impl RangeSensor {
    /// The scan period, seconds.
    pub fn period_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// One scan from `pos_ned` (local NED, metres) with heading `yaw_rad`: per body sector, centimetres
    /// (`max_cm + 1` when nothing is within range; `min_cm` when closer than the sensor can see).
    pub fn scan(&self, scene: &SensorScene, pos_ned: [f64; 3], yaw_rad: f64) -> [u16; SECTORS] {
        let mut out = [self.max_cm.saturating_add(1); SECTORS];
        let max_m = f64::from(self.max_cm) / 100.0;
        let n = self.rays_per_sector.max(1);
        let step = self.increment_deg / n as f64;
        for (j, slot) in out.iter_mut().enumerate() {
            let centre = j as f64 * self.increment_deg;
            let closest = (0..n)
                .map(|k| centre - self.increment_deg / 2.0 + step * (k as f64 + 0.5))
                .filter_map(|deg| scene.ray(pos_ned[0], pos_ned[1], -pos_ned[2], yaw_rad + deg.to_radians(), max_m))
                .reduce(f64::min);
            if let Some(d) = closest {
                let cm = (d * 100.0)
                    .round()
                    .clamp(f64::from(self.min_cm), f64::from(self.max_cm));
                *slot = cm as u16;
            }
        }
        out
    }

    /// The closest obstacle a scan shows, metres (`None` when every sector is free).
    pub fn closest_m(&self, scan: &[u16; SECTORS]) -> Option<f64> {
        scan.iter()
            .filter(|d| **d <= self.max_cm)
            .min()
            .map(|d| f64::from(*d) / 100.0)
    }
}

#[cfg(test)]
#[path = "range_sensor_tests.rs"]
mod tests;
