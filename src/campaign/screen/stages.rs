//! The campaign's LFS stages: screening candidates with one simulation each, and an ensemble for the
//! shortlisted ones. Both cache their results in the campaign folder for a resume.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use std::sync::atomic::AtomicBool;

use serde::{Deserialize, Serialize};

use crate::campaign::ground::candidate::{Candidate, CandidateId, LfsPrediction};
use crate::campaign::ground::error::CampaignError;
use crate::campaign::ground::screener::{Progress, Screener};
use crate::campaign::screen::parallel::{available_threads, parallel_map};
use crate::campaign::settings::CampaignSettings;
use crate::generator::{DrawDistribution, Neighbourhood};
use crate::io::write_json;
use crate::lfs::ensemble::{Ensemble, EnsembleParams};
use crate::model::TestCase;

/// Ensembles are run on at most this many of the most severe point predictions per flight left in the budget
/// (the near-duplicate filter thins the ranking, so it needs more than one candidate per flight).
pub const ENSEMBLE_SHORTLIST_PER_FLIGHT: usize = 2;

/// What the screening stages read.
pub struct Stage<'a> {
    /// The case study.
    pub case: &'a TestCase,
    /// Every candidate drawn so far, by index.
    pub candidates: &'a [Candidate],
    /// The campaign folder (caches).
    pub folder: &'a Path,
    /// The LFS.
    pub screener: &'a dyn Screener,
    /// Progress output.
    pub progress: &'a dyn Progress,
    /// Stops the stage.
    pub cancel: &'a AtomicBool,
}

/// A screening cache: the predictions and the draw distribution (and neighbourhoods) the candidates came from.
#[derive(Serialize, Deserialize)]
struct ScreenCache {
    distribution: DrawDistribution,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    around: Vec<Neighbourhood>,
    screened: Vec<LfsPrediction>,
}

/// Screens candidates `range` on every core; cached in `folder/cache_name` (reused only for the same
/// candidates from the same distribution and the same parents' neighbourhoods `around`).
pub fn screen_all(
    ctx: &Stage,
    range: Range<u64>,
    cache_name: &str,
    distribution: &DrawDistribution,
    around: &[Neighbourhood],
) -> Result<Vec<LfsPrediction>, CampaignError> {
    let cache = ctx.folder.join(cache_name);
    let want = (range.end - range.start) as usize;
    if let Ok(text) = std::fs::read_to_string(&cache) {
        let cached = serde_json::from_str::<ScreenCache>(&text)
            .ok()
            .filter(|c| &c.distribution == distribution && c.around == around)
            .map(|c| c.screened)
            // A bare list is a cache of the uniform distribution with no parents: accepted so such folders resume.
            .or_else(|| {
                serde_json::from_str::<Vec<LfsPrediction>>(&text)
                    .ok()
                    .filter(|_| distribution.is_uniform() && around.is_empty())
            });
        if let Some(cached) = cached
            && cached.len() == want
            && cached.first().is_none_or(|s| s.candidate.0 == range.start)
        {
            ctx.progress
                .note(&format!("screening: reusing {} cached predictions", cached.len()));
            return Ok(cached);
        }
    }
    ctx.progress.stage("screen", want);
    let indices: Vec<u64> = range.collect();
    let results = parallel_map(
        &indices,
        available_threads(),
        ctx.cancel,
        &|n| ctx.progress.tick(n),
        |&i| {
            let test = ctx.case.with_obstacles(ctx.candidates[i as usize].obstacles.clone());
            let s = ctx.screener.screen(&test);
            LfsPrediction::point(CandidateId(i), s.min_distance_m, s.flight_time_s, s.ending)
        },
    );
    let screened: Vec<LfsPrediction> = results.into_iter().flatten().collect();
    if screened.len() < want {
        return Err(CampaignError::Config("interrupted during screening".into()));
    }
    let entry = ScreenCache {
        distribution: distribution.clone(),
        around: around.to_vec(),
        screened: screened.clone(),
    };
    write_json(&cache, &entry, false)?;
    Ok(screened)
}

/// Runs the ensemble on the `shortlist` most severe candidates of `fresh` predicted below the threshold and
/// returns every cached candidate's member distances (raw, uncalibrated). Cached in `ensemble.json`; member
/// seeds depend on the campaign's seed and the candidate only.
pub fn ensemble_shortlist(
    ctx: &Stage,
    fresh: &[LfsPrediction],
    cfg: &CampaignSettings,
    shortlist: usize,
) -> Result<BTreeMap<u64, Vec<f64>>, CampaignError> {
    let cache_path = ctx.folder.join("ensemble.json");
    let mut cache: BTreeMap<u64, Vec<f64>> = std::fs::read_to_string(&cache_path)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let mut order: Vec<&LfsPrediction> = fresh
        .iter()
        .filter(|s| s.min_distance < cfg.screening.threshold_m)
        .collect();
    order.sort_by(|a, b| {
        a.min_distance
            .total_cmp(&b.min_distance)
            .then(a.candidate.cmp(&b.candidate))
    });
    order.truncate(shortlist);
    let todo: Vec<u64> = order
        .iter()
        .map(|s| s.candidate.0)
        .filter(|c| !cache.contains_key(c))
        .collect();
    if !todo.is_empty() {
        ctx.progress.stage("ensemble", todo.len());
        let results = parallel_map(
            &todo,
            available_threads(),
            ctx.cancel,
            &|n| ctx.progress.tick(n),
            |&c| {
                let test = ctx.case.with_obstacles(ctx.candidates[c as usize].obstacles.clone());
                (
                    c,
                    ctx.screener
                        .ensemble(&test, cfg.screening.ensemble, member_seed(cfg.campaign.seed, c)),
                )
            },
        );
        if results.iter().any(Option::is_none) {
            return Err(CampaignError::Config(
                "interrupted during the ensemble screening".into(),
            ));
        }
        cache.extend(results.into_iter().flatten().filter_map(|(c, v)| Some((c, v?))));
        write_json(&cache_path, &cache, false)?;
    }
    ctx.progress.note(&format!(
        "ensemble of {}: {} candidates ranked by expected points per minute",
        cfg.screening.ensemble,
        order.len()
    ));
    Ok(cache)
}

/// With `--ensemble`, runs the ensembles of the best [`ENSEMBLE_SHORTLIST_PER_FLIGHT`] candidates of `fresh`
/// per flight of the `remaining` ones, and sets their `p_fail` and expected points ([`apply_ensemble`]);
/// returns the seconds it took.
pub fn run_ensemble(
    ctx: &Stage,
    fresh: &mut [LfsPrediction],
    cfg: &CampaignSettings,
    remaining: usize,
) -> Result<f64, CampaignError> {
    if cfg.screening.ensemble == 0 || remaining == 0 {
        return Ok(0.0);
    }
    let t = std::time::Instant::now();
    let shortlist = remaining.saturating_mul(ENSEMBLE_SHORTLIST_PER_FLIGHT);
    let members = ensemble_shortlist(ctx, fresh, cfg, shortlist)?;
    apply_ensemble(fresh, &members, &ctx.screener.ensemble_params());
    Ok(t.elapsed().as_secs_f64())
}

/// Sets `p_fail` and expected points of every candidate with members, each member moved as far as the
/// candidate's prediction was moved from the LFS's own (`min_distance - raw_min_distance`: the online
/// calibration and the flights' surrogate; 0 without learning).
pub fn apply_ensemble(fresh: &mut [LfsPrediction], members: &BTreeMap<u64, Vec<f64>>, params: &EnsembleParams) {
    for s in fresh.iter_mut() {
        if let Some(m) = members.get(&s.candidate.0) {
            let shift = s.raw_min_distance.map_or(0.0, |raw| s.min_distance - raw);
            let e = Ensemble {
                member_min_distances: m.iter().map(|d| (d + shift).max(0.0)).collect(),
                fork_cycle: 0,
            };
            s.p_fail = e.p_fail(params);
            s.expected_points = e.expected_points(params);
        }
    }
}

/// The ensemble seed of candidate `c`: a SplitMix64 step of the campaign seed and the index, so candidates'
/// members are independent and the same for the same campaign seed.
pub fn member_seed(seed: u64, c: u64) -> u64 {
    let mut z = seed ^ c.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
