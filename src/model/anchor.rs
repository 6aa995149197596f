//! Re-anchoring a test at another home: a bench drone's home is wherever it stands. The local geometry (the
//! mission's local points, the obstacles, hence the fence) is kept; only the global positions move.

use super::{GeoPoint, LocalProjection, TestCase};

impl TestCase {
    /// The same test about `home`: every positional mission item keeps its local (North, East, altitude) point
    /// and gets the latitude/longitude of that point about `home`; obstacles stay where they are locally.
    pub fn anchored_at(&self, home: GeoPoint) -> TestCase {
        let projection = LocalProjection::new(home);
        let mut t = self.clone();
        for item in &mut t.mission.items {
            let (Some(local), Some(global)) = (item.local, item.global.as_mut()) else {
                continue;
            };
            let (lat, lon) = projection.unproject(local.north_m, local.east_m);
            global.lat_deg = lat;
            global.lon_deg = lon;
            item.params[4] = Some(lat);
            item.params[5] = Some(lon);
        }
        t.mission.home = home;
        if t.mission.planned_home.is_some() {
            t.mission.planned_home = Some(home);
        }
        t.home = home;
        t
    }

    /// Latitude and longitude (degrees) of each obstacle's centre about the test's home.
    pub fn obstacle_centres_deg(&self) -> Vec<(f64, f64)> {
        let projection = LocalProjection::new(self.home);
        self.obstacles
            .iter()
            .map(|o| projection.unproject(o.position.x, o.position.y))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Obstacle;

    #[test]
    fn anchoring_keeps_the_local_geometry_and_moves_the_globals() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
        let mut test = TestCase::load(&path).unwrap();
        test.obstacles = vec![Obstacle::new(2.0, 2.0, 10.0, 20.0, 5.0, 0.0)];
        let bench = GeoPoint {
            lat_deg: -33.8568,
            lon_deg: 151.2153,
            alt_m: 12.0,
        };
        let a = test.anchored_at(bench);
        assert_eq!(a.home, bench);
        assert_eq!(a.obstacles, test.obstacles);
        let p = LocalProjection::new(bench);
        for (old, new) in test.mission.items.iter().zip(&a.mission.items) {
            assert_eq!(old.local, new.local);
            let Some(g) = new.global else { continue };
            let (n, e) = p.project(g.lat_deg, g.lon_deg);
            let l = new.local.unwrap();
            assert!((n - l.north_m).abs() < 1e-6 && (e - l.east_m).abs() < 1e-6);
            assert_eq!((new.params[4], new.params[5]), (Some(g.lat_deg), Some(g.lon_deg)));
            assert_eq!(g.alt_m, old.global.unwrap().alt_m, "relative altitudes are kept");
        }
        let (lat, lon) = a.obstacle_centres_deg()[0];
        let (n, e) = p.project(lat, lon);
        assert!((n - 20.0).abs() < 1e-6 && (e - 5.0).abs() < 1e-6);
    }
}
