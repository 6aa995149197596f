//! The vehicle: a rigid multicopter body, its rotors and its landing gear, stepped by the time it
//! advances and knowing nothing of sockets or PX4.
//!
//! Frames: local NED world (metres, z down, z = 0 resting on the ground), body FRD about the centre of
//! mass; see [`rigid_body`].

pub mod ground;
pub mod iris;
pub mod rigid_body;
pub mod rotor;

use nalgebra::Vector3;

use ground::Ground;
use rigid_body::{BodyState, MassProperties, Wrench, integrate};
use rotor::Rotor;

/// Integration sub-steps per step: 1 ms for a 4 ms step, well inside the gear's 13 rad/s and the
/// attitude dynamics PX4 closes at 250 Hz.
const SUBSTEPS: u32 = 4;

/// A multicopter: body state, mass, rotors and gear.
#[derive(Debug, Clone)]
pub struct Vehicle {
    /// Where it is and how it moves.
    pub body: BodyState,
    /// Mass and inertia.
    pub mass: MassProperties,
    /// Rotors, index = PX4 motor output.
    pub rotors: Vec<Rotor>,
    /// The landing gear and the ground.
    pub ground: Ground,
    /// Gravity, m/s^2 (NED +z).
    pub gravity_m_s2: f64,
    resting: bool,
    specific_force_frd: Vector3<f64>,
}

impl Vehicle {
    /// The Gazebo Classic iris ([`iris`]) resting on the ground at the home, nose North.
    pub fn iris() -> Self {
        let mass = iris::mass();
        Self {
            body: BodyState::at_rest(Vector3::zeros(), 0.0),
            mass,
            rotors: iris::rotors().into_iter().map(Rotor::new).collect(),
            ground: Ground::for_vehicle(mass.mass_kg, iris::GRAVITY_M_S2),
            gravity_m_s2: iris::GRAVITY_M_S2,
            resting: true,
            specific_force_frd: Vector3::new(0.0, 0.0, -iris::GRAVITY_M_S2),
        }
    }

    /// Whether it rests on the hard stop (zero velocity, level).
    pub fn is_resting(&self) -> bool {
        self.resting
    }

    /// What an ideal accelerometer at the centre of mass read over the last step: the mean acceleration
    /// minus gravity, body FRD, m/s^2 (at rest, level: (0, 0, -g)).
    pub fn specific_force_frd(&self) -> Vector3<f64> {
        self.specific_force_frd
    }

    /// Advances `dt_s` seconds with rotor speed references `rotor_refs_rad_s` (missing ones are 0) in a
    /// wind of `wind_ned_m_s` (the air's velocity, NED).
    pub fn step(&mut self, rotor_refs_rad_s: &[f64], wind_ned_m_s: &Vector3<f64>, dt_s: f64) {
        for (i, r) in self.rotors.iter_mut().enumerate() {
            r.spin_towards(rotor_refs_rad_s.get(i).copied().unwrap_or(0.0), dt_s);
        }
        let v0 = self.body.velocity_ned_m_s;
        let h = dt_s / f64::from(SUBSTEPS);
        for _ in 0..SUBSTEPS {
            self.substep(wind_ned_m_s, h);
        }
        let accel = (self.body.velocity_ned_m_s - v0) / dt_s;
        let specific = accel - Vector3::new(0.0, 0.0, self.gravity_m_s2);
        self.specific_force_frd = self.body.ned_to_body(&specific);
    }

    fn substep(&mut self, wind_ned_m_s: &Vector3<f64>, h: f64) {
        let weight = self.mass.mass_kg * self.gravity_m_s2;
        let mut w = self.rotor_wrench(wind_ned_m_s);
        let gear = self.ground.stroke_wrench(&self.body, weight);
        w.force_ned_n += gear.force_ned_n;
        w.moment_frd_n_m += gear.moment_frd_n_m;
        integrate(&mut self.body, &self.mass, &w, self.gravity_m_s2, h);
        self.resting = self.ground.hard_stop(&mut self.body, w.force_ned_n.z + weight);
    }

    /// The rotors' force (NED) and moment (FRD), each hub meeting the air at the body's velocity relative
    /// to the wind plus its own motion from the body's rotation.
    fn rotor_wrench(&self, wind_ned_m_s: &Vector3<f64>) -> Wrench {
        let air_frd = self.body.ned_to_body(&(self.body.velocity_ned_m_s - wind_ned_m_s));
        let mut force_frd = Vector3::zeros();
        let mut moment = Vector3::zeros();
        for r in &self.rotors {
            let hub_air = air_frd + self.body.rates_frd_rad_s.cross(&r.params.position_frd_m);
            let (f, m) = r.wrench(&hub_air);
            force_frd += f;
            moment += m;
        }
        Wrench {
            force_ned_n: self.body.body_to_ned(&force_frd),
            moment_frd_n_m: moment,
        }
    }
}

#[cfg(test)]
mod tests;
