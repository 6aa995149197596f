//! The command line laid over the campaign TOML: each flag given replaces its key, and the recorder notes
//! which were given, for a resumed campaign's comparison with what it stored.

use prgenuav::generator::GeneratorConfig;

use super::Args;
use crate::cli::settings::{CampaignToml, Flight, Learning, Loaded, Mock, Output, Screening};

/// A setting given explicitly, by a flag or by the TOML file.
pub(super) struct Given {
    /// `--seed`, or `screening.threshold_m`.
    pub(super) name: String,
    /// The TOML file that gave it (`None`: the command line).
    pub(super) file: Option<String>,
    /// A switch (`--no-learn`) is named without a value.
    pub(super) switch: bool,
    /// Its key in campaign.json (`seed`, `generator.gap_m`).
    pub(super) key: String,
}

/// What the command line and the TOML file ask for: the flags laid over the file.
pub(super) struct Requested {
    pub(super) settings: CampaignToml,
    pub(super) generator: GeneratorConfig,
    pub(super) given: Vec<Given>,
    pub(super) out_given: bool,
}

/// Records where each setting came from while the flags are laid over the file.
pub(super) struct Recorder<'a> {
    pub(super) file: &'a Loaded,
    pub(super) given: Vec<Given>,
}

impl Recorder<'_> {
    pub(super) fn flag(&mut self, flag: &str, key: &str) {
        let switch = flag.starts_with("--no-")
            || ["--mock-free-running", "--anchor-at-vehicle-home", "--keep-ulog"].contains(&flag);
        self.given.push(Given {
            name: flag.to_string(),
            file: None,
            switch,
            key: key.to_string(),
        });
    }

    pub(super) fn file_key(&mut self, file_key: &str, key: &str) {
        self.given.push(Given {
            name: file_key.to_string(),
            file: Some(self.file.name()),
            switch: false,
            key: key.to_string(),
        });
    }

    /// The flag's value if given, else the file's, recording which.
    pub(super) fn pick<T>(&mut self, flag: Option<T>, file: Option<T>, (name, file_key, key): Names) -> Option<T> {
        match (flag, file) {
            (Some(v), _) if !key.is_empty() => {
                self.flag(name, key);
                Some(v)
            }
            (None, Some(v)) if !key.is_empty() => {
                self.file_key(file_key, key);
                Some(v)
            }
            (flag, file) => flag.or(file),
        }
    }
}

/// A setting's flag, its key in the TOML file, and its key in campaign.json (empty: campaign.json does not
/// store it, so a resumed campaign may change it).
pub(super) type Names = (&'static str, &'static str, &'static str);

/// The flags laid over the file's sections (a flag wins).
pub(super) fn lay_over(args: &Args, f: &CampaignToml, r: &mut Recorder) -> CampaignToml {
    let e = &args.expert;
    let (sc, mo) = (&f.screening, &f.mock);
    CampaignToml {
        generator: None,
        output: Output {
            spelling: r.pick(
                e.spelling,
                f.output.spelling,
                ("--spelling", "output.spelling", "old_spelling"),
            ),
        },
        screening: Screening {
            candidates: r.pick(
                args.candidates,
                sc.candidates,
                ("--candidates", "screening.candidates", "candidates"),
            ),
            threshold_m: r.pick(
                e.threshold,
                sc.threshold_m,
                ("--threshold", "screening.threshold_m", "threshold_m"),
            ),
            max_iou: r.pick(e.max_iou, sc.max_iou, ("--max-iou", "screening.max_iou", "max_iou")),
            motion: r.pick(e.motion, sc.motion, ("--motion", "screening.motion", "motion")),
            ensemble: r.pick(
                e.ensemble,
                sc.ensemble,
                ("--ensemble", "screening.ensemble", "ensemble"),
            ),
            screen: r.pick(
                e.no_screen.then_some(false),
                sc.screen,
                ("--no-screen", "screening.screen", "screen"),
            ),
        },
        mock: Mock {
            speed: r.pick(e.mock_speed, mo.speed, ("--mock-speed", "mock.speed", "mock_speed")),
            lockstep: r.pick(
                e.mock_free_running.then_some(false),
                mo.lockstep,
                ("--mock-free-running", "mock.lockstep", "mock_lockstep"),
            ),
            latency_ms: r.pick(
                e.mock_latency,
                mo.latency_ms,
                ("--mock-latency", "mock.latency_ms", "mock_latency_ms"),
            ),
            vehicles: r.pick(e.mock_vehicles, mo.vehicles, ("--mock-vehicles", "mock.vehicles", "")),
            profile: r.pick(
                e.mock_profile.clone(),
                mo.profile.clone(),
                ("--mock-profile", "mock.profile", "mock_profile"),
            ),
        },
        flight: flight(args, &f.flight, r),
        learning: learning(args, &f.learning, r),
    }
}

fn flight(args: &Args, fl: &Flight, r: &mut Recorder) -> Flight {
    let e = &args.expert;
    Flight {
        timeout_s: r.pick(
            e.timeout,
            fl.timeout_s,
            ("--timeout", "flight.timeout_s", "flight_timeout_s"),
        ),
        connect_timeout_s: r.pick(
            e.connect_timeout,
            fl.connect_timeout_s,
            ("--connect-timeout", "flight.connect_timeout_s", ""),
        ),
        connect_time_scale: r.pick(
            e.connect_time_scale,
            fl.connect_time_scale,
            ("--connect-time-scale", "flight.connect_time_scale", "hfs_time_scale"),
        ),
        anchor_at_vehicle_home: r.pick(
            e.anchor_at_vehicle_home.then_some(true),
            fl.anchor_at_vehicle_home,
            (
                "--anchor-at-vehicle-home",
                "flight.anchor_at_vehicle_home",
                "anchor_at_vehicle_home",
            ),
        ),
        confirm: r.pick(args.confirm, fl.confirm, ("--confirm", "flight.confirm", "confirm")),
        overlap: r.pick(None, fl.overlap, ("", "flight.overlap", "overlap")),
    }
}

fn learning(args: &Args, le: &Learning, r: &mut Recorder) -> Learning {
    let e = &args.expert;
    Learning {
        learn: r.pick(
            args.no_learn.then_some(false),
            le.learn,
            ("--no-learn", "learning.learn", "learn"),
        ),
        adapt: r.pick(
            e.no_adapt.then_some(false),
            le.adapt,
            ("--no-adapt", "learning.adapt", "adapt"),
        ),
        min_diversity: r.pick(
            e.min_diversity,
            le.min_diversity,
            ("--min-diversity", "learning.min_diversity", "min_diversity"),
        ),
        child_max_iou: r.pick(
            e.child_max_iou,
            le.child_max_iou,
            ("--child-max-iou", "learning.child_max_iou", "child_max_iou"),
        ),
    }
}
