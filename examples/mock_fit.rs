//! Fits the embedded mock's profile to real PX4: flies the 127 recorded cases with obstacles on an embedded
//! lockstep mock for each candidate setting and compares minimum distance (the recorded flights' definition)
//! and flight time with `tests/data/px4-flights` (PX4 v1.14 SITL, the same companion).
//!
//! `cargo run --release --example mock_fit -- fly OUT NAME SETTING [PARALLEL=3]` flies one setting (`SETTING`:
//! `profile:NAME` and/or `KEY=VALUE,...`, a key being a PX4 parameter or a profile constant of
//! `mock_autopilot::profile`) and appends its rows to `OUT/flights.csv` (setting, id, mock_m, flight_time_s,
//! status); a setting already there is skipped. `cargo run --release --example mock_fit -- cv OUT [K=5]` then
//! prints each setting's in-sample figures and the K-fold cross-validation of choosing the setting: folds by
//! obstacle set (`fidelity::fold_of`, repeats of a layout share a fold), the setting with the lowest objective
//! on the other folds predicts each fold. `mock_fit cv OUT mission`: one fold per mission instead, so each
//! mission's cases are predicted by the setting chosen on the other missions'.
//!
//! A setting with gusts (`MOCK_GUST_ACC`) differs from flight to flight: fly it once per seed with env
//! `MOCK_SEED=S` under the names `NAME@s0`, `NAME@s1`, ...; `cv` scores such a family by the mean of its
//! seeds' figures (the expected figure of one flight), so the choice cannot fall on a lucky seed.

// The shared module's env-driven `fly_mock` is for the other examples; this one flies its own settings.
#[path = "common/csv_append.rs"]
mod csv_append;
#[allow(dead_code)]
#[path = "common/mock_flight.rs"]
mod mock_flight;
#[path = "common/setting.rs"]
mod setting;

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context;
use mock_flight::fly_on_mock;
use prgenuav::bridge::{FlyMode, FlyOptions};
use prgenuav::campaign::fly::mock_mavlink::mock_builder_with;
use prgenuav::campaign::settings::mock_profile::MockProfile;
use prgenuav::judge::Judge;
use prgenuav::lfs::fidelity::{FlightCase, aggregate, fold_of, load_dir};
use prgenuav::lfs::px4_flights::{self, Px4Flight};
use prgenuav::model::TestCase;
use setting::parse_setting;
use tokio::sync::Semaphore;

const HEADER: &str = "setting,id,mock_m,flight_time_s,status";

/// One setting's flights by case id: (minimum distance if landed, flight time s).
type Flights = BTreeMap<String, (Option<f64>, f64)>;

fn reference() -> anyhow::Result<(Vec<FlightCase>, Vec<Px4Flight>)> {
    let (cases, _) = load_dir(Path::new("tests/data/hfs-flights"))?;
    let cases: Vec<FlightCase> = cases.into_iter().filter(|c| !c.obstacles.is_empty()).collect();
    let px4 = px4_flights::load(Path::new("tests/data/px4-flights"), &cases)?;
    Ok((cases, px4))
}

async fn fly_case(case: FlightCase, profile: MockProfile) -> anyhow::Result<(Option<f64>, f64, String)> {
    let base = TestCase::load(Path::new(&format!("missions/{}.yaml", case.mission_name)))?;
    let mut test = base.with_obstacles(case.obstacles.clone());
    test.params = case.params.clone();
    let opts = FlyOptions {
        timeout_s: 400.0,
        judge: Judge::E2025,
        // TRAJ_DIR=DIR keeps each flown trajectory as DIR/<id>.csv (to compare phases with PX4's).
        trajectory_csv: std::env::var_os("TRAJ_DIR").map(|d| PathBuf::from(d).join(format!("{}.csv", case.id))),
        ..FlyOptions::default()
    };
    // MOCK_SEED=S: the gusts' seed (a setting with MOCK_GUST_ACC scatters from flight to flight).
    let seed = std::env::var("MOCK_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let builder = mock_builder_with(&profile, FlyMode::Avoidance).seed(seed);
    let r = fly_on_mock(&test, builder, opts).await?;
    let d = r.min_distance.map(|d| (d - case.definition_offset_m).max(0.0));
    Ok((d, r.flight_time_s, r.status.as_str().to_string()))
}

fn read_rows(out: &Path) -> BTreeMap<String, Flights> {
    let mut by: BTreeMap<String, Flights> = BTreeMap::new();
    let text = std::fs::read_to_string(out.join("flights.csv")).unwrap_or_default();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 4 {
            continue;
        }
        let d = f[2].parse().ok();
        let t = f[3].parse().unwrap_or(f64::NAN);
        by.entry(f[0].replace(';', ","))
            .or_default()
            .insert(f[1].to_string(), (d, t));
    }
    by
}

fn fly_setting(out: &Path, name: &str, setting: &str, parallel: usize) -> anyhow::Result<()> {
    if read_rows(out).contains_key(name) {
        eprintln!("{name}: already flown");
        return Ok(());
    }
    let profile = parse_setting(setting)?;
    let (cases, _) = reference()?;
    let rt = tokio::runtime::Runtime::new()?;
    let gate = Arc::new(Semaphore::new(parallel.max(1)));
    let rows = rt.block_on(async {
        let mut handles = Vec::new();
        for case in cases {
            let gate = gate.clone();
            let profile = profile.clone();
            handles.push(tokio::spawn(async move {
                let _permit = gate.acquire_owned().await?;
                let id = case.id.clone();
                anyhow::Ok((id, fly_case(case, profile).await?))
            }));
        }
        let mut rows = Vec::new();
        for h in handles {
            rows.push(h.await??);
        }
        anyhow::Ok(rows)
    })?;
    let mut f = csv_append::append_csv(out, "flights.csv", HEADER)?;
    for (id, (d, t, status)) in rows {
        let d = d.map_or(String::new(), |d| format!("{d:.3}"));
        writeln!(f, "{},{id},{d},{t:.1},{status}", name.replace(',', ";"))?;
    }
    Ok(())
}

/// MAE, Spearman, median flight-time ratio (mock / PX4), mean signed error over `ids`.
fn figures(rows: &Flights, px4: &BTreeMap<&str, &Px4Flight>, ids: &[&str]) -> (f64, f64, f64, f64, usize) {
    let mut pairs = Vec::new();
    let mut ratios = Vec::new();
    for id in ids {
        let (Some((d, t)), Some(p)) = (rows.get(*id), px4.get(id)) else {
            continue;
        };
        if let (Some(d), Some(pd)) = (d, p.min_distance) {
            pairs.push((*d, pd));
        }
        if t.is_finite() && p.flight_time_s > 0.0 {
            ratios.push(t / p.flight_time_s);
        }
    }
    let a = aggregate(&pairs);
    ratios.sort_by(f64::total_cmp);
    let ratio = ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN);
    let bias = pairs.iter().map(|(p, t)| p - t).sum::<f64>() / pairs.len().max(1) as f64;
    (
        a.mae.unwrap_or(f64::NAN),
        a.spearman.unwrap_or(f64::NAN),
        ratio,
        bias,
        a.n,
    )
}

/// What the fit minimises: MAE (m) plus the flight time's log ratio (a 10 % slower or faster mock costs as
/// much as 0.1 m), so the fitted mock is right about distances without flying at a different pace.
fn objective(f: &(f64, f64, f64, f64, usize)) -> f64 {
    f.0 + f.2.ln().abs()
}

/// How the cases are split for cross-validation.
enum Folds {
    /// K folds by obstacle set (`fidelity::fold_of`).
    ObstacleSet(usize),
    /// One fold per mission.
    Mission,
}

impl Folds {
    fn parse(arg: Option<&String>) -> anyhow::Result<Self> {
        match arg.map(String::as_str) {
            None => Ok(Self::ObstacleSet(5)),
            Some("mission") => Ok(Self::Mission),
            Some(k) => Ok(Self::ObstacleSet(
                k.parse().context("K: a number of folds, or `mission`")?,
            )),
        }
    }

    /// Each case's fold, and what the folds are called.
    fn assign(&self, cases: &[FlightCase]) -> (Vec<usize>, String) {
        match self {
            Self::ObstacleSet(k) => (
                cases.iter().map(|c| fold_of(c, *k)).collect(),
                format!("{k} folds by obstacle set"),
            ),
            Self::Mission => {
                let mut missions: Vec<&str> = cases.iter().map(|c| c.mission_name.as_str()).collect();
                missions.sort_unstable();
                missions.dedup();
                let fold = |c: &FlightCase| missions.iter().position(|m| *m == c.mission_name).unwrap_or(0);
                (
                    cases.iter().map(fold).collect(),
                    format!("{} folds by mission", missions.len()),
                )
            }
        }
    }
}

fn cv(out: &Path, folds: &Folds) -> anyhow::Result<()> {
    let (cases, flights) = reference()?;
    let px4: BTreeMap<&str, &Px4Flight> = flights.iter().map(|f| (f.id.as_str(), f)).collect();
    let all: Vec<&str> = cases.iter().map(|c| c.id.as_str()).collect();
    let by = read_rows(out);
    // The fixed subset `tests/it/px4_reference.rs` checks the default profile on: every 4th case by id.
    let mut sorted = all.clone();
    sorted.sort_unstable();
    let subset: Vec<&str> = sorted.into_iter().step_by(4).collect();
    println!("| setting | n | MAE m | Spearman | time ratio | signed m | objective | subset MAE, Spearman |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, rows) in &by {
        let f = figures(rows, &px4, &all);
        let s = figures(rows, &px4, &subset);
        println!(
            "| {name} | {} | {:.3} | {:.3} | {:.3} | {:+.3} | {:.3} | {:.3}, {:.3} |",
            f.4,
            f.0,
            f.1,
            f.2,
            f.3,
            objective(&f),
            s.0,
            s.1
        );
    }
    // A gusty setting flown with several seeds (`NAME@sK`) is one candidate: its figures are the mean over its
    // seeds', the expected figure of one flight, so the choice cannot fall on a lucky seed.
    let mut families: BTreeMap<String, Vec<&Flights>> = BTreeMap::new();
    for (name, rows) in &by {
        families
            .entry(name.split('@').next().unwrap_or(name).to_string())
            .or_default()
            .push(rows);
    }
    let family_figures = |members: &[&Flights], ids: &[&str]| {
        let fs: Vec<_> = members.iter().map(|rows| figures(rows, &px4, ids)).collect();
        let mean = |g: fn(&(f64, f64, f64, f64, usize)) -> f64| fs.iter().map(g).sum::<f64>() / fs.len() as f64;
        (
            mean(|f| f.0),
            mean(|f| f.1),
            mean(|f| f.2),
            mean(|f| f.3),
            fs.first().map_or(0, |f| f.4),
        )
    };
    let row = |label: String, f: (f64, f64, f64, f64, usize)| {
        let o = objective(&f);
        println!(
            "| {label} | {} | {:.3} | {:.3} | {:.3} | {:+.3} | {o:.3} | |",
            f.4, f.0, f.1, f.2, f.3
        );
    };
    let seeded = || families.iter().filter(|(_, m)| m.len() > 1);
    for (name, members) in seeded() {
        row(
            format!("{name}, mean of {} seeds", members.len()),
            family_figures(members, &all),
        );
    }
    // The same families' expected distance (each case's mean over the seeds): what a mock with PX4's scatter
    // predicts of a PX4 flight at best, so its figures are the ceiling of a one-flight comparison.
    for (name, members) in seeded() {
        let f = figures(&seed_mean(members), &px4, &all);
        row(format!("{name}, distance averaged over {} seeds", members.len()), f);
    }
    println!("\n| fold | cases | chosen on the other folds | test MAE m | Spearman | time ratio |");
    println!("|---|---|---|---|---|---|");
    let (fold_of_case, folds_name) = folds.assign(&cases);
    let k = fold_of_case.iter().max().map_or(0, |m| m + 1);
    // Out of fold, one map per seed slot: a family of m seeds fills slot j with seed j % m.
    let slots = families.values().map(Vec::len).max().unwrap_or(1);
    let mut oof: Vec<Flights> = vec![BTreeMap::new(); slots];
    for fold in 0..k {
        let (mut test, mut train): (Vec<&FlightCase>, Vec<&FlightCase>) = (Vec::new(), Vec::new());
        for (c, f) in cases.iter().zip(&fold_of_case) {
            if *f == fold { test.push(c) } else { train.push(c) }
        }
        let train_ids: Vec<&str> = train.iter().map(|c| c.id.as_str()).collect();
        let test_ids: Vec<&str> = test.iter().map(|c| c.id.as_str()).collect();
        let best = families
            .iter()
            .min_by(|a, b| {
                objective(&family_figures(a.1, &train_ids)).total_cmp(&objective(&family_figures(b.1, &train_ids)))
            })
            .context("no settings flown")?;
        let f = family_figures(best.1, &test_ids);
        println!(
            "| {fold} | {} | {} | {:.3} | {:.3} | {:.3} |",
            test_ids.len(),
            best.0,
            f.0,
            f.1,
            f.2
        );
        for (j, slot) in oof.iter_mut().enumerate() {
            let rows = best.1[j % best.1.len()];
            for id in &test_ids {
                if let Some(r) = rows.get(*id) {
                    slot.insert((*id).to_string(), *r);
                }
            }
        }
    }
    repeat_noise(&cases, &px4);
    let oof: Vec<&Flights> = oof.iter().collect();
    let f = family_figures(&oof, &all);
    println!(
        "\ncross-validated ({folds_name}; mean over {slots} seed slot(s)): n {} MAE {:.3} m, Spearman {:.3}, \
         time ratio {:.3}, signed {:+.3} m",
        f.4, f.0, f.1, f.2, f.3
    );
    Ok(())
}

/// Each case's distance and flight time averaged over `members` (cases a member did not land are left out).
fn seed_mean(members: &[&Flights]) -> Flights {
    let mut out = Flights::new();
    for id in members.first().map(|m| m.keys()).into_iter().flatten() {
        let rows: Vec<(Option<f64>, f64)> = members.iter().filter_map(|m| m.get(id).copied()).collect();
        let d: Option<Vec<f64>> = rows.iter().map(|r| r.0).collect();
        let n = rows.len() as f64;
        if let Some(d) = d.filter(|d| d.len() == members.len()) {
            out.insert(
                id.clone(),
                (
                    Some(d.iter().sum::<f64>() / n),
                    rows.iter().map(|r| r.1).sum::<f64>() / n,
                ),
            );
        }
    }
    out
}

/// PX4's own run-to-run spread: identical obstacle sets (repeat groups) flown more than once; and the best a
/// deterministic mock could do on those cases (each flight predicted by its group's mean).
fn repeat_noise(cases: &[FlightCase], px4: &BTreeMap<&str, &Px4Flight>) {
    let mut groups: BTreeMap<(&str, &str), Vec<f64>> = BTreeMap::new();
    for c in cases {
        if let (Some(g), Some(d)) = (&c.repeat_group, px4.get(c.id.as_str()).and_then(|f| f.min_distance)) {
            groups.entry((g.as_str(), c.mission_name.as_str())).or_default().push(d);
        }
    }
    let mut dev = Vec::new();
    for v in groups.values().filter(|v| v.len() > 1) {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        dev.extend(v.iter().map(|d| (d - mean).abs()));
    }
    let n_groups = groups.values().filter(|v| v.len() > 1).count();
    println!(
        "\nPX4 repeat noise: {} flights in {n_groups} repeated obstacle sets, mean |d - set mean| {:.3} m",
        dev.len(),
        dev.iter().sum::<f64>() / dev.len().max(1) as f64
    );
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("fly") if args.len() >= 4 => {
            let parallel = args.get(4).map_or(Ok(3), |a| a.parse())?;
            fly_setting(&PathBuf::from(&args[1]), &args[2], &args[3], parallel)
        }
        Some("cv") if args.len() >= 2 => cv(&PathBuf::from(&args[1]), &Folds::parse(args.get(2))?),
        _ => anyhow::bail!("usage: mock_fit fly OUT NAME SETTING [PARALLEL] | mock_fit cv OUT [K | mission]"),
    }
}
