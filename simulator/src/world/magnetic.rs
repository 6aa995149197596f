//! The Earth's main magnetic field from the World Magnetic Model ([`wmm2025`](super::wmm2025)): a degree-12
//! spherical-harmonic expansion evaluated at a geodetic point and date, as the WMM technical report
//! defines it. PX4's pre-arm checks compare the measured field's strength and inclination with PX4's own
//! table of this model, so the simulated magnetometer must agree with it.

use nalgebra::Vector3;

use super::wmm2025::{COEFFICIENTS, EPOCH_YEAR, MAX_DEGREE};

/// WGS-84 semi-major axis, km.
const WGS84_A_KM: f64 = 6378.137;
/// WGS-84 flattening.
const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// The model's reference radius, km.
const REFERENCE_RADIUS_KM: f64 = 6371.2;

/// The field at one place and date.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagneticField {
    /// The field vector in local NED (north, east, down), nanotesla.
    pub ned_nt: Vector3<f64>,
}

impl MagneticField {
    /// The field vector in local NED, gauss (1 G = 100 000 nT), the unit of HIL_SENSOR.
    pub fn ned_gauss(&self) -> Vector3<f64> {
        self.ned_nt * 1e-5
    }

    /// Total intensity F, nanotesla.
    pub fn strength_nt(&self) -> f64 {
        self.ned_nt.norm()
    }

    /// Declination D: the angle from true North to the horizontal field, degrees, east positive.
    pub fn declination_deg(&self) -> f64 {
        self.ned_nt.y.atan2(self.ned_nt.x).to_degrees()
    }

    /// Inclination I: the angle below the horizontal, degrees, down positive.
    pub fn inclination_deg(&self) -> f64 {
        self.ned_nt.z.atan2(self.ned_nt.x.hypot(self.ned_nt.y)).to_degrees()
    }
}

/// The field at geodetic latitude/longitude (degrees), height above the WGS-84 ellipsoid (metres) and
/// decimal year (2025.0 to 2030.0 is the model's span; outside it the secular variation extrapolates).
pub fn field(lat_deg: f64, lon_deg: f64, height_m: f64, year: f64) -> MagneticField {
    let (r_km, lat_c) = geocentric(lat_deg.to_radians(), height_m * 1e-3);
    let lon = lon_deg.to_radians();
    let (p, dp) = legendre(std::f64::consts::FRAC_PI_2 - lat_c);
    let dt = year - EPOCH_YEAR;
    // X' north, Y' east, Z' down in the geocentric frame.
    let (mut x, mut y, mut z) = (0.0, 0.0, 0.0);
    let ratio = REFERENCE_RADIUS_KM / r_km;
    for &(n, m, g, h, gd, hd) in &COEFFICIENTS {
        let (n, m) = (usize::from(n), usize::from(m));
        let (g, h) = (g + dt * gd, h + dt * hd);
        let scale = ratio.powi(n as i32 + 2);
        let (sin_ml, cos_ml) = (m as f64 * lon).sin_cos();
        let k = idx(n, m);
        x += scale * (g * cos_ml + h * sin_ml) * dp[k];
        y += scale * m as f64 * (g * sin_ml - h * cos_ml) * p[k];
        z -= scale * (n as f64 + 1.0) * (g * cos_ml + h * sin_ml) * p[k];
    }
    // Y' divides by cos(lat'), which vanishes at the poles.
    y /= lat_c.cos().max(1e-10);
    // Rotate from the geocentric to the geodetic vertical.
    let psi = lat_c - lat_deg.to_radians();
    let (s, c) = psi.sin_cos();
    MagneticField {
        ned_nt: Vector3::new(x * c - z * s, y, x * s + z * c),
    }
}

/// Geocentric radius (km) and latitude (rad) of a geodetic latitude (rad) and ellipsoidal height (km).
fn geocentric(lat: f64, h_km: f64) -> (f64, f64) {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let (s, c) = lat.sin_cos();
    let rc = WGS84_A_KM / (1.0 - e2 * s * s).sqrt();
    let p = (rc + h_km) * c;
    let z = (rc * (1.0 - e2) + h_km) * s;
    let r = p.hypot(z);
    (r, (z / r).asin())
}

fn idx(n: usize, m: usize) -> usize {
    n * (n + 1) / 2 + m
}

/// Schmidt semi-normalised associated Legendre functions P_n^m(cos theta) and their derivatives with
/// respect to the colatitude theta, for n <= 12, indexed by [`idx`].
fn legendre(theta: f64) -> (Vec<f64>, Vec<f64>) {
    let size = idx(MAX_DEGREE, MAX_DEGREE) + 1;
    let (mut p, mut dp) = (vec![0.0; size], vec![0.0; size]);
    let (s, c) = theta.sin_cos();
    p[0] = 1.0;
    for n in 1..=MAX_DEGREE {
        // The sectoral term from the one below it.
        let (a, b) = (idx(n, n), idx(n - 1, n - 1));
        let k = if n == 1 {
            1.0
        } else {
            ((2 * n - 1) as f64 / (2 * n) as f64).sqrt()
        };
        p[a] = k * s * p[b];
        dp[a] = k * (c * p[b] + s * dp[b]);
        for m in 0..n {
            let (nf, mf) = (n as f64, m as f64);
            let (i1, denom) = (idx(n - 1, m), (nf * nf - mf * mf).sqrt());
            let (p2, dp2, k2) = if n >= 2 && m <= n - 2 {
                let i2 = idx(n - 2, m);
                (p[i2], dp[i2], ((nf - 1.0).powi(2) - mf * mf).sqrt())
            } else {
                (0.0, 0.0, 0.0)
            };
            let t = 2.0 * nf - 1.0;
            p[idx(n, m)] = (t * c * p[i1] - k2 * p2) / denom;
            dp[idx(n, m)] = (t * (c * dp[i1] - s * p[i1]) - k2 * dp2) / denom;
        }
    }
    (p, dp)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NOAA's WMM2025 test values (the WMM2025 report's table, as pygeomag's `WMM2025_TEST_VALUES.txt`
    /// ships them): year, height km, lat, lon, D deg, I deg, X, Y, Z, F nT.
    const NOAA: [[f64; 10]; 6] = [
        [
            2025.0,
            28.0,
            89.0,
            -121.0,
            -99.77,
            88.47,
            -255.388723,
            -1482.460628,
            56194.288771,
            56214.419888,
        ],
        [
            2025.0,
            65.0,
            43.0,
            93.0,
            0.50,
            64.10,
            24299.852822,
            210.517066,
            50037.923998,
            55626.621348,
        ],
        [
            2025.0,
            51.0,
            -33.0,
            109.0,
            -5.49,
            -67.50,
            21737.778822,
            -2090.274098,
            -52710.003920,
            57054.752538,
        ],
        [
            2025.0,
            18.0,
            0.0,
            21.0,
            1.29,
            -26.06,
            29274.811882,
            659.800118,
            -14316.722540,
            32594.761714,
        ],
        [
            2025.5,
            63.0,
            26.0,
            81.0,
            0.51,
            41.07,
            34802.613433,
            308.431881,
            30332.056989,
            46166.554053,
        ],
        [
            2026.0,
            46.0,
            -24.0,
            -122.0,
            14.01,
            -34.17,
            25846.118652,
            6448.863284,
            -18080.399376,
            32194.883578,
        ],
    ];

    #[test]
    fn matches_noaas_published_test_values() {
        for t in NOAA {
            let f = field(t[2], t[3], t[1] * 1e3, t[0]);
            let [x, y, z] = [f.ned_nt.x, f.ned_nt.y, f.ned_nt.z];
            for (got, want, what) in [
                (x, t[6], "X"),
                (y, t[7], "Y"),
                (z, t[8], "Z"),
                (f.strength_nt(), t[9], "F"),
            ] {
                assert!((got - want).abs() < 0.05, "{what} at {t:?}: {got} vs {want}");
            }
            assert!(
                (f.declination_deg() - t[4]).abs() < 0.006,
                "D at {t:?}: {}",
                f.declination_deg()
            );
            assert!(
                (f.inclination_deg() - t[5]).abs() < 0.006,
                "I at {t:?}: {}",
                f.inclination_deg()
            );
        }
    }

    #[test]
    fn zurich_points_north_east_and_steeply_down() {
        // The competition's home: about 3.3 deg east, 63.5 deg down, 48 400 nT in 2026.
        let f = field(47.397742, 8.545594, 488.0, 2026.0);
        assert!((f.declination_deg() - 3.3).abs() < 0.5, "{}", f.declination_deg());
        assert!((f.inclination_deg() - 63.5).abs() < 0.5, "{}", f.inclination_deg());
        assert!((f.strength_nt() - 48_400.0).abs() < 500.0, "{}", f.strength_nt());
        assert!((f.ned_gauss().norm() - f.strength_nt() * 1e-5).abs() < 1e-12);
    }
}
