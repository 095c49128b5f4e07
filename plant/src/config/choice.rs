//! Values chosen by name: on the command line and in configuration files.

/// A value chosen by name, on the command line and in configuration files.
pub trait Choice: Copy + 'static {
    /// Every value, in the order messages list them.
    fn all() -> &'static [Self];
    /// Its spelling.
    fn spelling(self) -> &'static str;
    /// The spellings, comma-separated.
    fn spellings() -> String {
        let names: Vec<&str> = Self::all().iter().map(|v| v.spelling()).collect();
        names.join(", ")
    }
    /// The value spelled `s`; the error lists the spellings.
    fn parse(s: &str) -> Result<Self, UnknownChoice> {
        Self::all()
            .iter()
            .copied()
            .find(|v| v.spelling() == s)
            .ok_or_else(|| UnknownChoice {
                allowed: Self::spellings(),
            })
    }
}

/// A spelling that names no value of a [`Choice`]; says which do.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("one of: {allowed}")]
pub struct UnknownChoice {
    /// The spellings, comma-separated.
    pub allowed: String,
}

/// Defines an enum chosen by name, its spellings written once: the enum (`Clone`,
/// `Copy` and the derives given), `ALL`, `as_str`, `Display`, [`Choice`], serde's
/// `Serialize`/`Deserialize` (a string, one of the spellings) and, with this crate's
/// feature `clap`, `clap::ValueEnum` (so `--help` lists the spellings).
///
/// ```
/// plant::choice! {
///     /// A side.
///     #[derive(Debug, PartialEq)]
///     pub enum Side {
///         /// The left one.
///         Left => "left",
///         /// The right one.
///         Right => "right",
///     }
/// }
/// assert_eq!(Side::Right.to_string(), "right");
/// assert_eq!(Side::ALL, [Side::Left, Side::Right]);
/// ```
#[macro_export]
macro_rules! choice {
    (
        $(#[$meta:meta])*
        $vis:vis enum $t:ident {
            $( $(#[$($vmeta:tt)*])* $v:ident => $s:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy)]
        $vis enum $t {
            $( $(#[$($vmeta)*])* $v ),+
        }
        impl $t {
            /// Every value, in the order messages and help texts list them.
            pub const ALL: [Self; [$($s),+].len()] = [$(Self::$v),+];
            /// The spellings, in the order of `ALL`.
            pub const NAMES: [&'static str; [$($s),+].len()] = [$($s),+];
            /// The command-line / config spelling.
            pub fn as_str(self) -> &'static str { match self { $(Self::$v => $s),+ } }
        }
        impl ::std::fmt::Display for $t {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.as_str())
            }
        }
        impl $crate::config::Choice for $t {
            fn all() -> &'static [Self] { &Self::ALL }
            fn spelling(self) -> &'static str { self.as_str() }
        }
        impl $crate::config::__serde::Serialize for $t {
            fn serialize<S: $crate::config::__serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_unit_variant(stringify!($t), *self as u32, self.as_str())
            }
        }
        impl<'de> $crate::config::__serde::Deserialize<'de> for $t {
            fn deserialize<D: $crate::config::__serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                $crate::config::deserialize_choice(d, &Self::NAMES)
            }
        }
        $crate::__choice_value_enum!($t, $( $s => $crate::__choice_doc!($(#[$($vmeta)*])*) ),+);
    };
}

/// The doc comment among a variant's attributes, its lines joined (the help text of the
/// value in `--help`).
#[doc(hidden)]
#[macro_export]
macro_rules! __choice_doc {
    () => { "" };
    (#[doc = $d:literal] $($rest:tt)*) => { concat!($d, $crate::__choice_doc!($($rest)*)) };
    (#[$($m:tt)*] $($rest:tt)*) => { $crate::__choice_doc!($($rest)*) };
}

/// A [`Choice`] read from its spelling; an unknown one is serde's "unknown variant" error
/// listing the spellings `names`.
pub fn deserialize_choice<'de, T, D>(d: D, names: &'static [&'static str]) -> Result<T, D::Error>
where
    T: Choice,
    D: serde::Deserializer<'de>,
{
    let s = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(d)?;
    T::parse(&s).map_err(|_| serde::de::Error::unknown_variant(&s, names))
}

/// `clap::ValueEnum` for a [`choice!`](crate::choice) enum (feature `clap`).
#[cfg(feature = "clap")]
#[doc(hidden)]
#[macro_export]
macro_rules! __choice_value_enum {
    ($t:ident, $( $s:literal => $doc:expr ),+) => {
        impl $crate::config::__clap::ValueEnum for $t {
            fn value_variants<'a>() -> &'a [Self] {
                &Self::ALL
            }
            fn to_possible_value(&self) -> Option<$crate::config::__clap::builder::PossibleValue> {
                let help = match self.as_str() { $( $s => $doc, )+ _ => "" };
                let value = $crate::config::__clap::builder::PossibleValue::new(self.as_str());
                Some(match help.trim() {
                    "" => value,
                    help => value.help(help),
                })
            }
        }
    };
}

/// Without the feature `clap`, no `clap::ValueEnum`.
#[cfg(not(feature = "clap"))]
#[doc(hidden)]
#[macro_export]
macro_rules! __choice_value_enum {
    ($($any:tt)*) => {};
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SystemName;

    #[test]
    fn parse_lists_the_spellings() {
        assert_eq!(SystemName::parse("arm-6.4"), Ok(SystemName::Arm64));
        assert_eq!(
            SystemName::parse("cartpole").unwrap_err().to_string(),
            "one of: pendulum, arm-vertical, arm-horizontal, arm-6.4, double-integrator"
        );
    }

    #[cfg(feature = "clap")]
    #[test]
    fn a_values_doc_comment_is_its_help_on_the_command_line() {
        use clap::ValueEnum;
        let value = SystemName::Arm64.to_possible_value().unwrap();
        assert_eq!(value.get_name(), "arm-6.4");
        assert_eq!(
            value.get_help().unwrap().to_string(),
            "The manipulator of §6.4.2 (Table 6.3): horizontal plane, `|u| ≤ 0.1 N m`, \
             operating range ±1.2 rad (leaving it ends the trial with reward −4·10⁴), four \
             start states."
        );
    }

    #[test]
    fn serde_reads_and_writes_the_spellings() {
        #[derive(serde::Serialize, serde::Deserialize, Debug, PartialEq)]
        struct Row {
            system: SystemName,
        }
        let row = Row {
            system: SystemName::Arm64,
        };
        let text = toml::to_string(&row).unwrap();
        assert_eq!(text, "system = \"arm-6.4\"\n");
        assert_eq!(toml::from_str::<Row>(&text).unwrap(), row);
        let e = toml::from_str::<Row>("system = \"cartpole\"").unwrap_err();
        assert!(
            e.message().starts_with(
                "unknown variant `cartpole`, expected one of `pendulum`, `arm-vertical`"
            ),
            "{e}"
        );
    }
}
