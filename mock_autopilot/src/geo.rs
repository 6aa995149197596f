//! The vehicle's own WGS-84 <-> local NED projection (PX4's azimuthal-equidistant `MapProjection`).
//!
//! Deliberately independent of the prgenuav library: the mock is the reference the bridge is tested
//! against, so it must not share the code under test (a projection bug there would otherwise cancel out).

/// Earth radius of PX4's projection, metres.
const RADIUS_M: f64 = 6_371_000.0;

/// The competition simulator's default home (PX4 SITL): 47.397742 N, 8.545594 E, 488 m AMSL.
pub const SIM_HOME: GeoPoint = GeoPoint {
    lat_deg: 47.397742,
    lon_deg: 8.545594,
    alt_m: 488.0,
};

/// Latitude and longitude in degrees (north, east positive) and altitude AMSL in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoPoint {
    /// Degrees north.
    pub lat_deg: f64,
    /// Degrees east.
    pub lon_deg: f64,
    /// Metres above mean sea level.
    pub alt_m: f64,
}

/// Projection about a reference point; local `north`/`east` in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalProjection {
    origin: GeoPoint,
}

impl LocalProjection {
    /// Projection about `origin`.
    pub fn new(origin: GeoPoint) -> Self {
        Self { origin }
    }

    /// `(north_m, east_m)` of a latitude/longitude (degrees).
    pub fn project(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        let (phi0, phi) = (self.origin.lat_deg.to_radians(), lat_deg.to_radians());
        let dlambda = (lon_deg - self.origin.lon_deg).to_radians();
        let cos_c = (phi0.sin() * phi.sin() + phi0.cos() * phi.cos() * dlambda.cos()).clamp(-1.0, 1.0);
        let c = cos_c.acos();
        let scale = if c > 1e-12 { c / c.sin() } else { 1.0 };
        let north = scale * (phi0.cos() * phi.sin() - phi0.sin() * phi.cos() * dlambda.cos());
        let east = scale * phi.cos() * dlambda.sin();
        (north * RADIUS_M, east * RADIUS_M)
    }

    /// Latitude and longitude (degrees) of a local `(north_m, east_m)`.
    pub fn unproject(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        let (xn, ye) = (north_m / RADIUS_M, east_m / RADIUS_M);
        let c = (xn * xn + ye * ye).sqrt();
        if c <= 0.0 {
            return (self.origin.lat_deg, self.origin.lon_deg);
        }
        let phi0 = self.origin.lat_deg.to_radians();
        let phi = (c.cos() * phi0.sin() + xn * c.sin() * phi0.cos() / c).asin();
        let dlambda = (ye * c.sin()).atan2(c * phi0.cos() * c.cos() - xn * phi0.sin() * c.sin());
        (phi.to_degrees(), self.origin.lon_deg + dlambda.to_degrees())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn origin_and_round_trip() {
        let p = LocalProjection::new(SIM_HOME);
        let (n, e) = p.project(SIM_HOME.lat_deg, SIM_HOME.lon_deg);
        assert!(n.abs() < 1e-9 && e.abs() < 1e-9);
        for (n, e) in [(53.97, -6.84), (-120.0, 300.0), (0.0, 1.0)] {
            let (lat, lon) = p.unproject(n, e);
            let (n2, e2) = p.project(lat, lon);
            assert!((n - n2).abs() < 1e-6 && (e - e2).abs() < 1e-6);
        }
        // Mission 2's waypoint (from its .plan) lies 53.97 m east and 6.84 m south of home.
        let (n, e) = p.project(47.39768051930175, 8.546310969707491);
        assert!((n + 6.84).abs() < 0.05 && (e - 53.97).abs() < 0.05, "{n} {e}");
    }
}
