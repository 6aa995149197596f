//! Local NED <-> WGS84 via PX4's azimuthal-equidistant projection.
//!
//! Temporary: the foundation (`prgenuav::model::geo`) will own this projection; once it is on
//! main this module becomes a re-export and its body goes away.

/// Earth radius PX4 uses for the projection, in metres.
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// A geographic position: degrees and metres above mean sea level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoPoint {
    /// Latitude, degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Altitude above mean sea level, metres.
    pub alt_amsl_m: f64,
}

/// The simulator's default home: PX4 SITL's Zurich position.
pub const DEFAULT_HOME: GeoPoint = GeoPoint {
    lat_deg: 47.397742,
    lon_deg: 8.545594,
    alt_amsl_m: 488.0,
};

/// Azimuthal-equidistant projection about a reference point (PX4 `MapProjection`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalProjection {
    ref_lat_rad: f64,
    ref_lon_rad: f64,
    sin_ref_lat: f64,
    cos_ref_lat: f64,
}

impl LocalProjection {
    /// Projection centred on `lat_deg`, `lon_deg`.
    pub fn new(lat_deg: f64, lon_deg: f64) -> Self {
        let ref_lat_rad = lat_deg.to_radians();
        Self {
            ref_lat_rad,
            ref_lon_rad: lon_deg.to_radians(),
            sin_ref_lat: ref_lat_rad.sin(),
            cos_ref_lat: ref_lat_rad.cos(),
        }
    }

    /// Degrees to local (north_m, east_m).
    pub fn project(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        let lat = lat_deg.to_radians();
        let (sin_lat, cos_lat) = lat.sin_cos();
        let d_lon = lon_deg.to_radians() - self.ref_lon_rad;
        let cos_d_lon = d_lon.cos();
        let arg =
            (self.sin_ref_lat * sin_lat + self.cos_ref_lat * cos_lat * cos_d_lon).clamp(-1.0, 1.0);
        let c = arg.acos();
        let k = if c.abs() > f64::EPSILON {
            c / c.sin()
        } else {
            1.0
        };
        let north = k * (self.cos_ref_lat * sin_lat - self.sin_ref_lat * cos_lat * cos_d_lon);
        let east = k * cos_lat * d_lon.sin();
        (north * EARTH_RADIUS_M, east * EARTH_RADIUS_M)
    }

    /// Local (north_m, east_m) to degrees (lat, lon).
    pub fn unproject(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        let x = north_m / EARTH_RADIUS_M;
        let y = east_m / EARTH_RADIUS_M;
        let c = (x * x + y * y).sqrt();
        if c.abs() <= f64::EPSILON {
            return (self.ref_lat_rad.to_degrees(), self.ref_lon_rad.to_degrees());
        }
        let (sin_c, cos_c) = c.sin_cos();
        let lat = (cos_c * self.sin_ref_lat + x * sin_c * self.cos_ref_lat / c).asin();
        let lon = self.ref_lon_rad
            + (y * sin_c).atan2(c * self.cos_ref_lat * cos_c - x * self.sin_ref_lat * sin_c);
        (lat.to_degrees(), lon.to_degrees())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn mission2_waypoint_projects_like_px4() {
        let p = LocalProjection::new(DEFAULT_HOME.lat_deg, DEFAULT_HOME.lon_deg);
        let (n, e) = p.project(47.39768051930175, 8.546310969707491);
        assert!((n - -6.84).abs() < 0.02, "north {n}");
        assert!((e - 53.97).abs() < 0.02, "east {e}");
        assert_eq!(p.project(47.397742, 8.545594), (0.0, 0.0));
    }

    proptest! {
        #[test]
        fn roundtrip(n in -5000.0f64..5000.0, e in -5000.0f64..5000.0) {
            let p = LocalProjection::new(47.397742, 8.545594);
            let (lat, lon) = p.unproject(n, e);
            let (n2, e2) = p.project(lat, lon);
            prop_assert!((n - n2).abs() < 1e-6 && (e - e2).abs() < 1e-6);
        }
    }
}
