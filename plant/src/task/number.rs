//! Numbers in task files: a TOML number (`inf` and `-inf` included), or a multiple of π
//! written as text — `"pi"`, `"-pi"`, `"8pi"`, `"-0.5*pi"`, `"π"` — so that angle ranges
//! and start states read as the thesis writes them.

use std::f64::consts::PI;
use std::fmt;

use serde::de::{self, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A number of a task file (see the module documentation); written back as a plain
/// TOML number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Number(pub f64);

impl Number {
    /// `k·π` for the text `s` (`"pi"`, `"-8pi"`, `"0.5*pi"`, `"π"`), else `None`.
    ///
    /// `k·π` is computed as `k * PI`, so `"-8pi"` is exactly `-8.0 * PI`.
    pub fn parse_pi(s: &str) -> Option<f64> {
        let s = s.trim();
        let k = s.strip_suffix("pi").or_else(|| s.strip_suffix('π'))?.trim();
        let k = k.strip_suffix('*').unwrap_or(k).trim();
        let factor = match k {
            "" | "+" => 1.0,
            "-" => -1.0,
            _ => k.parse::<f64>().ok().filter(|v| v.is_finite())?,
        };
        Some(factor * PI)
    }
}

impl Serialize for Number {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(self.0)
    }
}

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(NumberVisitor)
    }
}

struct NumberVisitor;

impl Visitor<'_> for NumberVisitor {
    type Value = Number;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number, or a multiple of pi as text (\"pi\", \"-8pi\", \"0.5*pi\")")
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Number, E> {
        Ok(Number(v))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Number, E> {
        Ok(Number(v as f64))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Number, E> {
        Ok(Number(v as f64))
    }

    fn visit_str<E: de::Error>(self, s: &str) -> Result<Number, E> {
        Number::parse_pi(s)
            .map(Number)
            .ok_or_else(|| E::invalid_value(de::Unexpected::Str(s), &self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn multiples_of_pi_are_the_products_the_code_writes() {
        assert_eq!(Number::parse_pi("pi"), Some(PI));
        assert_eq!(Number::parse_pi("-pi"), Some(-PI));
        assert_eq!(Number::parse_pi("π"), Some(PI));
        assert_eq!(Number::parse_pi("-8pi"), Some(-8.0 * PI));
        assert_eq!(Number::parse_pi("2 * pi"), Some(2.0 * PI));
        assert_eq!(Number::parse_pi("0.5*pi"), Some(0.5 * PI));
        for bad in ["", "p", "2", "pie", "x pi", "inf pi", "--pi"] {
            assert_eq!(Number::parse_pi(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn numbers_and_text_deserialise() {
        #[derive(Deserialize)]
        struct T {
            v: Vec<Number>,
        }
        let t: T = toml::from_str("v = [1, -2.5, \"-2pi\", inf, -inf]").unwrap();
        let v: Vec<f64> = t.v.iter().map(|n| n.0).collect();
        assert_eq!(v, [1.0, -2.5, -2.0 * PI, f64::INFINITY, f64::NEG_INFINITY]);
        let e = toml::from_str::<T>("v = [\"tau\"]").err().unwrap();
        assert!(e.message().contains("multiple of pi"), "{}", e.message());
    }
}
