//! `prgenuav sample CASE.yaml --count N [--seed S] [--out DIR] [--json]`: tests without screening.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use prgenuav::generator::{Family, Generator, GeneratorConfig, Placement};
use prgenuav::judge::diversity;
use prgenuav::model::{Range, TestCase};

use super::Spelling;

/// Arguments of `sample`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The case study YAML (mission, params, commands).
    case: PathBuf,
    /// How many tests to write.
    #[arg(long)]
    count: u64,
    /// Seed of every random draw: the same seed gives byte-identical tests.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output folder for test_0.yaml, test_1.yaml, ...
    #[arg(long, default_value = "generated_tests/samples")]
    out: PathBuf,
    /// Print a JSON summary instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    generator: GeneratorArgs,
}

/// Generator parameters: a TOML file and single overrides (see `GeneratorConfig`).
#[derive(Debug, clap::Args)]
pub struct GeneratorArgs {
    /// TOML file with generator parameters (keys of GeneratorConfig); flags below override it.
    #[arg(long, value_name = "FILE.toml")]
    pub config: Option<PathBuf>,
    /// Diagonal of obstacle 1's base, metres: MIN,MAX.
    #[arg(long, value_name = "MIN,MAX", value_parser = parse_range)]
    pub diagonal: Option<Range>,
    /// Acute angle between obstacle 1's A part and the direction of flight, degrees: MIN,MAX.
    #[arg(long, value_name = "MIN,MAX", value_parser = parse_range)]
    pub angle: Option<Range>,
    /// Gap between obstacle 1's A end and obstacle 2, metres: MIN,MAX.
    #[arg(long, value_name = "MIN,MAX", value_parser = parse_range)]
    pub gap: Option<Range>,
    /// Box height, metres.
    #[arg(long)]
    pub height: Option<f64>,
    /// Construction: paper (two obstacles, the paper's split) or extended (the split drawn too, and a third
    /// obstacle beyond the pair where the mission leaves room).
    #[arg(long, value_enum)]
    pub family: Option<FamilyArg>,
    /// Key spelling of the written YAML: new (robot/mission) or old (drone/test, Aerialist before 2025-09).
    #[arg(long, value_enum, default_value_t = Spelling::New)]
    pub spelling: Spelling,
}

impl GeneratorArgs {
    /// The configuration: defaults, then the TOML file, then the flags.
    pub fn config(&self) -> anyhow::Result<GeneratorConfig> {
        let mut c = match &self.config {
            Some(path) => {
                let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
                GeneratorConfig::from_toml(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?
            }
            None => GeneratorConfig::default(),
        };
        c.diagonal_m = self.diagonal.unwrap_or(c.diagonal_m);
        c.angle_deg = self.angle.unwrap_or(c.angle_deg);
        c.gap_m = self.gap.unwrap_or(c.gap_m);
        c.height_m = self.height.unwrap_or(c.height_m);
        c.family = match self.family {
            Some(FamilyArg::Paper) => Family::Paper,
            Some(FamilyArg::Extended) => Family::Extended,
            None => c.family,
        };
        c.validate().map_err(|e| anyhow::anyhow!("generator parameters: {e}"))?;
        Ok(c)
    }
}

/// `--family`'s values.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum FamilyArg {
    /// The paper's two-obstacle S.
    Paper,
    /// The split drawn, and a third obstacle where the case allows.
    Extended,
}

fn parse_range(s: &str) -> Result<Range, String> {
    let (a, b) = s.split_once(',').ok_or_else(|| format!("{s:?}: expected MIN,MAX"))?;
    let num = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("{t:?} is not a number"));
    Ok(Range::new(num(a)?, num(b)?))
}

#[derive(serde::Serialize)]
struct Written<'a> {
    file: String,
    #[serde(flatten)]
    placement: &'a Placement,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if args.count == 0 {
        bail!("--count must be at least 1");
    }
    let config = args.generator.config()?;
    let case = TestCase::load(&args.case)?;
    let generator = Generator::new(&case, config, args.seed)?;
    let placements: Vec<Placement> = (0..args.count).map(|i| generator.sample(i)).collect::<Result<_, _>>()?;
    let mut files = Vec::new();
    for p in &placements {
        let path = args.out.join(format!("test_{}.yaml", p.index));
        case.with_obstacles(p.obstacles.to_vec())
            .save(&path, args.generator.spelling.into())?;
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
            "seed": args.seed,
            "soi": generator.soi(),
            "a_side": generator.a_side(),
            "diversity": div,
            "tests": tests,
        }))?;
    } else {
        let s = generator.soi();
        println!(
            "segment of interest: mission segment {} from ({:.2}, {:.2}) to ({:.2}, {:.2}), A side {:?}",
            s.segment,
            s.start.x,
            s.start.y,
            s.end.x,
            s.end.y,
            generator.a_side()
        );
        println!(
            "wrote {} tests (seed {}), diversity {}",
            files.len(),
            args.seed,
            div.map_or("n/a".into(), |d| format!("{d:.3}"))
        );
        println!("output folder: {}", args.out.display());
    }
    Ok(ExitCode::SUCCESS)
}
