//! `prgenuav check TEST.yaml [--json]`.

use std::path::PathBuf;
use std::process::ExitCode;

use prgenuav::model::{Arena, TestCase};
use prgenuav::rules::{Violation, check, judgeable};

/// Arguments of `check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// The test (or case study) YAML.
    test: PathBuf,
    /// Print `{"valid", "judgeable", "violations": [{"path", "value", "rule"}]}`.
    #[arg(long)]
    json: bool,
}

#[derive(serde::Serialize)]
struct Report<'a> {
    valid: bool,
    /// Whether `evaluate` and `score` can judge it as a test (a case study without obstacles is valid, not
    /// judgeable).
    judgeable: bool,
    violations: &'a [Violation],
}

pub fn run(args: CheckArgs) -> anyhow::Result<ExitCode> {
    let test = TestCase::load(&args.test)?;
    let violations = check(&test, &Arena::default());
    let valid = violations.is_empty();
    let as_test = judgeable(&test);
    if args.json {
        super::print_json(&Report {
            valid,
            judgeable: as_test.is_none(),
            violations: &violations,
        })?;
    } else if let (true, Some(v)) = (valid, &as_test) {
        println!(
            "{}: valid as a case study (0 obstacles); not a test evaluate or score can judge: {} = {}: {}",
            args.test.display(),
            v.path,
            v.value,
            v.rule
        );
    } else if valid {
        println!("{}: valid ({} obstacles)", args.test.display(), test.obstacles.len());
    } else {
        println!(
            "{}: {}",
            args.test.display(),
            prgenuav::campaign::report::user_report::plural(violations.len(), "violation")
        );
        for v in &violations {
            println!("  {} = {}: {}", v.path, v.value, v.rule);
        }
    }
    Ok(if valid {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(super::EXIT_FAIL)
    })
}
