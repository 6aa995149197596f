//! The declaration of the settings that say what a campaign draws and how it screens it: the obstacle
//! construction (`[generator]`, whose type is the generator's own), the written files (`[output]`) and the
//! low-fidelity screening (`[screening]`).

use super::choice::SettingValue;
use super::declare::{BLANK, section};
use super::keys::MAX_CANDIDATES;
use super::rules;
use super::{DefaultValue, Flag, Setting};
use crate::generator::GeneratorConfig;
use crate::generator::limits as bounds;
use crate::lfs::ensemble::MAX_MEMBERS;
use crate::lfs::sim::Motion;
use crate::model::{Limit, Range, Spelling};

/// Declares the `[generator]` keys, whose type is the generator's own [`GeneratorConfig`].
macro_rules! generator {
    ($( $field:ident : $ty:ty { $($desc:tt)* } ),* $(,)?) => {
        /// The `[generator]` settings.
        pub const GENERATOR: &[Setting] = &[ $(
            Setting {
                section: "generator",
                key: stringify!($field),
                default: DefaultValue::Constant(|| toml::Value::try_from::<$ty>(GeneratorConfig::default().$field).ok()),
                parse: <$ty as SettingValue>::parse,
                choices: <$ty as SettingValue>::choices,
                $($desc)*
                ..BLANK
            }
        ),* ];
    };
}

generator! {
    diagonal_m: Range {
        flag: Some(Flag::value("--diagonal", "MIN,MAX")),
        range: Some(bounds::DIAGONAL_M),
        help: "Diagonal of obstacle 1's base, metres; the upper bound keeps obstacle 2 (1.75 x as long) within the 20 m rule.",
    },
    width_m: f64 {
        range: Some(bounds::WIDTH_M),
        help: "Width of both bases, metres.",
    },
    split: f64 {
        range: Some(bounds::SPLIT),
        help: "Share of obstacle 1's length on the A side of the segment of interest (the paper family's).",
    },
    length_factor: f64 {
        range: Some(bounds::LENGTH_FACTOR),
        help: "Obstacle 2's length as a multiple of obstacle 1's, so the drone cannot circle it.",
    },
    height_m: f64 {
        flag: Some(Flag::value("--height", "M")),
        range: Some(bounds::HEIGHT_M),
        help: "Height of both boxes, metres (above the 10 m flight altitude, so the drone cannot fly over).",
    },
    angle_deg: Range {
        flag: Some(Flag::value("--angle", "MIN,MAX")),
        range: Some(bounds::ANGLE_DEG),
        help: "Acute angle between obstacle 1's A part and the direction of flight, degrees.",
    },
    gap_m: Range {
        flag: Some(Flag::value("--gap", "MIN,MAX")),
        range: Some(bounds::GAP_M),
        help: "Gap between obstacle 1's A end and obstacle 2, metres.",
    },
    overhang: Range {
        range: Some(bounds::OVERHANG),
        help: "How far obstacle 2 reaches past obstacle 1's far face, as a share of its length.",
    },
    family: crate::generator::Family {
        flag: Some(Flag::value("--family", "FAMILY")),
        help: "`paper` (two obstacles, the paper's split), `extended` (the split drawn from `adapted_split`, and a \
               third obstacle beyond the pair where the mission leaves room) or `gate` (two boxes across the path \
               with a gap around 2 x CP_DIST; the default with --mode collision-prevention).",
    },
    adapted_split: Range {
        range: Some(bounds::ADAPTED_SPLIT),
        help: "The extended family's range of `split`.",
    },
    third_ahead_m: Range {
        range: Some(bounds::THIRD_AHEAD_M),
        help: "The extended family's clear distance along the segment of interest from the pair to the third \
               obstacle, metres.",
    },
    max_attempts: u32 {
        range: Some(bounds::MAX_ATTEMPTS),
        help: "Draws per test before the generator reports that the mission leaves no room.",
    },
}

section! {
    /// `[output]`.
    Output, OutputAsked, "output", OUTPUT {
        spelling: Spelling = [value Spelling::New] {
            flag: Some(Flag::value("--spelling", "SPELLING")),
            help: "Key spelling of the written YAML: `new` (robot/mission) or `old` (drone/test, Aerialist before \
                   2025-09).",
        },
    }
}

section! {
    /// `[screening]`.
    Screening, ScreeningAsked, "screening", SCREENING {
        candidates: usize = [rule rules::candidates, "3 x BUDGET, at least 20", "60"] {
            flag: Some(Flag::value("--candidates", "N")),
            range: Some(Limit::count(1, MAX_CANDIDATES, "")),
            help: "Candidates to draw and screen with the low-fidelity simulator.",
        },
        threshold_m: f64 = [value 3.0] {
            flag: Some(Flag::value("--threshold", "M")),
            range: Some(Limit::above(0.0, 100.0, "m")),
            help: "Fly only candidates the simulator predicts closer than this, metres.",
        },
        max_iou: f64 = [value 0.5] {
            flag: Some(Flag::value("--max-iou", "IOU")),
            range: Some(Limit::within(0.0, 1.0, "")),
            help: "Skip a candidate whose footprints overlap an already chosen one by more than this IoU.",
        },
        motion: Motion = [value Motion::Px4] {
            flag: Some(Flag::value("--motion", "MOTION")),
            help: "The simulator's motion model: `px4` or `paper`.",
        },
        ensemble: usize = [rule rules::ensemble, "0 with mock vehicles, 8 with MAVLink ones", "0"] {
            flag: Some(Flag::value("--ensemble", "N")),
            range: Some(Limit::count(0, MAX_MEMBERS, "members")),
            help: "Members of the simulator ensemble run on the 2 x BUDGET most severe candidates, which are then \
                   flown in order of expected points per minute; 0 ranks by the point prediction. An ensemble costs \
                   about 1 s of CPU per candidate: more than a mock flight, far less than a PX4 or hardware flight.",
        },
        screen: bool = [value true] {
            flag: Some(Flag::switch("--no-screen", false).helped(
                "Skip the simulator: fly candidates in the order drawn (screening.screen = false).",
            )),
            help: "`false` skips the simulator and flies candidates in the order drawn (the baseline that shows what \
                   screening buys); it also turns learning off.",
        },
    }
}
