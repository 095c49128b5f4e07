//! Values chosen by name: on the command line and in configuration files.

use crate::SystemName;

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

impl Choice for SystemName {
    fn all() -> &'static [Self] {
        &SystemName::ALL
    }
    fn spelling(self) -> &'static str {
        self.as_str()
    }
}

/// Spells the values of an enum with an `ALL` constant: `as_str`, `Display` and
/// [`Choice`](crate::config::Choice).
///
/// ```
/// #[derive(Clone, Copy)]
/// enum Side { Left, Right }
/// impl Side { const ALL: [Side; 2] = [Side::Left, Side::Right]; }
/// plant::choice_names!(Side, Left => "left", Right => "right");
/// assert_eq!(Side::Right.to_string(), "right");
/// ```
#[macro_export]
macro_rules! choice_names {
    ($t:ty, $($v:ident => $s:literal),*) => {
        impl $t {
            /// The command-line / config spelling.
            pub fn as_str(self) -> &'static str { match self { $(Self::$v => $s),* } }
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
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_lists_the_spellings() {
        assert_eq!(SystemName::parse("arm-6.4"), Ok(SystemName::Arm64));
        assert_eq!(
            SystemName::parse("cartpole").unwrap_err().to_string(),
            "one of: pendulum, arm-vertical, arm-horizontal, arm-6.4, double-integrator"
        );
    }
}
