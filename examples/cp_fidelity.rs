//! How well the LFS's Collision Prevention model (`src/lfs/cp_model.rs`) predicts PX4's Collision Prevention
//! flights. Reads `tests/data/px4-cp-flights/tests.jsonl` (PX4 v1.16.2 SIH campaigns in
//! `--mode collision-prevention`; one line per test: its mission, whether the campaign screened, its
//! obstacles, every PX4 flight of it), predicts each test and compares with its first PX4 flight.
//!
//! - `cargo run --release --example cp_fidelity`: mean absolute error, mean bias (predicted - flown),
//!   Spearman, and the share below 1.5 m, per mission and draw, then overall, at the model's defaults.
//! - `... -- cv K [SEED]`: cross-validates the model's velocity lag `vel_tau_s` over a grid with K folds by
//!   obstacle set (each test is one set; its re-flights stay with it), and prints the cross-validated MAE
//!   first, then the in-sample one and the constant each fold chose.
//! - `... -- collect OUT.jsonl FOLDER...`: builds the data file from `generate` output folders (their
//!   `campaign.json` and `journal.jsonl`; flights that did not run to their end are left out) and from
//!   `fly --json` outputs `X.json` of `sample` tests `X.yaml`. `--draws NAME` before folders labels their
//!   tests NAME instead of `screened` / `no-screen`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use prgenuav::lfs::cp_model::{CpSimConfig, simulate_cp};
use prgenuav::lfs::cp_params::CpParams;
use prgenuav::lfs::cv::{Truth, choose};
use prgenuav::lfs::fidelity::aggregate;
use prgenuav::model::competition::FAIL_BELOW_M;
use prgenuav::model::{Obstacle, TestCase};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

const DATA: &str = "tests/data/px4-cp-flights/tests.jsonl";

/// The velocity lags the cross-validation chooses from, seconds.
const TAU_GRID: [f64; 11] = [0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2];

/// One PX4 flight of a test.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Flight {
    /// The judged (2026) minimum distance, metres (`None`: nothing usable recorded).
    min_distance: Option<f64>,
    /// The closest the vehicle's centre came to a box, metres.
    closest_centre_m: Option<f64>,
    /// How it ended.
    status: String,
}

/// One test and its PX4 flights, first first.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Row {
    mission: u32,
    /// `screened` or `no-screen`.
    draws: String,
    obstacles: Vec<Obstacle>,
    flights: Vec<Flight>,
}

impl Row {
    fn first(&self) -> Option<f64> {
        self.flights.first().and_then(|f| f.min_distance)
    }

    fn test(&self) -> anyhow::Result<TestCase> {
        let path = format!("missions/mission{}.yaml", self.mission);
        let case = TestCase::load(Path::new(&path)).with_context(|| path.clone())?;
        Ok(case.with_obstacles(self.obstacles.clone()))
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("collect") => {
            let out = args.get(1).context("collect OUT.jsonl FOLDER...")?;
            collect(Path::new(out), &args[2..])
        }
        Some("cv") => {
            let k: usize = args.get(1).context("cv K [SEED]")?.parse()?;
            let seed: u64 = args.get(2).map_or(Ok(0), |s| s.parse())?;
            cross_validate(&load()?, k, seed)
        }
        None => report(&load()?),
        Some("rows") => {
            let rows = load()?;
            let predicted = predict_all(&rows, CpSimConfig::default().vel_tau_s)?;
            for (r, p) in rows.iter().zip(predicted) {
                let flown: Vec<String> = (r.flights.iter())
                    .map(|f| format!("{}:{}", show(f.min_distance), f.status))
                    .collect();
                println!(
                    "{} {} predicted {} flown {}",
                    r.mission,
                    r.draws,
                    show(p),
                    flown.join(" ")
                );
            }
            Ok(())
        }
        Some(other) => bail!("unknown command {other:?}: none, `rows`, `cv K [SEED]` or `collect OUT FOLDER...`"),
    }
}

fn load() -> anyhow::Result<Vec<Row>> {
    let text = std::fs::read_to_string(DATA).with_context(|| format!("reading {DATA}"))?;
    (text.lines().enumerate())
        .map(|(i, l)| serde_json::from_str(l).with_context(|| format!("{DATA}:{}", i + 1)))
        .collect()
}

/// The model's prediction of every row at velocity lag `tau` (two threads).
fn predict_all(rows: &[Row], tau: f64) -> anyhow::Result<Vec<Option<f64>>> {
    let cfg = CpSimConfig {
        vel_tau_s: tau,
        ..CpSimConfig::default()
    };
    let predict = |r: &Row| -> anyhow::Result<Option<f64>> {
        let test = r.test()?;
        let cp = CpParams::from_params(&test.params).map_err(anyhow::Error::msg)?;
        Ok(simulate_cp(&test, &cp, &cfg).min_distance)
    };
    let half = rows.len().div_ceil(2);
    let (a, b) = rows.split_at(half);
    std::thread::scope(|s| {
        let h = s.spawn(|| a.iter().map(predict).collect::<anyhow::Result<Vec<_>>>());
        let mut out = b.iter().map(predict).collect::<anyhow::Result<Vec<_>>>()?;
        let mut first = h
            .join()
            .map_err(|_| anyhow::anyhow!("a prediction thread panicked"))??;
        first.append(&mut out);
        Ok(first)
    })
}

/// `(predicted, flown first)` of the rows with both.
fn pairs(rows: &[&Row], predicted: &[Option<f64>]) -> Vec<(f64, f64)> {
    rows.iter()
        .zip(predicted)
        .filter_map(|(r, p)| Some(((*p)?, r.first()?)))
        .collect()
}

fn report(rows: &[Row]) -> anyhow::Result<()> {
    let predicted = predict_all(rows, CpSimConfig::default().vel_tau_s)?;
    table(rows, &predicted);
    // The floor no model of the test reaches: how far PX4's second flight of a test lands from its first.
    let repeats: Vec<(f64, f64)> = (rows.iter())
        .filter_map(|r| Some((r.flights.get(1)?.min_distance?, r.first()?)))
        .collect();
    println!(
        "PX4's own repeatability: |second flight - first| over {} re-flown tests: mean {}",
        repeats.len(),
        show(aggregate(&repeats).mae)
    );
    Ok(())
}

/// A group's rows and their predictions.
type Group<'a> = (Vec<&'a Row>, Vec<Option<f64>>);

/// The comparison per mission and draw, then over all rows.
fn table(rows: &[Row], predicted: &[Option<f64>]) {
    let mut groups: BTreeMap<(u32, String), Group> = BTreeMap::new();
    for (r, p) in rows.iter().zip(predicted) {
        let g = groups.entry((r.mission, r.draws.clone())).or_default();
        g.0.push(r);
        g.1.push(*p);
    }
    println!("| mission | draws | tests | MAE m | bias m | Spearman | below 1.5 m: PX4 / LFS | precision / recall |");
    println!("|---|---|---|---|---|---|---|---|");
    for ((mission, draws), (rs, ps)) in &groups {
        print_row(&format!("{mission}"), draws, &pairs(rs, ps));
    }
    let all: Vec<&Row> = rows.iter().collect();
    print_row("all", "all", &pairs(&all, predicted));
}

fn print_row(mission: &str, draws: &str, p: &[(f64, f64)]) {
    let a = aggregate(p);
    let bias = p.iter().map(|(x, y)| x - y).sum::<f64>() / p.len().max(1) as f64;
    let share = |f: fn(&(f64, f64)) -> f64| {
        let below = p.iter().filter(|x| f(x) < FAIL_BELOW_M).count();
        format!("{below}/{}", p.len())
    };
    println!(
        "| {mission} | {draws} | {} | {} | {bias:+.2} | {} | {} / {} | {} / {} |",
        p.len(),
        show(a.mae),
        show(a.spearman),
        share(|x| x.1),
        share(|x| x.0),
        show(a.precision),
        show(a.recall)
    );
}

fn show(x: Option<f64>) -> String {
    x.map_or("-".into(), |x| format!("{x:.2}"))
}

/// K folds by obstacle set: each fold's lag is the one with the smallest MAE on the other folds; the
/// held-out errors of all folds make the cross-validated MAE.
fn cross_validate(rows: &[Row], k: usize, seed: u64) -> anyhow::Result<()> {
    if k < 2 || k > rows.len() {
        bail!("K must be 2 to {} (the tests)", rows.len());
    }
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.shuffle(&mut rand::rngs::StdRng::seed_from_u64(seed));
    let mut fold = vec![0; rows.len()];
    for (n, i) in order.into_iter().enumerate() {
        fold[i] = n % k;
    }
    let grid: Vec<Vec<Option<f64>>> = (TAU_GRID.iter())
        .map(|t| predict_all(rows, *t))
        .collect::<anyhow::Result<_>>()?;
    let (held_out, chosen) = fold_out(rows, &fold, k, &grid)?;
    println!("cross-validated ({k} folds by obstacle set, seed {seed}), chosen per fold: {chosen:?}");
    table(rows, &held_out);
    let missions: Vec<u32> = rows
        .iter()
        .map(|r| r.mission)
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    if missions.len() > 1 {
        let fold: Vec<usize> = (rows.iter())
            .map(|r| missions.iter().position(|m| *m == r.mission).unwrap_or(0))
            .collect();
        let (held_out, chosen) = fold_out(rows, &fold, missions.len(), &grid)?;
        println!("each mission predicted with the lag chosen on the others ({missions:?}): {chosen:?}");
        table(rows, &held_out);
    }
    println!("in sample, every lag of the grid:");
    let all: Vec<&Row> = rows.iter().collect();
    for (t, ps) in TAU_GRID.iter().zip(&grid) {
        print_row(&format!("tau {t}"), "all", &pairs(&all, ps));
    }
    Ok(())
}

/// The held-out predictions of `k` folds (`fold[i]` is row i's), each fold predicted with the grid's lag of
/// smallest MAE on the other folds (`lfs::cv::choose`, as the motion models are cross-validated); and the
/// lags chosen.
fn fold_out(
    rows: &[Row],
    fold: &[usize],
    k: usize,
    grid: &[Vec<Option<f64>>],
) -> anyhow::Result<(Vec<Option<f64>>, Vec<f64>)> {
    let truth: Vec<Truth> = (rows.iter())
        .map(|r| Truth {
            real: r.first().unwrap_or(f64::NAN),
            tier: r.mission.to_string(),
        })
        .collect();
    // A test without a measured first flight predicts nothing it could be scored on.
    let grid: Vec<Vec<Option<f64>>> = (grid.iter())
        .map(|ps| {
            ps.iter()
                .zip(rows)
                .map(|(p, r)| p.filter(|_| r.first().is_some()))
                .collect()
        })
        .collect();
    let mut held_out = vec![None; rows.len()];
    let mut chosen = Vec::new();
    for f in 0..k {
        let best = choose(&grid, &truth, |i| fold[i] != f).context("no lag predicts the training folds")?;
        chosen.push(TAU_GRID[best]);
        for (i, g) in fold.iter().enumerate() {
            if *g == f {
                held_out[i] = grid[best][i];
            }
        }
    }
    Ok((held_out, chosen))
}

/// A journal line, the fields this needs.
#[derive(Deserialize)]
struct JournalLine {
    candidate: u64,
    obstacles: Vec<Obstacle>,
    min_distance: Option<f64>,
    status: String,
    closest_centre_m: Option<f64>,
    #[serde(default)]
    attempt: u32,
}

/// `fly --json` output, the fields this needs.
#[derive(Deserialize)]
struct FlyJson {
    min_distance: Option<f64>,
    status: String,
    collision_prevention: Option<FlyCp>,
}

#[derive(Deserialize)]
struct FlyCp {
    closest_centre_m: Option<f64>,
}

/// A `fly --mode collision-prevention --json` output `X.json` of the test `X.yaml` beside it (a `sample` test):
/// one row of draws `sample`.
fn fly_row(json: &Path) -> anyhow::Result<Row> {
    let fly: FlyJson =
        serde_json::from_str(&std::fs::read_to_string(json)?).with_context(|| json.display().to_string())?;
    let yaml = json.with_extension("yaml");
    let test = TestCase::load(&yaml).with_context(|| yaml.display().to_string())?;
    let text = std::fs::read_to_string(&yaml)?;
    let mission: u32 = (text.lines())
        .find_map(|l| l.split("mission").last()?.strip_suffix(".plan")?.parse().ok())
        .with_context(|| format!("{}: no missions/missionN.plan", yaml.display()))?;
    Ok(Row {
        mission,
        draws: "sample".into(),
        obstacles: test.obstacles,
        flights: vec![Flight {
            min_distance: fly.min_distance,
            closest_centre_m: fly.collision_prevention.and_then(|c| c.closest_centre_m),
            status: fly.status,
        }],
    })
}

fn collect(out: &Path, folders: &[String]) -> anyhow::Result<()> {
    let mut lines = Vec::new();
    let mut label: Option<String> = None;
    let mut args = folders.iter();
    while let Some(folder) = args.next() {
        if folder == "--draws" {
            label = Some(args.next().context("--draws NAME")?.clone());
            continue;
        }
        if folder.ends_with(".json") {
            lines.push(serde_json::to_string(&fly_row(Path::new(folder))?)?);
            continue;
        }
        let folder = PathBuf::from(folder);
        let campaign: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(folder.join("campaign.json"))?)?;
        let case = campaign["case"].as_str().context("campaign.json: case")?;
        let mission: u32 = (case.rsplit('/').next())
            .and_then(|f| f.strip_prefix("mission")?.strip_suffix(".yaml")?.parse().ok())
            .with_context(|| format!("{case}: not missions/missionN.yaml"))?;
        let screened = campaign["screen"].as_bool().unwrap_or(true);
        let mut tests: BTreeMap<u64, Row> = BTreeMap::new();
        let mut journal: Vec<JournalLine> = (std::fs::read_to_string(folder.join("journal.jsonl"))?.lines())
            .map(serde_json::from_str)
            .collect::<Result<_, _>>()?;
        journal.sort_by_key(|l| l.attempt);
        // Flights that ran to their end: a lost link or a backend failure measures PX4's machine, not the test.
        let ran = |l: &JournalLine| matches!(l.status.as_str(), "landed" | "collision" | "timeout");
        for l in journal.into_iter().filter(ran) {
            let row = tests.entry(l.candidate).or_insert_with(|| Row {
                mission,
                draws: (label.clone()).unwrap_or_else(|| if screened { "screened" } else { "no-screen" }.into()),
                obstacles: l.obstacles.clone(),
                flights: Vec::new(),
            });
            row.flights.push(Flight {
                min_distance: l.min_distance,
                closest_centre_m: l.closest_centre_m,
                status: l.status,
            });
        }
        for row in tests.into_values() {
            lines.push(serde_json::to_string(&row)?);
        }
    }
    std::fs::write(out, lines.join("\n") + "\n").with_context(|| format!("writing {}", out.display()))?;
    println!("{} tests written to {}", lines.len(), out.display());
    Ok(())
}
