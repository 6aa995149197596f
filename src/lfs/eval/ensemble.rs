//! A failure probability from an ensemble of perturbed simulations.
//!
//! The real simulator does not fly one test the same way twice (repeats of one obstacle set differ by 0.29 m on
//! average, up to 3 m), so one deterministic prediction cannot say how likely a failure is. Each member flies
//! the test with what varies from run to run in the real pipeline drawn at random: where the camera frames and
//! planner ticks fall along the path (a phase of a fraction of the 0.1 s tick), the control latency (the motion
//! model's delay ticks), the cruise speed (a few percent) and a placement of the boxes up to 10 cm and 5 degrees
//! off (Gazebo's spawned models, the depth image's quantisation). `p_fail` is the posterior mean of a Beta prior
//! updated with the members below [`FAIL_BELOW_M`]: a plain fraction of 8 members would claim certainty (0 or 1)
//! that a bimodal simulator does not have, which a Brier score punishes hardest.
//!
//! Members share the flight up to the last tick at which no box can be within sensor range even after the
//! perturbations (takeoff and the approach); each is then forked from a clone of that state. Every member is
//! judged against the test's own obstacles (the jitter models the flight, not the test). A member ends once it
//! descends straight down off every box for a second (its judged distance can no longer change).
//!
//! Seeds: member `k` of seed `s` draws from ChaCha8 stream `k` of seed `s`, so the members do not depend on
//! the number of threads or on `n`.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::geometry::P2;
use crate::judge::judge_in_frame;
use crate::lfs::mission::Phase;
use crate::lfs::sim::{MotionModel, SimConfig, SimError, World, step};
use crate::model::competition::FAIL_BELOW_M;
use crate::model::{Mission, Obstacle, Param};

/// Most members one ensemble may have (a guard against typos; 4096 members of a test take minutes).
pub const MAX_MEMBERS: usize = 4096;

/// The perturbation scales and the prior of `p_fail`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnsembleParams {
    /// A member's phase is uniform in `[0, phase_ticks)` ticks: the vehicle moves that much of a tick further
    /// before its first forked tick.
    pub phase_ticks: f64,
    /// A member's delay is uniform in `delay - j ..= delay + j` ticks (not below 0).
    pub delay_jitter_ticks: usize,
    /// A member's cruise speed is the model's times a factor uniform in `[1 - s, 1 + s]`.
    pub speed_rel: f64,
    /// Each box's centre moves uniform in `[-p, p]` metres north and east.
    pub obstacle_pos_m: f64,
    /// Each box turns uniform in `[-y, y]` degrees.
    pub obstacle_yaw_deg: f64,
    /// Beta prior of `p_fail`: pseudo-members below 1.5 m.
    pub prior_fail: f64,
    /// Beta prior of `p_fail`: pseudo-members at or above 1.5 m.
    pub prior_pass: f64,
}

impl EnsembleParams {
    /// No perturbation and no prior: every member is the plain simulation and `p_fail` the plain fraction.
    pub fn none() -> Self {
        Self {
            phase_ticks: 0.0,
            delay_jitter_ticks: 0,
            speed_rel: 0.0,
            obstacle_pos_m: 0.0,
            obstacle_yaw_deg: 0.0,
            prior_fail: 0.0,
            prior_pass: 0.0,
        }
    }

    /// Refuses negative, non-finite or absurd scales, naming the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let fields = [
            ("ensemble phase_ticks must be in [0, 1]", self.phase_ticks, 1.0),
            ("ensemble speed_rel must be in [0, 0.5]", self.speed_rel, 0.5),
            ("ensemble obstacle_pos_m must be in [0, 1]", self.obstacle_pos_m, 1.0),
            (
                "ensemble obstacle_yaw_deg must be in [0, 45]",
                self.obstacle_yaw_deg,
                45.0,
            ),
            ("ensemble prior_fail must be in [0, 100]", self.prior_fail, 100.0),
            ("ensemble prior_pass must be in [0, 100]", self.prior_pass, 100.0),
        ];
        for (msg, v, hi) in fields {
            if !(0.0..=hi).contains(&v) {
                return Err(SimError::Setting(msg));
            }
        }
        if self.delay_jitter_ticks > 10 {
            return Err(SimError::Setting("ensemble delay_jitter_ticks must be at most 10"));
        }
        Ok(())
    }

    /// `p_fail` from `below` of `n` members below the threshold.
    pub fn p_fail(&self, below: usize, n: usize) -> Option<f64> {
        let den = n as f64 + self.prior_fail + self.prior_pass;
        (den > 0.0).then(|| (below as f64 + self.prior_fail) / den)
    }
}

impl Default for EnsembleParams {
    /// Chosen by 5-fold cross-validation with folds by obstacle set on the recorded flights, lowest Brier score
    /// (`examples/fit_ensemble.rs`; grid and figures: docs/design-constants.md#ensemble-perturbation-scales).
    fn default() -> Self {
        Self {
            phase_ticks: 1.0,
            delay_jitter_ticks: 1,
            speed_rel: 0.03,
            obstacle_pos_m: 0.1,
            obstacle_yaw_deg: 5.0,
            prior_fail: 2.0,
            prior_pass: 0.0,
        }
    }
}

/// What one member draws.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberDraw {
    /// Fraction of a tick moved before the first forked tick.
    pub phase: f64,
    /// The motion model with the member's delay and speed.
    pub motion: MotionModel,
    /// The jittered boxes (`None` without obstacle jitter).
    pub obstacles: Option<Vec<Obstacle>>,
}

fn symmetric(rng: &mut ChaCha8Rng, scale: f64) -> f64 {
    (rng.random::<f64>() * 2.0 - 1.0) * scale
}

/// Member `k`'s draw for seed `seed` (stream `k`; always the same number of draws, whatever the scales).
pub fn draw_member(
    params: &EnsembleParams,
    motion: MotionModel,
    obstacles: &[Obstacle],
    seed: u64,
    k: u64,
) -> MemberDraw {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(k);
    let phase = rng.random::<f64>() * params.phase_ticks;
    let j = params.delay_jitter_ticks as i64;
    let dj = if j > 0 { rng.random_range(-j..=j) } else { 0 };
    let speed = 1.0 + symmetric(&mut rng, params.speed_rel);
    let shift = |d: usize| (d as i64 + dj).max(0) as usize;
    let motion = match motion {
        MotionModel::Paper(mut p) => {
            p.delay_ticks = shift(p.delay_ticks);
            p.max_speed_m_s *= speed;
            MotionModel::Paper(p)
        }
        MotionModel::Px4(mut p) => {
            p.delay_ticks = shift(p.delay_ticks);
            p.max_speed_xy_m_s *= speed;
            MotionModel::Px4(p)
        }
    };
    let mut jittered = obstacles.to_vec();
    for o in &mut jittered {
        o.position.x += symmetric(&mut rng, params.obstacle_pos_m);
        o.position.y += symmetric(&mut rng, params.obstacle_pos_m);
        o.position.r += symmetric(&mut rng, params.obstacle_yaw_deg);
    }
    let jitter = params.obstacle_pos_m > 0.0 || params.obstacle_yaw_deg > 0.0;
    MemberDraw {
        phase,
        motion,
        obstacles: jitter.then_some(jittered),
    }
}

/// The members' verdicts.
#[derive(Debug, Clone, PartialEq)]
pub struct Ensemble {
    /// Each member's judged minimum distance (the config's judge), metres, in member order.
    pub member_min_distances: Vec<f64>,
    /// The tick at which the members were forked from the shared flight.
    pub fork_cycle: u64,
}

impl Ensemble {
    /// `p_fail` of "below `threshold_m`" under `params`' prior.
    pub fn p_fail_below(&self, params: &EnsembleParams, threshold_m: f64) -> Option<f64> {
        let below = self.member_min_distances.iter().filter(|d| **d < threshold_m).count();
        params.p_fail(below, self.member_min_distances.len())
    }

    /// `p_fail` of "below 1.5 m".
    pub fn p_fail(&self, params: &EnsembleParams) -> Option<f64> {
        self.p_fail_below(params, FAIL_BELOW_M)
    }

    /// Expected competition points of one flight ([`crate::judge::points`]): `p_fail` times the mean points
    /// of the failing members. Without a failing member (the prior's failures alone) a failure is taken to
    /// earn the least a failure earns, 1 point: the members say nothing about how deep it would go.
    pub fn expected_points(&self, params: &EnsembleParams) -> Option<f64> {
        let failing: Vec<u32> = self
            .member_min_distances
            .iter()
            .filter(|d| **d < FAIL_BELOW_M)
            .map(|d| crate::judge::points(*d))
            .collect();
        let per_failure = if failing.is_empty() {
            1.0
        } else {
            f64::from(failing.iter().sum::<u32>()) / failing.len() as f64
        };
        self.p_fail(params).map(|p| p * per_failure)
    }
}

/// Why an ensemble cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EnsembleError {
    /// `n` out of range.
    #[error("the ensemble needs 1 to {MAX_MEMBERS} members, not {0}")]
    Members(usize),
    /// Nothing to be near.
    #[error("the test has no obstacles, so there is no minimum distance to predict")]
    NoObstacles,
    /// The simulation cannot start.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// Whether no box can be within sensor range of the next frame, with room for every member's perturbation.
fn out_of_sight(world: &World, obstacles: &[Obstacle], params: &EnsembleParams) -> bool {
    let c = world.config();
    let speed = match c.motion {
        MotionModel::Paper(p) => p.max_speed_m_s,
        MotionModel::Px4(p) => p.max_speed_xy_m_s,
    };
    // Camera ahead of the body, the phase's extra move, a tick of motion, box jitter (half diagonal x yaw).
    let reach = f64::from(c.planner.max_sensor_range_m)
        + 1.0
        + speed * (1.0 + params.speed_rel) * c.dt_s * (1.0 + params.phase_ticks);
    let p = world.vehicle.position_enu;
    let at = P2::new(p.y, p.x);
    obstacles.iter().all(|o| {
        let half_diag = 0.5 * o.size.l.hypot(o.size.w);
        let jitter =
            params.obstacle_pos_m * std::f64::consts::SQRT_2 + half_diag * params.obstacle_yaw_deg.to_radians();
        o.footprint().distance_to_point(at) > reach + jitter
    })
}

/// Whether the member is descending straight down, at one spot for a second, off every box: every later
/// sample (and 0.5 s bin mean) repeats a point already judged, so the judged distance can no longer change
/// (up to the rounding of a bin's mean). Spares the landing's ticks. `since` = where and when the spot began.
fn descent_settled(w: &World, since: &mut Option<(f64, f64, f64)>, obstacles: &[Obstacle]) -> bool {
    if w.mission().phase() != Phase::Descend {
        *since = None;
        return false;
    }
    let p = w.vehicle.position_enu;
    match *since {
        Some((x, y, t0)) if x == p.x && y == p.y => {
            w.time_s - t0 >= 1.0 - 1e-9 && obstacles.iter().all(|o| !o.footprint().contains(P2::new(p.y, p.x)))
        }
        _ => {
            *since = Some((p.x, p.y, w.time_s));
            false
        }
    }
}

/// Runs `n` members of the flight of `mission` among `obstacles` (members on up to `jobs` threads; the result
/// does not depend on `jobs`).
#[allow(clippy::too_many_arguments)]
pub fn run_ensemble(
    mission: &Mission,
    obstacles: &[Obstacle],
    px4_params: &[Param],
    config: &SimConfig,
    params: &EnsembleParams,
    n: usize,
    seed: u64,
    jobs: usize,
) -> Result<Ensemble, EnsembleError> {
    if n == 0 || n > MAX_MEMBERS {
        return Err(EnsembleError::Members(n));
    }
    if obstacles.is_empty() {
        return Err(EnsembleError::NoObstacles);
    }
    params.validate()?;
    let mut shared = World::from_parts(mission, obstacles, px4_params, config.clone())?;
    let dt = config.dt_s;
    // The next tick's frame is the first that might see a box: fork before it.
    while shared.status.is_none() && out_of_sight(&shared, obstacles, params) {
        step(&mut shared, dt);
    }
    let fork_cycle = shared.cycles;
    let member = |k: usize| -> Result<f64, EnsembleError> {
        let draw = draw_member(params, config.motion, obstacles, seed, k as u64);
        let mut w = shared.clone();
        if let Some(o) = &draw.obstacles {
            w.set_obstacles(o);
        }
        if draw.motion != config.motion {
            w.set_motion(draw.motion)?;
        }
        w.shift_phase(draw.phase);
        let mut since = None;
        while step(&mut w, dt).is_none() && !descent_settled(&w, &mut since, obstacles) {}
        let d = judge_in_frame(&w.trajectory(), obstacles, config.judge).ok_or(EnsembleError::NoObstacles)?;
        Ok(d.min_distance)
    };
    let member_min_distances = in_chunks(n, jobs, member)
        .into_iter()
        .map(|r| r.unwrap_or(Err(EnsembleError::Members(n))))
        .collect::<Result<Vec<f64>, _>>()?;
    Ok(Ensemble {
        member_min_distances,
        fork_cycle,
    })
}

/// `f(0..n)` on up to `jobs` scoped threads, each taking a contiguous chunk; in order, whatever `jobs` is.
fn in_chunks<T: Clone + Send>(n: usize, jobs: usize, f: impl Fn(usize) -> T + Sync) -> Vec<Option<T>> {
    let chunk_len = n.div_ceil(jobs.clamp(1, n.max(1))).max(1);
    let mut out: Vec<Option<T>> = vec![None; n];
    std::thread::scope(|s| {
        for (t, chunk) in out.chunks_mut(chunk_len).enumerate() {
            let f = &f;
            s.spawn(move || {
                for (i, slot) in chunk.iter_mut().enumerate() {
                    *slot = Some(f(t * chunk_len + i));
                }
            });
        }
    });
    out
}

#[cfg(test)]
#[path = "ensemble_tests.rs"]
mod tests;
