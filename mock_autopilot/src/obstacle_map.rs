//! The obstacle map of PX4's Collision Prevention: 72 bins of 5 degrees around the vehicle, in the body frame
//! (bin 0 straight ahead, clockwise), filled from OBSTACLE_DISTANCE messages as PX4 v1.16 fills it
//! (CollisionPrevention.cpp `_addObstacleSensorData`, `_enterData`; ObstacleMath.cpp).
//!
//! Distances are centimetres. `u16::MAX` means "unknown"; a reading at or beyond the sensor's `max_distance`
//! (conventionally `max_distance + 1`) means "nothing within range". Messages in `MAV_FRAME_GLOBAL` or
//! `MAV_FRAME_LOCAL_NED` are North-aligned and turned into the body frame with the vehicle's heading;
//! `MAV_FRAME_BODY_FRD` messages are front-aligned already. Angle arithmetic is in f32, as PX4's.

use std::time::Duration;

use mavlink::dialects::common::{MavDistanceSensor, MavFrame, OBSTACLE_DISTANCE_DATA};

/// Bins in the map (as many as OBSTACLE_DISTANCE carries).
pub const BIN_COUNT: usize = 72;
/// Width of a bin, degrees.
pub const BIN_DEG: f32 = 5.0;
/// A bin or message older than this is stale (PX4's `RANGE_STREAM_TIMEOUT_US`).
pub const RANGE_TIMEOUT: Duration = Duration::from_millis(500);
/// "No data" in a bin.
pub const UNKNOWN: u16 = u16::MAX;

/// The body-frame map with, per bin, when it was written, the range of the sensor that wrote it and whether
/// any sensor ever covered it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObstacleMap {
    /// Distance per bin, cm (`UNKNOWN`: no data).
    pub distances: [u16; BIN_COUNT],
    /// When each bin was last written (vehicle time).
    pub stamps: [Duration; BIN_COUNT],
    /// `max_distance` (cm) of the message that wrote each bin.
    pub max_ranges: [u16; BIN_COUNT],
    /// Bins some sensor has covered (PX4's `_data_fov`).
    pub covered: [bool; BIN_COUNT],
    /// Time of the newest message taken in.
    pub stamp: Duration,
    /// Smallest `min_distance` (cm) of the messages taken in (`UNKNOWN` before the first).
    pub min_distance: u16,
    /// Largest `max_distance` (cm) of the messages taken in.
    pub max_distance: u16,
}

impl Default for ObstacleMap {
    fn default() -> Self {
        Self {
            distances: [UNKNOWN; BIN_COUNT],
            stamps: [Duration::ZERO; BIN_COUNT],
            max_ranges: [0; BIN_COUNT],
            covered: [false; BIN_COUNT],
            stamp: Duration::ZERO,
            min_distance: UNKNOWN,
            max_distance: 0,
        }
    }
}

/// `angle` wrapped to [0, 360); NaN stays NaN.
pub fn wrap_360(angle: f32) -> f32 {
    let w = angle.rem_euclid(360.0);
    if w >= 360.0 { 0.0 } else { w }
}

fn wrap_bin(bin: i64, count: i64) -> i64 {
    bin.rem_euclid(count.max(1))
}

/// The lower edge (degrees, [0, 360)) of sector `bin` of `width` degrees whose sector 0 is centred on `offset`.
pub fn lower_edge(bin: i64, width: f32, offset: f32) -> f32 {
    let count = (360.0 / width) as i64;
    let bin = wrap_bin(bin, count);
    wrap_360(bin as f32 * width + offset - width / 2.0)
}

/// The map bin whose centre is nearest to `angle_deg` (body frame).
pub fn bin_at(angle_deg: f32) -> usize {
    let b = (wrap_360(angle_deg) / BIN_DEG).round();
    if b.is_finite() {
        wrap_bin(b as i64, BIN_COUNT as i64) as usize
    } else {
        0
    }
}

/// The sector width of a message: `increment_f` when positive, else `increment`.
pub fn message_increment(m: &OBSTACLE_DISTANCE_DATA) -> f32 {
    if m.increment_f > 0.0 {
        m.increment_f
    } else {
        f32::from(m.increment)
    }
}

/// Whether message sector [lo, hi) and map bin [blo, bhi) overlap, with PX4's rules for edges.
fn overlaps(mut lo: f32, hi: f32, mut blo: f32, bhi: f32) -> bool {
    if blo > bhi {
        blo -= 360.0;
    }
    if lo > hi {
        lo -= 360.0;
    }
    (lo > blo && lo < bhi) || (hi > blo && hi < bhi) || (lo <= blo && hi >= bhi) || (lo >= blo && hi <= bhi)
}

impl ObstacleMap {
    /// Takes in a message received at `received`, the vehicle heading `yaw_rad` (0 North, clockwise) at
    /// `now`. Stale messages and messages without a sector width are ignored; Err names an unsupported frame.
    pub fn ingest(
        &mut self,
        m: &OBSTACLE_DISTANCE_DATA,
        received: Duration,
        yaw_rad: f64,
        now: Duration,
    ) -> Result<(), String> {
        let inc = message_increment(m);
        if now.saturating_sub(received) >= RANGE_TIMEOUT || inc.is_nan() || inc <= 0.0 {
            return Ok(());
        }
        let offset = match m.frame {
            MavFrame::MAV_FRAME_GLOBAL | MavFrame::MAV_FRAME_LOCAL_NED => {
                m.angle_offset - (yaw_rad as f32).to_degrees()
            }
            MavFrame::MAV_FRAME_BODY_FRD => m.angle_offset,
            other => {
                return Err(format!(
                    "Obstacle message received in unsupported frame {}",
                    other as u8
                ));
            }
        };
        self.stamp = self.stamp.max(received);
        self.max_distance = self.max_distance.max(m.max_distance);
        self.min_distance = self.min_distance.min(m.min_distance);
        // PX4 reads at most 72 sectors in the North-aligned frames; beyond them the body-frame branch reads
        // past the array, which the mock does not imitate.
        let sectors = (0..BIN_COUNT).take_while(|&j| (j as f32) < 360.0 / inc);
        let sectors: Vec<usize> = sectors.collect();
        for i in 0..BIN_COUNT {
            let blo = lower_edge(i as i64, BIN_DEG, 0.0);
            let bhi = lower_edge(i as i64 + 1, BIN_DEG, 0.0);
            for &j in &sectors {
                let lo = lower_edge(j as i64, inc, offset);
                let hi = lower_edge(j as i64 + 1, inc, offset);
                let d = m.distances[j];
                if d != UNKNOWN && overlaps(lo, hi, blo, bhi) && self.accepts(i, m.max_distance, d) {
                    self.distances[i] = d;
                    self.stamps[i] = self.stamp;
                    self.max_ranges[i] = m.max_distance;
                    self.covered[i] = true;
                }
            }
        }
        Ok(())
    }

    /// PX4's `_enterData`: whether a reading `reading_cm` of a sensor with range `range_cm` replaces bin `i`.
    /// A shorter-range sensor wins among in-range readings; an out-of-range reading only overwrites a bin that
    /// is out of range too (from a sensor of no longer range) or that the same sensor wrote.
    fn accepts(&self, i: usize, range_cm: u16, reading_cm: u16) -> bool {
        let (range_m, reading_m) = (f32::from(range_cm) * 0.01, f32::from(reading_cm) * 0.01);
        let range = (100.0 * range_m + 0.5) as u16;
        let (cur, cur_range) = (self.distances[i], self.max_ranges[i]);
        if reading_m < range_m {
            range <= cur_range || cur >= cur_range
        } else {
            (cur >= cur_range && range >= cur_range) || (cur < cur_range && range == cur_range)
        }
    }

    /// Forgets bins not written for [`RANGE_TIMEOUT`].
    pub fn drop_stale(&mut self, now: Duration) {
        for i in 0..BIN_COUNT {
            if now.saturating_sub(self.stamps[i]) > RANGE_TIMEOUT {
                self.distances[i] = UNKNOWN;
            }
        }
    }

    /// The map as PX4 streams it back (`obstacle_distance_fused`): body frame, 5-degree `increment_f`.
    pub fn to_message(&self, time_usec: u64) -> OBSTACLE_DISTANCE_DATA {
        OBSTACLE_DISTANCE_DATA {
            time_usec,
            distances: self.distances,
            min_distance: self.min_distance,
            max_distance: self.max_distance,
            sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
            increment: 0,
            increment_f: BIN_DEG,
            angle_offset: 0.0,
            frame: MavFrame::MAV_FRAME_BODY_FRD,
        }
    }
}

#[cfg(test)]
#[path = "obstacle_map_tests.rs"]
mod tests;
