//! One simulation: the vehicle, the wind and the sensors on one clock, stepped 4 ms at a time by whoever
//! owns the clock policy (the HIL link). Knows nothing of sockets.

use std::time::Duration;

use geodesy::{GeoPoint, LocalProjection};
use nalgebra::{UnitQuaternion, Vector3};

use crate::sensors::{SensorConfig, SensorFrame, Sensors};
use crate::time::{STEP, SimTime};
use crate::vehicle::Vehicle;
use crate::vehicle::iris::{COMMAND, CommandMapping};
use crate::vehicle::rigid_body::BodyState;
use crate::world::wind::{Wind, WindConfig};

/// Everything a simulation is made of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// The local NED origin and the resting point of the vehicle (altitude above mean sea level).
    pub home: GeoPoint,
    /// Seed of every random draw.
    pub seed: u64,
    /// Sensor figures.
    pub sensors: SensorConfig,
    /// Wind (calm by default).
    pub wind: WindConfig,
    /// Motor commands older than this stop the rotors (Gazebo: 0.2 s).
    pub actuator_timeout: Duration,
    /// How commands become rotor speeds.
    pub command: CommandMapping,
    /// Where the nose points at rest, degrees clockwise from North (NED yaw). 0 as jMAVSim and SIH start;
    /// Gazebo Classic spawns the iris at ENU yaw 0, that is facing East (90).
    pub heading_deg: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            home: geodesy::SIM_HOME,
            seed: 0,
            sensors: SensorConfig::default(),
            wind: WindConfig::default(),
            actuator_timeout: Duration::from_millis(200),
            command: COMMAND,
            heading_deg: 0.0,
        }
    }
}

/// The vehicle's true state at one instant (what the host records as ground truth).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundTruth {
    /// Simulated time.
    pub time: SimTime,
    /// Centre of mass, local NED about the home, metres.
    pub position_ned_m: Vector3<f64>,
    /// The same position on the Earth (altitude above mean sea level).
    pub position: GeoPoint,
    /// Velocity, local NED, m/s.
    pub velocity_ned_m_s: Vector3<f64>,
    /// Attitude, body FRD to NED.
    pub attitude: UnitQuaternion<f64>,
    /// Body rates, FRD, rad/s.
    pub rates_frd_rad_s: Vector3<f64>,
    /// Specific force, body FRD, m/s^2 (what an ideal accelerometer reads).
    pub specific_force_frd_m_s2: Vector3<f64>,
    /// Resting on the ground.
    pub on_ground: bool,
    /// Whether the last motor command said armed.
    pub armed: bool,
}

/// The last motor command.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Command {
    controls: [f32; 16],
    armed: bool,
    at: SimTime,
}

/// A simulation in progress.
#[derive(Debug, Clone)]
pub struct Simulation {
    config: SimConfig,
    projection: LocalProjection,
    vehicle: Vehicle,
    wind: Wind,
    sensors: Sensors,
    time: SimTime,
    command: Option<Command>,
}

impl Simulation {
    /// The iris resting at the home at time zero, its nose at `config.heading_deg`.
    pub fn new(config: SimConfig) -> Self {
        let mut vehicle = Vehicle::iris();
        vehicle.body = BodyState::at_rest(Vector3::zeros(), config.heading_deg.to_radians());
        Self {
            projection: LocalProjection::new(config.home),
            sensors: Sensors::new(config.sensors, config.home, vehicle.gravity_m_s2, config.seed),
            wind: Wind::new(config.wind, config.seed),
            vehicle,
            config,
            time: SimTime::ZERO,
            command: None,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Simulated time (the end of the last step).
    pub fn time(&self) -> SimTime {
        self.time
    }

    /// The vehicle.
    pub fn vehicle(&self) -> &Vehicle {
        &self.vehicle
    }

    /// The vehicle, to place it (tests, scenarios).
    pub fn vehicle_mut(&mut self) -> &mut Vehicle {
        &mut self.vehicle
    }

    /// Takes a motor command (HIL_ACTUATOR_CONTROLS `controls`, 0..1 for motors) as of now.
    pub fn set_actuators(&mut self, controls: &[f32], armed: bool) {
        let mut c = [0.0; 16];
        for (d, s) in c.iter_mut().zip(controls) {
            *d = *s;
        }
        self.command = Some(Command {
            controls: c,
            armed,
            at: self.time,
        });
    }

    /// Rotor speed references now: the command mapped, or zero without a fresh one.
    fn rotor_refs(&self) -> [f64; 16] {
        let mut refs = [0.0; 16];
        let Some(c) = self.command else { return refs };
        if self.time.since(c.at) > self.config.actuator_timeout {
            return refs;
        }
        for (r, u) in refs.iter_mut().zip(c.controls) {
            *r = self.config.command.reference_rad_s(f64::from(u), c.armed);
        }
        refs
    }

    /// Advances one step (4 ms) and returns what the sensors read at its end.
    pub fn step(&mut self) -> SensorFrame {
        let dt = STEP.as_secs_f64();
        let refs = self.rotor_refs();
        let wind = self.wind.velocity_ned_m_s();
        self.vehicle.step(&refs, &wind, dt);
        self.wind.step(dt);
        self.time = self.time.plus(STEP);
        self.sensors.sample(self.time, &self.vehicle, dt)
    }

    /// The true state now.
    pub fn truth(&self) -> GroundTruth {
        let b = &self.vehicle.body;
        let p = b.position_ned_m;
        GroundTruth {
            time: self.time,
            position_ned_m: p,
            position: self.projection.point_at(p.x, p.y, p.z),
            velocity_ned_m_s: b.velocity_ned_m_s,
            attitude: b.attitude,
            rates_frd_rad_s: b.rates_frd_rad_s,
            specific_force_frd_m_s2: self.vehicle.specific_force_frd(),
            on_ground: self.vehicle.is_resting(),
            armed: self.command.is_some_and(|c| c.armed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensors::mag::MagNoise;

    #[test]
    fn stale_commands_stop_the_rotors() {
        let mut sim = Simulation::new(SimConfig::default());
        sim.set_actuators(&[0.5; 4], true);
        sim.step();
        assert!(sim.vehicle().rotors[0].speed_rad_s > 0.0);
        for _ in 0..60 {
            sim.step();
        }
        // 244 ms after the command: the references are zero and the rotors spin down.
        assert_eq!(sim.rotor_refs()[0], 0.0);
    }

    #[test]
    fn a_heading_of_90_degrees_rests_the_nose_east() {
        let at = |heading_deg| {
            let mut sim = Simulation::new(SimConfig {
                heading_deg,
                sensors: SensorConfig {
                    mag: MagNoise {
                        noise_density: 0.0,
                        random_walk: 0.0,
                        bias_tau_s: 600.0,
                    },
                    ..SensorConfig::default()
                },
                ..SimConfig::default()
            });
            let frame = sim.step();
            (sim.truth(), frame.mag_frd_gauss)
        };
        let (north, mag_n) = at(0.0);
        let (east, mag_e) = at(90.0);
        let yaw = |t: &GroundTruth| t.attitude.euler_angles().2.to_degrees();
        assert!(yaw(&north).abs() < 1e-9 && (yaw(&east) - 90.0).abs() < 1e-9);
        // Facing East, the body's x axis reads the field's East part and its y axis (to the right, South)
        // minus its North part; z is unchanged.
        let (n, e) = (
            mag_n.expect("mag at the first step"),
            mag_e.expect("mag at the first step"),
        );
        assert!(
            (e.x - n.y).abs() < 1e-9 && (e.y + n.x).abs() < 1e-9 && (e.z - n.z).abs() < 1e-9,
            "{n:?} {e:?}"
        );
        assert!(n.x > 0.1, "the field points North at the home: {n:?}");
        assert!(east.on_ground && east.position_ned_m.norm() < 1e-9);
    }

    #[test]
    fn the_same_seed_repeats_the_sensor_stream_bit_for_bit() {
        let run = |seed| {
            let mut sim = Simulation::new(SimConfig {
                seed,
                ..SimConfig::default()
            });
            let mut out = Vec::new();
            for k in 0..600 {
                sim.set_actuators(&[if k > 100 { 0.75 } else { 0.0 }; 4], k > 50);
                out.push(sim.step());
            }
            out
        };
        let (a, b) = (run(5), run(5));
        assert!(a.iter().zip(&b).all(|(x, y)| format!("{x:?}") == format!("{y:?}")));
        let c = run(6);
        assert_ne!(format!("{:?}", a[10]), format!("{:?}", c[10]));
        assert!(a.iter().any(|f| f.gps.is_some()) && a.iter().any(|f| f.baro.is_some()));
    }
}
