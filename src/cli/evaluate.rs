//! `prgenuav evaluate FOLDER [--runs 5] [--top N]`: flies every test of a suite several times on the same
//! backends as `generate` and writes the 2026 evaluation into FOLDER/evaluation/ (docs/evaluate.md).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Instant;

use anyhow::bail;
use prgenuav::campaign::evaluation::RUNS_2026;
use prgenuav::campaign::evaluation::flying::{EVALUATION_DIR, EvaluateSetup, Evaluated, evaluate_by_flying};
use prgenuav::campaign::evaluation::{kept, report};
use prgenuav::campaign::fly::backend;
use prgenuav::campaign::settings::evaluation::EvaluationSettings;
use prgenuav::campaign::settings::{CampaignSettings, Loaded};
use prgenuav::campaign::store::journal::FlightRecord;
use prgenuav::judge::similarity::SIMILAR_BELOW_M;

use super::limits;
use super::setting_flags::EvaluateFlags;

/// Arguments of `evaluate`.
#[derive(Debug, clap::Args)]
pub struct EvaluateArgs {
    /// The suite: a `generate` output folder or any folder of Aerialist test YAMLs, best first (test_N.yaml
    /// by N; without any, every .yaml by name).
    folder: PathBuf,
    /// Flights per test (1 to 20; the 2026 competition flies 5).
    #[arg(long, default_value_t = RUNS_2026)]
    runs: usize,
    /// Only the first N tests (the others are not read).
    #[arg(long, value_name = "N")]
    top: Option<usize>,
    /// Two tests are too similar when the DTW distance of their average trajectories is below this (metres,
    /// summed over the alignment; docs/evaluate.md).
    #[arg(long, value_name = "METRES", default_value_t = SIMILAR_BELOW_M)]
    similar_below: f64,
    /// Print report.json on stdout.
    #[arg(long)]
    json: bool,
    /// No progress on stderr (warnings and errors still go there).
    #[arg(short, long)]
    quiet: bool,
    /// The flights' settings (a suite that is a campaign's folder is flown as the campaign was: its mode,
    /// judge, seed and vehicles, unless given here).
    #[command(flatten)]
    settings: EvaluateFlags,
}

/// The flights' settings: what the evaluation kept when it ran before (a fixed setting asked otherwise is
/// refused), else the suite's campaign.json when it has one (the same mock it was generated on), else the
/// defaults; the flags given here override them, a backend given replaces the suite's.
fn settings(args: &EvaluateArgs) -> anyhow::Result<EvaluationSettings> {
    let mut request = args.settings.request(&Loaded::default())?;
    request.check().map_err(anyhow::Error::msg)?;
    request.make_paths_absolute().map_err(anyhow::Error::msg)?;
    // A link or a folder in its place is refused by the reader, naming it, rather than passed over.
    let suite = match std::fs::symlink_metadata(args.folder.join("campaign.json")) {
        Ok(_) => Some(CampaignSettings::load(&args.folder)?),
        Err(_) => None,
    };
    let evaluation = args.folder.join(EVALUATION_DIR);
    let settings = kept::settings(&evaluation, &request, suite.as_ref())?;
    backend::px4_build(&settings.flights())?;
    Ok(settings)
}

/// The numbers given, checked before any vehicle starts.
fn check(args: &EvaluateArgs) -> anyhow::Result<()> {
    limits::EVALUATE_RUNS.check(args.runs as f64)?;
    limits::SIMILAR_BELOW.check(args.similar_below)?;
    if args.top == Some(0) {
        bail!("--top 0 is out of range: 1 or more tests");
    }
    Ok(())
}

pub fn run(args: EvaluateArgs) -> anyhow::Result<ExitCode> {
    check(&args)?;
    let settings = settings(&args)?;
    let (runtime, stop) =
        super::generate::runtime_stopped_by_signals_resuming("run the same evaluate command again to resume")?;
    let flights = settings.flights();
    let mut fleet = backend::fleet(&flights, args.folder.join(EVALUATION_DIR), runtime.handle())?;
    let quiet = args.quiet || args.json;
    // A flight's warnings (a bench's caveats among them), each said once, as a campaign says them.
    let said = std::sync::Mutex::new(std::collections::BTreeSet::new());
    let on_flight = move |r: &FlightRecord| {
        if !quiet {
            let d = r.flown.min_distance.map_or("-".into(), |d| format!("{d:.2} m"));
            eprintln!(
                "flight candidate {}: {} {d} ({:.0} s)",
                r.candidate, r.flown.status, r.flown.flight_time_s
            );
        }
        let mut said = said.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        for w in r.flown.warnings.iter().filter(|w| said.insert((*w).clone())) {
            eprintln!("warning: {w} (candidate {}; said once)", r.candidate);
        }
    };
    let started = Instant::now();
    let on_warning = |w: &str| eprintln!("{w}");
    let setup = EvaluateSetup {
        suite: &args.folder,
        runs: args.runs,
        top: args.top,
        settings: &settings,
        similar_below_m: args.similar_below,
        cancel: &stop,
        on_flight: &on_flight,
        on_warning: &on_warning,
    };
    let done = evaluate_by_flying(&mut fleet, &setup)?;
    print_summary(&done, args.json, started)?;
    if done.missing.flights > 0 || stop.load(Ordering::SeqCst) {
        eprintln!("incomplete: {} flight(s) missing; why:", done.missing.flights);
        for why in &done.missing.why {
            eprintln!("  - {why}");
        }
        eprintln!("run the same command again to fly them (once what failed is fixed)");
        return Ok(ExitCode::from(super::EXIT_FAIL));
    }
    Ok(ExitCode::SUCCESS)
}

/// report.json on stdout, or the figures in two lines.
fn print_summary(done: &Evaluated, json: bool, started: Instant) -> anyhow::Result<()> {
    let e = &done.evaluation;
    if json {
        println!("{}", report::json(e, &done.missing)?);
        return Ok(());
    }
    println!(
        "final score {:.3} = total {} x sim_pen {:.3} ({} of {} tests similar below DTW {} m); 2025: {} failing, failure score {:.3}",
        e.final_score,
        report::total_with_sd(e),
        e.sim_pen,
        e.similar_tests,
        e.evaluated,
        prgenuav::model::limit::number(e.similar_below_m),
        e.figures_2025.failing,
        e.figures_2025.failure_score
    );
    println!(
        "{} flights this run in {:.0} s; evaluation folder: {}",
        done.outcome.flown,
        started.elapsed().as_secs_f64(),
        done.folder.display()
    );
    Ok(())
}
