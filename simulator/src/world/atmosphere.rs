//! The International Standard Atmosphere's troposphere: pressure, temperature and density by altitude.

/// Sea-level standard pressure, Pa.
pub const SEA_LEVEL_PRESSURE_PA: f64 = 101_325.0;
/// Sea-level standard temperature, K.
pub const SEA_LEVEL_TEMPERATURE_K: f64 = 288.15;
/// Temperature lapse rate of the troposphere, K/m.
pub const LAPSE_RATE_K_M: f64 = 0.0065;
/// Standard gravity the ISA is defined with, m/s^2.
const G0_M_S2: f64 = 9.80665;
/// Molar mass of dry air, kg/mol.
const AIR_MOLAR_MASS_KG_MOL: f64 = 0.028_964_4;
/// Universal gas constant, J/(mol K).
const GAS_CONSTANT_J_MOL_K: f64 = 8.314_462_618;

/// The air at one altitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Air {
    /// Static pressure, Pa.
    pub pressure_pa: f64,
    /// Temperature, K.
    pub temperature_k: f64,
    /// Density, kg/m^3.
    pub density_kg_m3: f64,
}

/// The standard air at `altitude_m` above mean sea level (troposphere, below 11 km).
pub fn isa(altitude_m: f64) -> Air {
    let temperature_k = SEA_LEVEL_TEMPERATURE_K - LAPSE_RATE_K_M * altitude_m;
    let exponent = G0_M_S2 * AIR_MOLAR_MASS_KG_MOL / (GAS_CONSTANT_J_MOL_K * LAPSE_RATE_K_M);
    let pressure_pa = SEA_LEVEL_PRESSURE_PA * (temperature_k / SEA_LEVEL_TEMPERATURE_K).powf(exponent);
    let density_kg_m3 = pressure_pa * AIR_MOLAR_MASS_KG_MOL / (GAS_CONSTANT_J_MOL_K * temperature_k);
    Air {
        pressure_pa,
        temperature_k,
        density_kg_m3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sea_level_is_the_standard() {
        let a = isa(0.0);
        assert_eq!(a.pressure_pa, 101_325.0);
        assert!((a.density_kg_m3 - 1.225).abs() < 1e-3);
    }

    #[test]
    fn the_home_at_488_m_by_hand() {
        // T = 288.15 - 0.0065 * 488 = 284.978 K; p = 101325 * (284.978 / 288.15)^5.25588 = 95 598 Pa.
        let a = isa(488.0);
        assert!((a.temperature_k - 284.978).abs() < 1e-9);
        let by_hand = 101_325.0 * (284.978f64 / 288.15).powf(5.255_88);
        assert!((a.pressure_pa - by_hand).abs() < 0.5, "{} vs {by_hand}", a.pressure_pa);
        assert!((a.pressure_pa - 95_598.3).abs() < 1.0, "{}", a.pressure_pa);
    }

    #[test]
    fn pressure_falls_about_12_pa_per_metre_near_the_ground() {
        let dp = isa(488.0).pressure_pa - isa(489.0).pressure_pa;
        // dp/dh = rho g = 1.168 * 9.81 = 11.46 Pa/m at 488 m.
        assert!((dp - 11.46).abs() < 0.05, "{dp}");
    }
}
