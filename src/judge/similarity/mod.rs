//! How the 2026 competition compares tests by their flights: each test's flights are averaged into one
//! trajectory (soft-DTW barycenter, then the landing cut), and two tests whose averages lie within a DTW
//! distance of each other are *too similar*. Follows Aerialist's `Trajectory.dtw_average` and
//! `dtw_distance` (`docs/evaluate.md`). Frame: `x` North, `y` East, `z` up, metres; time in seconds.

pub mod barycenter;
pub mod bounded;
pub mod dtw;
pub mod landing;
pub mod lbfgs;
pub mod softdtw;

use crate::model::{AERIALIST_BIN_S, Sample, Trajectory};
use dtw::Point3;
use softdtw::Series;

/// The default DTW distance below which two tests' average trajectories are too similar, metres summed
/// over the alignment (how it was chosen: `docs/evaluate.md`).
pub const SIMILAR_BELOW_M: f64 = 75.0;

/// Aerialist's smoothing of the barycenter (`AVE_GAMMA` of the 2026 evaluation).
pub const AVERAGE_GAMMA: f64 = 200.0;

/// A flight as Aerialist reads it before averaging: time and position from the first sample, 0.5 s bins.
pub fn prepare(flight: &Trajectory) -> Trajectory {
    flight.origin_aligned().binned(AERIALIST_BIN_S)
}

fn points(t: &Trajectory) -> Vec<Point3> {
    t.samples.iter().map(|s| [s.x, s.y, s.z]).collect()
}

fn series(t: &Trajectory, dim: usize, f: impl Fn(&Sample) -> Vec<f64>) -> Series {
    Series {
        dim,
        values: t.samples.iter().flat_map(f).collect(),
    }
}

/// The average trajectory of a test's flights (each already [`prepare`]d): the soft-DTW barycenter of
/// their positions, of their times and of their headings (0 where unknown; the average has a heading only
/// if every flight has one), then the landing cut; one flight is its own average, and long flights are
/// averaged within the bounds of [`bounded`]. Its times never run backwards (the barycenter of flights of
/// different lengths can wobble back a little: each time is at least the one before). `None` without
/// flights or with an empty one.
pub fn average(flights: &[Trajectory]) -> Option<Trajectory> {
    let opt = lbfgs::Options::default();
    let bary = |dim: usize, f: &dyn Fn(&Sample) -> Vec<f64>| {
        let all: Vec<Series> = flights.iter().map(|t| series(t, dim, f)).collect();
        bounded::barycenter(&all, AVERAGE_GAMMA, opt)
    };
    let xyz = bary(3, &|s| vec![s.x, s.y, s.z])?;
    let time = bary(1, &|s| vec![s.t_s])?;
    let with_heading = flights.iter().all(|t| t.samples.iter().all(|s| s.r.is_some()));
    let heading = bary(1, &|s| vec![s.r.unwrap_or(0.0)])?;
    let mut latest = f64::NEG_INFINITY;
    let samples: Vec<Sample> = (0..xyz.len())
        .map(|i| {
            latest = latest.max(time.values[i]);
            Sample {
                t_s: latest,
                x: xyz.point(i)[0],
                y: xyz.point(i)[1],
                z: xyz.point(i)[2],
                r: with_heading.then(|| heading.values[i]),
            }
        })
        .collect();
    Some(cut_landed(Trajectory::new(samples)))
}

/// Replaces the samples from the landing cut on by their mean (unchanged without a cut).
pub fn cut_landed(t: Trajectory) -> Trajectory {
    let Some(cut) = bounded::cut(&points(&t)) else {
        return t;
    };
    let mut samples = t.samples;
    let tail = samples.split_off(cut);
    if let Some(mean) = mean(&tail) {
        samples.push(mean);
    }
    Trajectory::new(samples)
}

/// The mean sample (heading only if every sample has one); `None` when empty.
fn mean(s: &[Sample]) -> Option<Sample> {
    if s.is_empty() {
        return None;
    }
    let n = s.len() as f64;
    let avg = |f: fn(&Sample) -> f64| s.iter().map(f).sum::<f64>() / n;
    let r = s.iter().map(|p| p.r).sum::<Option<f64>>().map(|r| r / n);
    Some(Sample {
        t_s: avg(|p| p.t_s),
        x: avg(|p| p.x),
        y: avg(|p| p.y),
        z: avg(|p| p.z),
        r,
    })
}

/// The DTW distance between two trajectories on `x`, `y`, `z` (time ignored), metres summed over the
/// alignment; `None` if either is empty.
pub fn path_distance(a: &Trajectory, b: &Trajectory) -> Option<f64> {
    dtw::dtw(&points(a), &points(b))
}

#[cfg(test)]
#[path = "similarity_tests.rs"]
mod tests;
