//! A WGS-84 home and PX4's azimuthal-equidistant projection about it (`MapProjection`): local `x` North,
//! `y` East, metres.

/// Earth radius PX4 uses for its local projection and its waypoint distances (`CONSTANTS_RADIUS_OF_EARTH`),
/// metres.
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// The competition simulator's default home (PX4 SITL): latitude, longitude (degrees), altitude AMSL (m).
pub const SIM_HOME: GeoPoint = GeoPoint {
    lat_deg: 47.397742,
    lon_deg: 8.545594,
    alt_m: 488.0,
};

/// A WGS-84 position: latitude and longitude in degrees (north and east positive), altitude in metres
/// (above mean sea level for a home).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoPoint {
    /// Latitude, degrees, north positive.
    pub lat_deg: f64,
    /// Longitude, degrees, east positive.
    pub lon_deg: f64,
    /// Altitude, metres.
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

    /// The WGS-84 point of a local NED position (metres; `down_m` below the reference's altitude).
    pub fn point_at(&self, north_m: f64, east_m: f64, down_m: f64) -> GeoPoint {
        let (lat_deg, lon_deg) = self.unproject(north_m, east_m);
        GeoPoint {
            lat_deg,
            lon_deg,
            alt_m: self.reference.alt_m - down_m,
        }
    }
}

/// Great-circle distance between two points given in degrees, metres (haversine, as PX4's
/// `get_distance_to_next_waypoint`).
pub fn distance_m(lat1: f64, lon1: f64, lat2: f64, lon2: f64) -> f64 {
    let (p1, p2) = (lat1.to_radians(), lat2.to_radians());
    let dlat = p2 - p1;
    let dlon = (lon2 - lon1).to_radians();
    let a = (dlat / 2.0).sin().powi(2) + (dlon / 2.0).sin().powi(2) * p1.cos() * p2.cos();
    2.0 * EARTH_RADIUS_M * a.sqrt().atan2((1.0 - a).max(0.0).sqrt())
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
        assert_eq!(p.unproject(0.0, 0.0), (SIM_HOME.lat_deg, SIM_HOME.lon_deg));
    }

    #[test]
    fn one_arc_minute_north_is_about_1853_m() {
        let p = LocalProjection::new(SIM_HOME);
        let (n, e) = p.project(SIM_HOME.lat_deg + 1.0 / 60.0, SIM_HOME.lon_deg);
        assert!((n - EARTH_RADIUS_M * (1.0f64 / 60.0).to_radians()).abs() < 1e-6, "{n}");
        assert!(e.abs() < 1e-9);
    }

    #[test]
    fn east_shrinks_with_the_cosine_of_the_latitude() {
        // 0.001 degree of longitude at 47.397742 N: R cos(lat) * 0.001 deg = 75.28 m (by hand).
        let p = LocalProjection::new(SIM_HOME);
        let (n, e) = p.project(SIM_HOME.lat_deg, SIM_HOME.lon_deg + 0.001);
        let by_hand = EARTH_RADIUS_M * SIM_HOME.lat_deg.to_radians().cos() * 0.001f64.to_radians();
        assert!((e - by_hand).abs() < 1e-3, "{e} {by_hand}");
        assert!(n.abs() < 1e-3, "{n}");
    }

    #[test]
    fn mission_2_waypoint_as_px4_placed_it() {
        // Mission 2's waypoint (its .plan) lies 53.97 m east and 6.84 m south of the competition's home.
        let p = LocalProjection::new(SIM_HOME);
        let (n, e) = p.project(47.39768051930175, 8.546310969707491);
        assert!((n + 6.84).abs() < 0.05 && (e - 53.97).abs() < 0.05, "{n} {e}");
    }

    #[test]
    fn a_point_keeps_its_height_below_the_reference() {
        let p = LocalProjection::new(SIM_HOME);
        let g = p.point_at(10.0, -20.0, -12.5);
        assert!((g.alt_m - 500.5).abs() < 1e-12);
        let (n, e) = p.project(g.lat_deg, g.lon_deg);
        assert!((n - 10.0).abs() < 1e-6 && (e + 20.0).abs() < 1e-6);
    }

    #[test]
    fn haversine_distance() {
        // One degree of latitude is R * pi / 180.
        let d = distance_m(47.0, 8.0, 48.0, 8.0);
        assert!((d - EARTH_RADIUS_M.to_radians()).abs() < 1e-6, "{d}");
        assert_eq!(distance_m(47.0, 8.0, 47.0, 8.0), 0.0);
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

        #[test]
        fn projected_distance_matches_the_great_circle(n in -3000.0f64..3000.0, e in -3000.0f64..3000.0) {
            // The projection is equidistant from its reference: the local range is the great-circle distance.
            let p = LocalProjection::new(SIM_HOME);
            let (la, lo) = p.unproject(n, e);
            let d = distance_m(SIM_HOME.lat_deg, SIM_HOME.lon_deg, la, lo);
            prop_assert!((d - n.hypot(e)).abs() < 1e-3, "{} vs {}", d, n.hypot(e));
        }
    }
}
