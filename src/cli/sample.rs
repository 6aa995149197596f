//! `prgenuav sample CASE N [--seed S] [--out DIR] [--json]`: tests without screening.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use prgenuav::campaign::report::user_report::plural;
use prgenuav::generator::{Generator, GeneratorConfig, Placement};
use prgenuav::judge::diversity;
use prgenuav::model::TestCase;

use prgenuav::campaign::settings::Loaded;
use prgenuav::model::Spelling;

use super::setting_flags::GeneratorFlags;

/// The most tests `sample` writes: the suite's diversity compares every pair, about 30 s at 5,000 (2.6 s at
/// 1,000, 12.7 s at 3,000 on one core), and each test is a file.
const MAX_COUNT: u64 = 5_000;

/// Arguments of `sample`.
#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// The case study YAML (mission, params, commands).
    #[arg(value_name = "CASE")]
    case: PathBuf,
    /// How many tests to write: 1 to 5000.
    #[arg(value_name = "N", required_unless_present = "count", conflicts_with = "count")]
    n: Option<u64>,
    /// The same as N (kept for scripts).
    #[arg(long, hide = true, value_name = "N")]
    count: Option<u64>,
    /// Folder the tests are written to (test_0.yaml, test_1.yaml, ...); refused when it holds files, unless
    /// --force.
    #[arg(short, long, value_name = "DIR", default_value = "generated_tests/samples")]
    out: PathBuf,
    /// Write into a folder that holds files, replacing its test_N.yaml files.
    #[arg(long)]
    force: bool,
    /// Print a JSON summary instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    generator: GeneratorArgs,
}

/// Generator parameters: the campaign TOML's `[generator]` and `[output]`, and their flags.
#[derive(Debug, clap::Args)]
pub struct GeneratorArgs {
    /// Campaign TOML: its [generator] keys and [output] spelling apply (see docs/cli.md); flags override it.
    #[arg(long, value_name = "FILE.toml")]
    pub config: Option<PathBuf>,
    #[command(flatten)]
    flags: GeneratorFlags,
}

impl GeneratorArgs {
    /// The configuration (defaults, then the TOML file, then the flags), the spelling to write and the seed.
    pub fn config(&self) -> anyhow::Result<(GeneratorConfig, Spelling, u64)> {
        let file = Loaded::read(self.config.as_deref()).map_err(anyhow::Error::msg)?;
        let req = self.flags.request(&file)?;
        Ok((req.generator(), req.asked.output.spelling(), req.asked.campaign.seed()))
    }
}

#[derive(serde::Serialize)]
struct Written<'a> {
    file: String,
    #[serde(flatten)]
    placement: &'a Placement,
}

pub fn run(args: SampleArgs) -> anyhow::Result<ExitCode> {
    let count = args.n.or(args.count).unwrap_or_default();
    if !(1..=MAX_COUNT).contains(&count) {
        bail!("N {count} is out of range: 1 to {MAX_COUNT} tests");
    }
    super::check_outputs(&[("--out", Some(args.out.join("test_0.yaml").as_path()))])?;
    let (config, spelling, seed) = args.generator.config()?;
    let case = TestCase::load(&args.case)?.with_absolute_references()?;
    let generator = Generator::new(&case, config, seed)?;
    let placements: Vec<Placement> = (0..count).map(|i| generator.sample(i)).collect::<Result<_, _>>()?;
    super::out_folder::claim(&args.out, args.force)?;
    let mut files = Vec::new();
    for p in &placements {
        let path = args.out.join(format!("test_{}.yaml", p.index));
        case.with_obstacles(p.obstacles.to_vec()).save(&path, spelling)?;
        files.push(path.display().to_string());
    }
    let suites: Vec<_> = placements.iter().map(|p| p.obstacles.to_vec()).collect();
    let div = diversity(&suites);
    if args.json {
        let tests: Vec<Written> = placements
            .iter()
            .zip(&files)
            .map(|(p, f)| Written {
                file: f.clone(),
                placement: p,
            })
            .collect();
        super::print_json(&serde_json::json!({
            "output_folder": args.out.display().to_string(),
            "seed": seed,
            "soi": generator.soi(),
            "a_side": generator.a_side(),
            "diversity": div,
            "tests": tests,
        }))?;
    } else {
        let s = generator.soi();
        println!(
            "segment of interest: mission segment {} from ({:.2}, {:.2}) to ({:.2}, {:.2}), A side {}",
            s.segment,
            s.start.x,
            s.start.y,
            s.end.x,
            s.end.y,
            format!("{:?}", generator.a_side()).to_lowercase()
        );
        println!(
            "wrote {} (seed {}), diversity {}",
            plural(files.len(), "test"),
            seed,
            div.map_or("n/a".into(), |d| format!("{d:.3}"))
        );
        println!("output folder: {}", args.out.display());
    }
    Ok(ExitCode::SUCCESS)
}
