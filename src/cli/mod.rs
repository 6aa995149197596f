//! Subcommands, one file each: validate arguments, call the library, print, return an exit code.

mod check;
mod distance;
#[cfg(test)]
mod doc;
mod evaluate;
mod fidelity;
mod fly;
mod fly_backend;
mod generate;
mod limits;
mod out_folder;
mod progress;
mod render;
mod sample;
mod score;
mod setting_flags;
mod simulate;
mod stop_signals;
mod values;
mod wording;

use std::process::ExitCode;

use clap::{ArgMatches, CommandFactory, FromArgMatches, Parser, Subcommand};

/// Exit code: the input broke a rule (or a flight failed a check).
pub const EXIT_FAIL: u8 = 1;
/// Exit code: the input could not be read or the job could not run.
pub const EXIT_ERROR: u8 = 2;

/// Pseudo-random UAV test generation with a low-fidelity simulator, and flights over MAVLink.
#[derive(Debug, Parser)]
#[command(name = "prgenuav", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The main job: sample candidates, screen them with the LFS, fly the most severe within BUDGET flights,
    /// and write the failing tests best first with a report.
    #[command(override_usage = "prgenuav generate [OPTIONS] CASE BUDGET\n       prgenuav generate --resume FOLDER")]
    Generate(Box<generate::GenerateArgs>),
    /// Check a test against the competition's rules (exit 0 valid, 1 violations, 2 unreadable).
    Check(check::CheckArgs),
    /// Minimum distance of a recorded flight (Aerialist trajectory CSV) to a test's obstacles.
    Distance(distance::DistanceArgs),
    /// Write N generated tests for a case study (the paper's two-obstacle placement, no screening).
    #[command(override_usage = "prgenuav sample [OPTIONS] CASE N")]
    Sample(sample::SampleArgs),
    /// The competition's metrics for a folder of tests with flights (trajectory CSVs or PX4 ULogs).
    Score(score::ScoreArgs),
    /// Fly every test of a suite several times (the 2026 competition's 5) and score it the 2026 way: mean
    /// points, average trajectories, similarity penalty (docs/evaluate.md).
    Evaluate(Box<evaluate::EvaluateArgs>),
    /// Render the depth image (and point cloud) the vehicle's camera sees at a pose.
    Render(render::RenderArgs),
    /// Simulate a test with the low-fidelity simulator (3DVFH* + depth camera) and predict its minimum distance.
    Simulate(simulate::SimulateArgs),
    /// Compare simulated with real minimum distances over a folder of recorded flights (JSON).
    Fidelity(fidelity::FidelityArgs),
    /// Fly a test over MAVLink (PX4 SITL, hardware or the mock) with virtual obstacles; report the true minimum
    /// distance (exit 0: landed or collision; 1: the flight did not complete (timeout, link lost, aborted,
    /// refused by the vehicle); 2: an error, also a vehicle too far from the test's home).
    Fly(fly::FlyArgs),
}

/// The command line's definition, with a fixed help width so `--help` and docs/cli.md read the same on every
/// terminal.
pub fn command() -> clap::Command {
    Cli::command().term_width(100)
}

/// Parses the process's arguments (exiting with clap's message on a usage error) and runs the subcommand.
pub fn main() -> anyhow::Result<ExitCode> {
    let matches = command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    run(cli, &matches)
}

/// Runs the parsed command line; `matches` tells flags given from defaults.
fn run(cli: Cli, matches: &ArgMatches) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Generate(a) => {
            let empty = ArgMatches::default();
            generate::run(*a, matches.subcommand_matches("generate").unwrap_or(&empty))
        }
        Command::Check(a) => check::run(a),
        Command::Distance(a) => distance::run(a),
        Command::Sample(a) => sample::run(a),
        Command::Score(a) => score::run(a),
        Command::Evaluate(a) => evaluate::run(*a),
        Command::Render(a) => render::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Fidelity(a) => fidelity::run(a),
        Command::Fly(a) => fly::run(a),
    }
}

/// Loads a test and applies the competition's rules; an invalid test gets `check`'s violations on stderr
/// and `None` (the caller exits with [`EXIT_FAIL`]).
pub fn load_valid_test(path: &std::path::Path) -> anyhow::Result<Option<prgenuav::model::TestCase>> {
    let test = prgenuav::model::TestCase::load(path)?;
    let violations = prgenuav::rules::check(&test, &prgenuav::model::Arena::default());
    if violations.is_empty() {
        return Ok(Some(test));
    }
    eprintln!(
        "{}: {}",
        path.display(),
        prgenuav::campaign::report::user_report::plural(violations.len(), "violation")
    );
    for v in &violations {
        eprintln!("  {} = {}: {}", v.path, v.value, v.rule);
    }
    Ok(None)
}

/// Checks every output a command was given before it does any work (a flight flown for a plot that cannot be
/// written is a flight wasted), naming the flag.
pub fn check_outputs(outputs: &[(&str, Option<&std::path::Path>)]) -> anyhow::Result<()> {
    for (flag, path) in outputs {
        if let Some(path) = path {
            prgenuav::io::check_writable(path).map_err(|e| anyhow::anyhow!("{flag}: {e}"))?;
        }
    }
    Ok(())
}

/// Loads a test for `fly` or `simulate`: a test that breaks the current competition rules (older editions
/// allowed 10 m high boxes and footprints past the arena; the recorded flights use them) is accepted with a
/// warning naming each rule, unless `strict`, which refuses it as `check` does (`None`: exit [`EXIT_FAIL`]).
pub fn load_test(path: &std::path::Path, strict: bool) -> anyhow::Result<Option<prgenuav::model::TestCase>> {
    if strict {
        return load_valid_test(path);
    }
    let test = prgenuav::model::TestCase::load(path)?;
    for v in prgenuav::rules::check(&test, &prgenuav::model::Arena::default()) {
        eprintln!(
            "warning: {}: breaks a current rule, flown anyway (--strict refuses): {} = {}: {}",
            path.display(),
            v.path,
            v.value,
            v.rule
        );
    }
    Ok(Some(test))
}

/// Prints `value` as pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}
