//! The declaration of every campaign setting, section by section: the section types of the campaign TOML
//! ([`super::file`]) are generated from it, with a getter for each constant default.

use super::{DefaultValue, Flag, FlagText, Setting};
use crate::generator::GeneratorConfig;
use crate::generator::limits as bounds;
use crate::model::Range;

/// The largest speed-up of simulated time: beyond it a vehicle's physics step outruns any link.
pub const MAX_TIME_SCALE: f64 = 1000.0;
/// The largest budget accepted. A campaign keeps its journal in memory (about 1 KB a flight) and the report
/// compares failing tests pairwise, so 10,000 flights stay small; on the mock they take about 5 hours.
pub const MAX_BUDGET: usize = 10_000;
/// The most candidates accepted. Each is screened by a full low-fidelity flight (about 0.2 s of one core), so
/// 100,000 are hours of screening; they are held as a few hundred bytes each.
pub const MAX_CANDIDATES: usize = 100_000;
/// Fitted against the recorded competition flights: any pose age only adds clearance, so none is modelled
/// (docs/design-constants.md#mock-pose-latency).
pub const DEFAULT_MOCK_LATENCY_MS: f64 = 0.0;
/// Embedded mock autopilots per core, at most: each simulates and judges a flight on the campaign's threads.
pub const MOCKS_PER_CORE: usize = 8;

/// A setting with no flag, no stored key and no range: what each declaration starts from.
pub(super) const BLANK: Setting = Setting {
    section: "",
    key: "",
    flag: None,
    stored: "",
    default: DefaultValue::Setup { doc: "", example: "" },
    range: None,
    choices: &[],
    help: "",
    parse: <String as FlagText>::parse,
};

/// Declares a section: its type (every key optional, unknown keys refused), a getter per constant default
/// (`[value EXPR]`), and its table of [`Setting`]s. `[setup "words", "example"]` is a default the campaign's
/// setup decides.
macro_rules! section {
    ($(#[$m:meta])* $name:ident, $section:literal, $table:ident {
        $( $field:ident : $ty:ty = [$($default:tt)*] { $($desc:tt)* } ),* $(,)?
    }) => {
        $(#[$m])*
        #[derive(Debug, Default, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name { $( #[doc = concat!("`", $section, ".", stringify!($field), "`.")] pub $field: Option<$ty>, )* }

        impl $name { $( section!(@get $field $ty [$($default)*]); )* }

        #[doc = concat!("The `[", $section, "]` settings.")]
        pub const $table: &[Setting] = &[ $( section!(@setting $section, $field, $ty, [$($default)*], $($desc)*) ),* ];
    };
    (@setting $section:literal, $field:ident, $ty:ty, [$($default:tt)*], $($desc:tt)*) => {
        Setting {
            section: $section,
            key: stringify!($field),
            default: section!(@default $ty [$($default)*]),
            parse: <$ty as FlagText>::parse,
            $($desc)*
            ..BLANK
        }
    };
    (@get $field:ident $ty:ty [value $d:expr]) => {
        /// The value given, else the default.
        pub fn $field(&self) -> $ty { self.$field.clone().unwrap_or_else(|| $d) }
    };
    (@get $field:ident $ty:ty [setup $doc:literal, $ex:literal]) => {};
    (@default $ty:ty [value $d:expr]) => { DefaultValue::Constant(|| toml::Value::try_from::<$ty>($d).ok()) };
    (@default $ty:ty [setup $doc:literal, $ex:literal]) => { DefaultValue::Setup { doc: $doc, example: $ex } };
}

/// Declares the `[generator]` keys, whose type is the generator's own [`GeneratorConfig`].
macro_rules! generator {
    ($( $field:ident : $ty:ty { $($desc:tt)* } ),* $(,)?) => {
        /// The `[generator]` settings.
        pub const GENERATOR: &[Setting] = &[ $(
            section!(@setting "generator", $field, $ty, [value GeneratorConfig::default().$field], $($desc)*)
        ),* ];
    };
}

generator! {
    diagonal_m: Range {
        flag: Some(Flag::value("--diagonal", "MIN,MAX")),
        stored: "generator.diagonal_m",
        range: Some(bounds::DIAGONAL_M),
        help: "Diagonal of obstacle 1's base, metres; the upper bound keeps obstacle 2 (1.75 x as long) within the 20 m rule.",
    },
    width_m: f64 {
        stored: "generator.width_m",
        range: Some(bounds::WIDTH_M),
        help: "Width of both bases, metres.",
    },
    split: f64 {
        stored: "generator.split",
        range: Some(bounds::SPLIT),
        help: "Share of obstacle 1's length on the A side of the segment of interest (the paper family's).",
    },
    length_factor: f64 {
        stored: "generator.length_factor",
        range: Some(bounds::LENGTH_FACTOR),
        help: "Obstacle 2's length as a multiple of obstacle 1's, so the drone cannot circle it.",
    },
    height_m: f64 {
        flag: Some(Flag::value("--height", "M")),
        stored: "generator.height_m",
        range: Some(bounds::HEIGHT_M),
        help: "Height of both boxes, metres (above the 10 m flight altitude, so the drone cannot fly over).",
    },
    angle_deg: Range {
        flag: Some(Flag::value("--angle", "MIN,MAX")),
        stored: "generator.angle_deg",
        range: Some(bounds::ANGLE_DEG),
        help: "Acute angle between obstacle 1's A part and the direction of flight, degrees.",
    },
    gap_m: Range {
        flag: Some(Flag::value("--gap", "MIN,MAX")),
        stored: "generator.gap_m",
        range: Some(bounds::GAP_M),
        help: "Gap between obstacle 1's A end and obstacle 2, metres.",
    },
    overhang: Range {
        stored: "generator.overhang",
        range: Some(bounds::OVERHANG),
        help: "How far obstacle 2 reaches past obstacle 1's far face, as a share of its length.",
    },
    family: crate::generator::Family {
        flag: Some(Flag::value("--family", "FAMILY")),
        stored: "generator.family",
        choices: &[
            ("paper", "The paper's two-obstacle S."),
            ("extended", "The split drawn too, and a third obstacle where the case allows."),
            ("gate", "Two boxes across the path with a gap around 2 x CP_DIST."),
        ],
        help: "`paper` (two obstacles, the paper's split), `extended` (the split drawn from `adapted_split`, and a \
               third obstacle beyond the pair where the mission leaves room) or `gate` (two boxes across the path \
               with a gap around 2 x CP_DIST; the default with --mode collision-prevention).",
    },
    adapted_split: Range {
        stored: "generator.adapted_split",
        range: Some(bounds::ADAPTED_SPLIT),
        help: "The extended family's range of `split`.",
    },
    third_ahead_m: Range {
        stored: "generator.third_ahead_m",
        range: Some(bounds::THIRD_AHEAD_M),
        help: "The extended family's clear distance along the segment of interest from the pair to the third \
               obstacle, metres.",
    },
    max_attempts: u32 {
        stored: "generator.max_attempts",
        range: Some(bounds::MAX_ATTEMPTS),
        help: "Draws per test before the generator reports that the mission leaves no room.",
    },
}

section! {
    /// `[output]`.
    Output, "output", OUTPUT {
        spelling: String = [value "new".to_string()] {
            flag: Some(Flag::value("--spelling", "SPELLING")),
            stored: "old_spelling",
            choices: &[
                ("new", "`robot:` and `mission:` (Aerialist since 2025-09)."),
                ("old", "`drone:` and `test:` (Aerialist before 2025-09, e.g. the 2025 competition's)."),
            ],
            help: "Key spelling of the written YAML: `new` (robot/mission) or `old` (drone/test, Aerialist before \
                   2025-09).",
        },
    }
}

pub(super) use section;

/// Numbers only the command line gives.
pub mod flags {
    use crate::model::Limit;

    /// Runner jobs at once, at most: each is a thread and a local process (`sh -c`, `srun`, `kubectl`, ...).
    pub const MAX_JOBS: usize = 1024;
    /// `--jobs` with `--runner`.
    pub const JOBS: Limit = Limit::count(1, MAX_JOBS, "(each job is a thread and a local process)");
    /// `--job-timeout`.
    pub const JOB_TIMEOUT: Limit = Limit::above(0.0, 604_800.0, "s");
    /// `--speed-factor`.
    pub const PX4_SPEED_FACTOR: Limit = Limit::above(0.0, 100.0, "x wall time");
    /// `--instances` with `--px4`.
    pub const INSTANCES: Limit = Limit::count(
        1,
        crate::bridge::sitl::slot::SLOTS as usize,
        "PX4 instances (docs/px4.md)",
    );
    /// BUDGET.
    pub const BUDGET: Limit = Limit::count(1, super::MAX_BUDGET, "flights");
}
