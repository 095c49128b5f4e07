//! Configuration errors and the range checks that produce them.

use std::path::{Path, PathBuf};

/// A configuration error: where, which key, what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}{message}", file_prefix(file.as_deref()), key_prefix(key))]
pub struct ConfigError {
    /// The file the value came from, if any.
    pub file: Option<PathBuf>,
    /// Dotted key, e.g. `critic.neighbours`.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl ConfigError {
    /// An error at `key` (no file yet: the resolver adds the one the value came from).
    pub fn new(key: &str, message: impl Into<String>) -> Self {
        Self {
            file: None,
            key: key.to_string(),
            message: message.into(),
        }
    }
}

/// `FILE: ` when the error has a file.
fn file_prefix(file: Option<&Path>) -> String {
    file.map(|p| format!("{}: ", p.display()))
        .unwrap_or_default()
}

/// `` `KEY`: `` when the error has a key.
fn key_prefix(key: &str) -> String {
    if key.is_empty() {
        String::new()
    } else {
        format!("`{key}`: ")
    }
}

/// Checks `lo ≤ v ≤ hi` (`lo < v < hi` if `open`) and finiteness for a float key; the
/// error names the range.
pub fn check_float(key: &str, v: f64, lo: f64, hi: f64, open: bool) -> Result<(), ConfigError> {
    let ok = v.is_finite()
        && if open {
            v > lo && v < hi
        } else {
            v >= lo && v <= hi
        };
    if ok {
        Ok(())
    } else {
        let range = if open {
            format!("({lo}, {hi})")
        } else {
            format!("[{lo}, {hi}]")
        };
        Err(ConfigError::new(
            key,
            format!("{v} is out of range: must be a finite number in {range}"),
        ))
    }
}

/// Checks `lo ≤ v ≤ hi` for an integer key; the error names the range.
pub fn check_int(key: &str, v: u64, lo: u64, hi: u64) -> Result<(), ConfigError> {
    if v >= lo && v <= hi {
        Ok(())
    } else {
        Err(ConfigError::new(
            key,
            format!("{v} is out of range: must be an integer in {lo}..={hi}"),
        ))
    }
}

/// Checks that a list key has `want` entries, one per `what`.
pub fn check_len(key: &str, len: usize, want: usize, what: &str) -> Result<(), ConfigError> {
    if len == want {
        Ok(())
    } else {
        Err(ConfigError::new(
            key,
            format!("has {len} entries; must have {want}, one per {what}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_file_key_and_range() {
        let mut e = check_float("learning.gamma", 1.5, 0.0, 1.0, true).unwrap_err();
        assert_eq!(
            e.to_string(),
            "`learning.gamma`: 1.5 is out of range: must be a finite number in (0, 1)"
        );
        e.file = Some("exp.toml".into());
        assert!(e.to_string().starts_with("exp.toml: `learning.gamma`: "));
        assert!(check_float("k", f64::NAN, 0.0, 1.0, false).is_err());
        assert!(check_float("k", 1.0, 0.0, 1.0, false).is_ok());
        let e = check_int("run.runs", 0, 1, 100_000).unwrap_err();
        assert_eq!(
            e.message,
            "0 is out of range: must be an integer in 1..=100000"
        );
        let e = check_len("critic.centres", 2, 3, "state component").unwrap_err();
        assert_eq!(
            e.message,
            "has 2 entries; must have 3, one per state component"
        );
    }
}
