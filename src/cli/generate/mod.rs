//! `prgenuav generate CASE BUDGET`: the competition's main job. `--help` shows the flags a campaign is
//! usually run with; the expert knobs are keys of the campaign TOML (`--config`) and hidden flags, both listed
//! in docs/cli.md.

pub(super) mod plan;

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::Context;
use clap::ArgMatches;
use prgenuav::campaign::report::outputs::Report;
use prgenuav::campaign::report::user_report;
use prgenuav::campaign::run::run_campaign;

use super::progress::Reporter;
use super::setting_flags::CampaignFlags;
use super::stop_signals::StopSignals;
use plan::Plan;

/// Arguments of `generate`: every campaign setting's flag (CASE, BUDGET and the expert ones among them, from
/// their declarations), and how this run reads and prints.
#[derive(Debug, clap::Args)]
pub struct GenerateArgs {
    /// Folder in which the campaign's timestamped output folder is created.
    #[arg(short, long, value_name = "DIR", default_value = "generated_tests")]
    out: PathBuf,
    /// Continue a killed campaign in FOLDER with the settings in its campaign.json (a flag asking for a
    /// different value is refused).
    #[arg(long, value_name = "FOLDER")]
    resume: Option<PathBuf>,
    /// Campaign TOML with the expert knobs: [generator], [output], [screening], [mock], [flight], [learning].
    /// Each knob also has a flag, hidden here; flags override the file. docs/cli.md lists both.
    #[arg(long, value_name = "FILE.toml")]
    config: Option<PathBuf>,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
    /// Print the report as JSON on stdout (and no progress output).
    #[arg(long)]
    json: bool,
    /// The campaign settings' flags (the expert ones hidden; each sets its campaign TOML key).
    #[command(flatten)]
    settings: CampaignFlags,
}

pub fn run(args: GenerateArgs, matches: &ArgMatches) -> anyhow::Result<ExitCode> {
    let plan = plan::plan(&args, matches)?;
    let cfg = &plan.settings;
    if args.resume.is_some()
        && let Some(note) = complete_note(&plan.folder, cfg.campaign.budget)
    {
        eprintln!("{note}");
    }
    let (runtime, stop) = runtime_stopped_by_signals()?;
    let progress = Reporter::new(args.quiet || args.json);
    let report = run_campaign(cfg, &plan.folder, &progress, &stop, runtime.handle())?;
    print_summary(&report, &plan, args.json)?;
    let unspent = cfg.campaign.budget.saturating_sub(report.suite.flown);
    if unspent > 0 && !stop.load(Ordering::SeqCst) {
        eprintln!(
            "warning: {unspent} of the budget's {} flights went unspent: too few candidates were predicted below \
             --threshold {} m, or vehicles or backends failed (see the warnings above)",
            cfg.campaign.budget, cfg.screening.threshold_m
        );
    }
    if let Some(w) = floor_warning(report.suite.diversity, cfg.adapts(), cfg.learning.min_diversity) {
        eprintln!("warning: {w}");
    }
    let failed_jobs: usize = report.backends.iter().map(|b| b.failed_jobs).sum();
    if failed_jobs > 0 {
        eprintln!(
            "warning: {} failed on their backend (not charged; see report.md)",
            user_report::plural(failed_jobs, "flight")
        );
        if report.suite.flown == 0 {
            // Every flight failed on the backend: that is a broken setup, not a clean run with no failure.
            return Ok(ExitCode::from(super::EXIT_FAIL));
        }
    }
    if stop.load(Ordering::SeqCst) {
        eprintln!(
            "interrupted: resume with  prgenuav generate --resume {}",
            plan.folder.display()
        );
        return Ok(ExitCode::from(super::EXIT_FAIL));
    }
    Ok(ExitCode::SUCCESS)
}

/// How long the campaign may take to stop after the first Ctrl-C: landing commands are bounded at a few
/// seconds and every stage checks the stop between candidates, so this is a backstop, not the usual path.
const STOP_WITHIN: Duration = Duration::from_secs(20);

/// The async runtime a campaign's vehicles use, and the flag Ctrl-C, SIGTERM or SIGHUP raises to stop it.
pub(super) fn runtime_stopped_by_signals() -> anyhow::Result<(tokio::runtime::Runtime, Arc<AtomicBool>)> {
    runtime_stopped_by_signals_resuming("resume with --resume")
}

/// [`runtime_stopped_by_signals`] for a command that resumes otherwise: `resume` says how.
pub(super) fn runtime_stopped_by_signals_resuming(
    resume: &'static str,
) -> anyhow::Result<(tokio::runtime::Runtime, Arc<AtomicBool>)> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    let stop = Arc::new(AtomicBool::new(false));
    let signals = StopSignals::register(runtime.handle()).context("handling Ctrl-C, SIGTERM and SIGHUP")?;
    runtime.spawn(watch_ctrl_c(stop.clone(), signals, resume));
    Ok((runtime, stop))
}

/// Exit code after a forced stop (128 + SIGINT, as a shell reports it).
const EXIT_INTERRUPTED: i32 = 130;

/// First Ctrl-C (or SIGTERM, or SIGHUP): stop the campaign (vehicles in the air land; their flights are
/// journaled `interrupted`, not charged, flown first on resume; runner jobs are stopped). A second one, or
/// [`STOP_WITHIN`] without stopping, exits at once: the journal keeps every finished flight, and a flight cut
/// mid-record is a torn line the next resume drops.
async fn watch_ctrl_c(stop: Arc<AtomicBool>, mut signals: StopSignals, resume: &'static str) {
    let first = signals.next().await;
    eprintln!(
        "{first}: landing the vehicles in flight, keeping every finished flight (stops within {} s; Ctrl-C again \
         to exit now); {resume}",
        STOP_WITHIN.as_secs()
    );
    stop.store(true, Ordering::SeqCst);
    tokio::select! {
        second = signals.next() => {
            eprintln!("second {second}: exiting now; flights in the air are flown again on resume");
        }
        () = tokio::time::sleep(STOP_WITHIN) => {
            eprintln!("did not stop within {} s: exiting now; {resume}", STOP_WITHIN.as_secs());
        }
    }
    std::process::exit(EXIT_INTERRUPTED);
}

/// The report on stdout: JSON, or the figures, the verdict and next step, and the output folder.
fn print_summary(report: &Report, plan: &Plan, json: bool) -> anyhow::Result<()> {
    let folder = &plan.folder;
    if json {
        let mut value = serde_json::to_value(report)?;
        value["output_folder"] = serde_json::json!(folder.display().to_string());
        return super::print_json(&value);
    }
    for line in user_report::stdout_lines(&report.view(), folder) {
        println!("{line}");
    }
    Ok(())
}

/// What `--resume` of a campaign that already flew its budget says: nothing is left to fly.
fn complete_note(folder: &std::path::Path, budget: usize) -> Option<String> {
    let records = prgenuav::campaign::store::journal::Journal::read(&folder.join("journal.jsonl")).ok()?;
    let flown = prgenuav::campaign::store::journal::flights_charged(&records);
    (flown >= budget).then(|| {
        format!(
            "the campaign in {} is complete: it flew its budget ({flown} of {budget} flights); nothing is left to \
             fly, its report is written again",
            folder.display()
        )
    })
}

/// The floor bounds an expectation: what to say when a learning campaign's failing tests still ended below it.
fn floor_warning(diversity: Option<f64>, adapt: bool, floor: f64) -> Option<String> {
    let d = diversity.filter(|&d| adapt && d < floor)?;
    Some(format!(
        "the failing tests' diversity {d:.3} ended below --min-diversity {floor} (the campaign kept their expected \
         diversity above it; the failures fell closer together than expected)"
    ))
}

#[cfg(test)]
mod tests {
    use super::floor_warning;

    #[test]
    fn a_learning_campaign_below_its_diversity_floor_says_so() {
        let w = floor_warning(Some(0.708), true, 0.8).unwrap();
        assert!(w.contains("0.708") && w.contains("--min-diversity 0.8"), "{w}");
        assert_eq!(floor_warning(Some(0.81), true, 0.8), None);
        assert_eq!(floor_warning(None, true, 0.8), None, "fewer than two failing tests");
        assert_eq!(
            floor_warning(Some(0.5), false, 0.8),
            None,
            "static campaigns have no floor"
        );
    }
}
