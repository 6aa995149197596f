//! `--world out.world`: the test's boxes as a Gazebo Classic world, so a Gazebo SITL user flies the same scene
//! with real sensors. Gazebo is ENU; Aerialist writes its boxes with an axis swap (x and y swapped, l and w
//! swapped, yaw = -r), which maps our local NED boxes onto the same ground footprint in Gazebo.

use std::fmt::Write as _;

use crate::model::Obstacle;

/// One box in Gazebo's frame: centre (x East, y North, z up), size along its own axes, yaw (radians, CCW from
/// +x East).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GazeboBox {
    /// Centre, ENU metres (z = half the height above the base).
    pub center_enu: [f64; 3],
    /// Size along the box's x, y, z axes, metres.
    pub size: [f64; 3],
    /// Yaw, radians counter-clockwise from East.
    pub yaw_rad: f64,
}

/// Aerialist's conversion of an obstacle to Gazebo.
pub fn to_gazebo(o: &Obstacle) -> GazeboBox {
    GazeboBox {
        center_enu: [o.position.y, o.position.x, o.position.z + o.size.h / 2.0],
        size: [o.size.w, o.size.l, o.size.h],
        yaw_rad: -o.position.r.to_radians(),
    }
}

/// The SDF text of a world with sun, ground and the boxes (static, named `obstacle_<i>`).
pub fn world_sdf(obstacles: &[Obstacle]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\" ?>\n<!-- Written by prgenuav: the test's obstacles (Aerialist's axis swap). -->\n\
         <sdf version=\"1.6\">\n  <world name=\"prgenuav\">\n    <include><uri>model://sun</uri></include>\n    \
         <include><uri>model://ground_plane</uri></include>\n",
    );
    for (i, o) in obstacles.iter().enumerate() {
        let b = to_gazebo(o);
        let [x, y, z] = b.center_enu;
        let [l, w, h] = b.size;
        let _ = write!(
            s,
            "    <model name=\"obstacle_{i}\">\n      <static>true</static>\n      \
             <pose>{x:.4} {y:.4} {z:.4} 0 0 {yaw:.6}</pose>\n      <link name=\"link\">\n        \
             <collision name=\"collision\"><geometry><box><size>{l:.4} {w:.4} {h:.4}</size></box></geometry></collision>\n        \
             <visual name=\"visual\"><geometry><box><size>{l:.4} {w:.4} {h:.4}</size></box></geometry></visual>\n      \
             </link>\n    </model>\n",
            yaw = b.yaw_rad
        );
    }
    s.push_str("  </world>\n</sdf>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::P2;
    use proptest::prelude::*;

    /// The Gazebo box's footprint, with its corners turned back from ENU to (North, East).
    fn corners_ne(b: &GazeboBox) -> Vec<P2> {
        let (s, c) = b.yaw_rad.sin_cos();
        let (hl, hw) = (b.size[0] / 2.0, b.size[1] / 2.0);
        [(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw)]
            .iter()
            .map(|&(u, v)| {
                let e = b.center_enu[0] + u * c - v * s;
                let n = b.center_enu[1] + u * s + v * c;
                P2::new(n, e)
            })
            .collect()
    }

    proptest! {
        #[test]
        fn same_footprint_on_the_ground(l in 1.0f64..20.0, w in 1.0f64..20.0, x in -40.0f64..40.0,
                                        y in -40.0f64..40.0, r in -180.0f64..180.0) {
            let o = Obstacle::new(l, w, 10.0, x, y, r);
            let f = o.footprint();
            for p in corners_ne(&to_gazebo(&o)) {
                // Every Gazebo corner is a corner of our footprint.
                prop_assert!(f.corners().iter().any(|q| (q - p).norm() < 1e-9), "{:?} not in {:?}", p, f.corners());
            }
        }
    }

    #[test]
    fn world_text() {
        let o = Obstacle::new(10.0, 2.0, 20.0, 5.0, -3.0, 30.0);
        let b = to_gazebo(&o);
        assert_eq!(b.center_enu, [-3.0, 5.0, 10.0]);
        assert_eq!(b.size, [2.0, 10.0, 20.0]);
        let sdf = world_sdf(&[o, o]);
        assert!(sdf.contains("obstacle_1") && sdf.contains("<size>2.0000 10.0000 20.0000</size>"));
        assert!(
            sdf.contains("<pose>-3.0000 5.0000 10.0000 0 0 -0.523599</pose>"),
            "{sdf}"
        );
    }
}
