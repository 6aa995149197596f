//! The world around the vehicle: the air (standard atmosphere, wind), the Earth's magnetic field, the home.

pub mod atmosphere;
pub mod magnetic;
pub mod wind;
pub mod wmm2025;
