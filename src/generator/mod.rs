//! The pseudo-random test generator (paper, section II): two box obstacles placed on the mission's segment
//! of interest so that the drone must fly an S-shape (in the extended family, perhaps a third beyond them for
//! a second, reversed S).

pub mod adaptive;
mod config;
pub mod gate;
mod placement;
mod soi;

pub use adaptive::{DrawDistribution, Neighbourhood, Proposal};
pub use config::{Family, GeneratorConfig, limits};
pub use placement::{Draw, Mirror, Side, canonical_mirror, left_of, room};
pub use soi::{Soi, SoiKind, segment_of_interest};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::lfs::cp_params::{CpParams, DEFAULT_CP_DIST_M};
use crate::model::{Arena, Mission, Obstacle, TestCase};
use crate::rules::check_obstacles;

/// Why no test could be generated.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// The configuration cannot produce a test.
    #[error("generator configuration: {0}")]
    Config(String),
    /// The mission's path never enters the arena.
    #[error("the mission ({mission}) never flies through the obstacle area; no segment of interest to obstruct")]
    NoSegment {
        /// The mission file.
        mission: String,
    },
    /// Every attempt broke a rule.
    #[error("no valid placement after {attempts} attempts for test {index}: the segment of interest from ({:.2}, {:.2}) to ({:.2}, {:.2}) leaves too little room", .soi.start.x, .soi.start.y, .soi.end.x, .soi.end.y)]
    NoRoom {
        /// The test's index.
        index: u64,
        /// Attempts made.
        attempts: u32,
        /// The SoI.
        soi: Soi,
    },
    /// Every valid draw was refused by the caller's filter.
    #[error("no draw for test {index} passed the campaign's filter in {asked} valid draws")]
    Refused {
        /// The test's index.
        index: u64,
        /// Valid draws offered to the filter.
        asked: u32,
    },
}

/// One generated test: its obstacles and how they were drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Placement {
    /// The test's index for its seed.
    pub index: u64,
    /// Obstacle 1 (crossing the SoI), obstacle 2 (beyond its A end) and perhaps a
    /// third (the extended family: obstacle 1 mirrored, beyond the pair).
    pub obstacles: Vec<Obstacle>,
    /// The numbers drawn.
    pub draw: Draw,
    /// Attempts it took (1 = the first draw was valid).
    pub attempts: u32,
}

/// Generates tests for one case study. Test `i` depends only on the seed and `i`, so tests can be drawn in
/// any order or in parallel and the same seed always gives the same tests, bit for bit.
#[derive(Debug, Clone)]
pub struct Generator {
    mission: Mission,
    arena: Arena,
    config: GeneratorConfig,
    seed: u64,
    soi: Soi,
    mirror: Mirror,
    a_side: Side,
    proposal: Proposal,
    /// The `CP_DIST` the gate family's gaps are drawn around, metres.
    cp_dist_m: f64,
}

impl Generator {
    /// A generator for `case`'s mission in the competition's arena.
    pub fn new(case: &TestCase, config: GeneratorConfig, seed: u64) -> Result<Self, GenerateError> {
        let mut g = Self::for_mission(&case.mission, Arena::default(), config, seed)?;
        // A case whose CP parameters are refused is refused when it flies; its gates use the default.
        g.cp_dist_m = CpParams::from_params(&case.params).map_or(DEFAULT_CP_DIST_M, |c| c.dist_m);
        Ok(g)
    }

    /// A generator for any mission and arena.
    pub fn for_mission(
        mission: &Mission,
        arena: Arena,
        config: GeneratorConfig,
        seed: u64,
    ) -> Result<Self, GenerateError> {
        config.validate().map_err(GenerateError::Config)?;
        let soi = segment_of_interest(mission, &arena).ok_or_else(|| GenerateError::NoSegment {
            mission: mission.source.display().to_string(),
        })?;
        let (mirror, a_side) = canonical_mirror(&soi, &arena);
        Ok(Self {
            mission: mission.clone(),
            arena,
            config,
            seed,
            soi,
            mirror,
            a_side,
            proposal: Proposal::Histogram(Box::default()),
            cp_dist_m: DEFAULT_CP_DIST_M,
        })
    }

    /// The same generator drawing from `distribution` (an adaptive campaign's learnt one).
    pub fn with_distribution(self, distribution: DrawDistribution) -> Self {
        self.with_proposal(Proposal::Histogram(Box::new(distribution)))
    }

    /// The same generator drawing from `proposal` (a histogram, or the neighbourhood of a flown test).
    pub fn with_proposal(mut self, proposal: Proposal) -> Self {
        self.proposal = proposal;
        self
    }

    /// The same generator drawing from `family` (its configuration's, by default the paper's).
    pub fn with_family(mut self, family: Family) -> Self {
        self.config.family = family;
        self
    }

    /// The construction it draws from.
    pub fn family(&self) -> Family {
        self.config.family
    }

    /// Where the draws come from.
    pub fn proposal(&self) -> &Proposal {
        &self.proposal
    }

    /// The segment of interest.
    pub fn soi(&self) -> &Soi {
        &self.soi
    }

    /// The side of the direction of flight obstacle 1's A part (and obstacle 2) lies on.
    pub fn a_side(&self) -> Side {
        self.a_side
    }

    /// The configuration.
    pub fn config(&self) -> &GeneratorConfig {
        &self.config
    }

    /// Test number `index`: redraws until the pair passes every rule, at most `max_attempts` times.
    pub fn sample(&self, index: u64) -> Result<Placement, GenerateError> {
        self.sample_where(index, u32::MAX, |_| true)
    }

    /// Test number `index` as [`Self::sample`], from the first valid draw that `accept` also takes (a
    /// campaign's own filter, e.g. no near-duplicate of a flown test), asking it at most `max_asked` times.
    /// Still a function of the seed, `index` and the filter's answers only.
    pub fn sample_where(
        &self,
        index: u64,
        max_asked: u32,
        mut accept: impl FnMut(&[Obstacle]) -> bool,
    ) -> Result<Placement, GenerateError> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(index);
        let mut asked = 0;
        for attempt in 1..=self.config.max_attempts {
            let drawn = match self.config.family {
                Family::Gate => {
                    let place = (self.mirror, &self.arena);
                    gate::draw_gate(&mut rng, &self.soi, place, &self.config, &self.proposal, self.cp_dist_m)
                }
                family => placement::draw_test(
                    &mut rng,
                    &self.soi,
                    (self.mirror, &self.arena),
                    &self.config,
                    (family, &self.proposal),
                ),
            };
            let Some((draw, obstacles)) = drawn else {
                continue;
            };
            if check_obstacles(&obstacles, &self.mission, &self.arena).is_empty() {
                if !accept(&obstacles) {
                    asked += 1;
                    if asked >= max_asked {
                        return Err(GenerateError::Refused { index, asked });
                    }
                    continue;
                }
                return Ok(Placement {
                    index,
                    obstacles,
                    draw,
                    attempts: attempt,
                });
            }
        }
        Err(GenerateError::NoRoom {
            index,
            attempts: self.config.max_attempts,
            soi: self.soi,
        })
    }
}
