//! PX4's azimuthal-equidistant projection between WGS-84 latitude/longitude and local North/East metres.

/// Earth radius PX4 uses for its local projection (`CONSTANTS_RADIUS_OF_EARTH`), metres.
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// The competition simulator's default home (PX4 SITL): latitude, longitude (degrees), altitude AMSL (m).
pub const SIM_HOME: GeoPoint = GeoPoint {
    lat_deg: 47.397742,
    lon_deg: 8.545594,
    alt_m: 488.0,
};

/// A WGS-84 position: latitude and longitude in degrees (north and east positive), altitude in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoPoint {
    /// Latitude, degrees, north positive.
    pub lat_deg: f64,
    /// Longitude, degrees, east positive.
    pub lon_deg: f64,
    /// Altitude, metres (AMSL for a home position).
    pub alt_m: f64,
}

/// PX4's `MapProjection` about a reference point: local `x` = North, `y` = East, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalProjection {
    reference: GeoPoint,
    lat_rad: f64,
    lon_rad: f64,
    sin_lat: f64,
    cos_lat: f64,
}

impl LocalProjection {
    /// A projection about `reference` (its altitude is kept for the caller and not used here).
    pub fn new(reference: GeoPoint) -> Self {
        let lat_rad = reference.lat_deg.to_radians();
        Self {
            reference,
            lat_rad,
            lon_rad: reference.lon_deg.to_radians(),
            sin_lat: lat_rad.sin(),
            cos_lat: lat_rad.cos(),
        }
    }

    /// The reference point.
    pub fn reference(&self) -> GeoPoint {
        self.reference
    }

    /// Local `(north_m, east_m)` of a latitude/longitude in degrees.
    pub fn project(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        let lat = lat_deg.to_radians();
        let dlon = lon_deg.to_radians() - self.lon_rad;
        let (sin_lat, cos_lat) = lat.sin_cos();
        let cos_dlon = dlon.cos();
        let arg = (self.sin_lat * sin_lat + self.cos_lat * cos_lat * cos_dlon).clamp(-1.0, 1.0);
        let c = arg.acos();
        // k -> 1 as c -> 0; PX4 switches at the float epsilon, we at a tiny angle.
        let k = if c.abs() < 1e-12 { 1.0 } else { c / c.sin() };
        let north = k * (self.cos_lat * sin_lat - self.sin_lat * cos_lat * cos_dlon) * EARTH_RADIUS_M;
        let east = k * cos_lat * dlon.sin() * EARTH_RADIUS_M;
        (north, east)
    }

    /// Latitude and longitude (degrees) of a local `(north_m, east_m)`.
    pub fn unproject(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        let x = north_m / EARTH_RADIUS_M;
        let y = east_m / EARTH_RADIUS_M;
        let c = x.hypot(y);
        if c == 0.0 {
            return (self.reference.lat_deg, self.reference.lon_deg);
        }
        let (sin_c, cos_c) = c.sin_cos();
        let lat = (cos_c * self.sin_lat + x * sin_c * self.cos_lat / c).asin();
        let lon = self.lon_rad + (y * sin_c).atan2(c * self.cos_lat * cos_c - x * self.sin_lat * sin_c);
        (lat.to_degrees(), lon.to_degrees())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn reference_is_origin() {
        let p = LocalProjection::new(SIM_HOME);
        let (n, e) = p.project(SIM_HOME.lat_deg, SIM_HOME.lon_deg);
        assert!(n.abs() < 1e-9 && e.abs() < 1e-9);
    }

    #[test]
    fn one_arc_minute_north_is_about_1853_m() {
        let p = LocalProjection::new(SIM_HOME);
        let (n, e) = p.project(SIM_HOME.lat_deg + 1.0 / 60.0, SIM_HOME.lon_deg);
        assert!((n - EARTH_RADIUS_M * (1.0f64 / 60.0).to_radians()).abs() < 1e-6, "{n}");
        assert!(e.abs() < 1e-9);
    }

    proptest! {
        #[test]
        fn round_trip_within_1_mm(n in -5000.0f64..5000.0, e in -5000.0f64..5000.0,
                                  lat in -80.0f64..80.0, lon in -179.0f64..179.0) {
            let p = LocalProjection::new(GeoPoint { lat_deg: lat, lon_deg: lon, alt_m: 0.0 });
            let (la, lo) = p.unproject(n, e);
            let (n2, e2) = p.project(la, lo);
            prop_assert!((n - n2).hypot(e - e2) < 1e-3, "{} {} -> {} {}", n, e, n2, e2);
        }

        #[test]
        fn geo_round_trip_within_1_mm(dlat in -0.05f64..0.05, dlon in -0.05f64..0.05) {
            let p = LocalProjection::new(SIM_HOME);
            let (n, e) = p.project(SIM_HOME.lat_deg + dlat, SIM_HOME.lon_deg + dlon);
            let (la, lo) = p.unproject(n, e);
            let back = LocalProjection::new(GeoPoint { lat_deg: la, lon_deg: lo, alt_m: 0.0 });
            let (dn, de) = back.project(SIM_HOME.lat_deg + dlat, SIM_HOME.lon_deg + dlon);
            prop_assert!(dn.hypot(de) < 1e-3);
        }
    }
}
