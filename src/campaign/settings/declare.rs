//! The macro that declares a section of settings once: from each key's name, type, default and description
//! it generates the section as asked (every key optional, as the TOML file and the flags give it), the section
//! as resolved (every default filled in, the setup's rules applied) and the section's table of [`Setting`]s
//! (flags, ranges, docs).

use super::choice::SettingValue;
use super::{DefaultValue, Resume, Setting};

/// No choices: an open type.
fn no_choices() -> &'static [(&'static str, &'static str)] {
    &[]
}

/// A setting with no flag and no range, fixed for the campaign's life: what each declaration starts from.
pub(super) const BLANK: Setting = Setting {
    section: "",
    key: "",
    flag: None,
    resume: Resume::Fixed,
    default: DefaultValue::Absent { doc: "", example: "" },
    range: None,
    choices: no_choices,
    help: "",
    parse: <String as SettingValue>::parse,
};

/// Declares a section: `$asked` (each key an `Option`, unknown keys refused), `$name` (each key resolved), a
/// getter on `$asked` per constant default, `$asked::resolve` and the table `$table`.
///
/// Defaults: `[value EXPR]` a constant; `[rule FN, "words", "example"]` a rule of the setup (`FN(&Setup)`);
/// `[required "example"]` none, a new campaign must give it; `[absent "words", "example"]` none, the key is an
/// `Option` in `$name` too.
macro_rules! section {
    (@ty $ty:ty, [value $d:expr]) => { $ty };
    (@ty $ty:ty, [rule $f:path, $doc:literal, $ex:literal]) => { $ty };
    (@ty $ty:ty, [required $ex:literal]) => { $ty };
    (@ty $ty:ty, [absent $doc:literal, $ex:literal]) => { Option<$ty> };
    (@get $field:ident, $ty:ty, [value $d:expr]) => {
        /// The value given, else the default.
        pub fn $field(&self) -> $ty { self.$field.clone().unwrap_or_else(|| $d) }
    };
    (@get $field:ident, $ty:ty, [$($other:tt)*]) => {};
    (@resolve $v:expr, $s:ident, $key:expr, [value $d:expr]) => { $v.clone().unwrap_or_else(|| $d) };
    (@resolve $v:expr, $s:ident, $key:expr, [rule $f:path, $doc:literal, $ex:literal]) => {
        $v.clone().unwrap_or_else(|| $f($s))
    };
    (@resolve $v:expr, $s:ident, $key:expr, [required $ex:literal]) => {
        $v.clone().ok_or_else(|| format!("{} is required", $key))?
    };
    (@resolve $v:expr, $s:ident, $key:expr, [absent $doc:literal, $ex:literal]) => { $v.clone() };
    (@over $kept:expr, $asked:expr, [absent $doc:literal, $ex:literal]) => { $asked.clone().or($kept.clone()) };
    (@over $kept:expr, $asked:expr, [$($other:tt)*]) => { $asked.clone().unwrap_or($kept.clone()) };
    (@default $ty:ty, [value $d:expr]) => {
        $crate::campaign::settings::DefaultValue::Constant(|| toml::Value::try_from::<$ty>($d).ok())
    };
    (@default $ty:ty, [rule $f:path, $doc:literal, $ex:literal]) => {
        $crate::campaign::settings::DefaultValue::Rule { doc: $doc, example: $ex }
    };
    (@default $ty:ty, [required $ex:literal]) => {
        $crate::campaign::settings::DefaultValue::Required { example: $ex }
    };
    (@default $ty:ty, [absent $doc:literal, $ex:literal]) => {
        $crate::campaign::settings::DefaultValue::Absent { doc: $doc, example: $ex }
    };
    ($(#[$m:meta])* $name:ident, $asked:ident, $section:literal, $table:ident {
        $( $field:ident : $ty:ty = [$($default:tt)*] { $($desc:tt)* } ),* $(,)?
    }) => {
        #[doc = concat!("The `[", $section, "]` settings as asked: each one given by the campaign TOML or a flag, or not.")]
        #[derive(Debug, Default, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
        #[serde(deny_unknown_fields)]
        pub struct $asked {
            $( #[doc = concat!("`", $section, ".", stringify!($field), "`.")] pub $field: Option<$ty>, )*
        }

        $(#[$m])*
        #[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $( #[doc = concat!("`", $section, ".", stringify!($field), "` (its declaration says what it does).")]
               pub $field: section!(@ty $ty, [$($default)*]), )*
        }

        impl $asked {
            $( section!(@get $field, $ty, [$($default)*]); )*

            /// The section with every default filled in, the setup's rules from `setup`; an error names a
            /// required key not given.
            pub fn resolve(&self, setup: &$crate::campaign::settings::rules::Setup) -> Result<$name, String> {
                let _ = setup;
                Ok($name {
                    $( $field: section!(@resolve self.$field, setup, concat!($section, ".", stringify!($field)),
                                        [$($default)*]), )*
                })
            }
        }

        impl $name {
            /// The section with the keys `asked` gives laid over it.
            pub fn overridden(&self, asked: &$asked) -> $name {
                $name { $( $field: section!(@over self.$field, asked.$field, [$($default)*]), )* }
            }
        }

        #[doc = concat!("The `[", $section, "]` settings.")]
        #[allow(clippy::needless_update, reason = "a declaration may give every field the blank one has")]
        pub const $table: &[$crate::campaign::settings::Setting] = &[ $(
            $crate::campaign::settings::Setting {
                section: $section,
                key: stringify!($field),
                default: section!(@default $ty, [$($default)*]),
                parse: <$ty as $crate::campaign::settings::choice::SettingValue>::parse,
                choices: <$ty as $crate::campaign::settings::choice::SettingValue>::choices,
                $($desc)*
                ..$crate::campaign::settings::declare::BLANK
            }
        ),* ];
    };
}

pub(super) use section;
