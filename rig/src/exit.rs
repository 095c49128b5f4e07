//! How a command of `rig` ends: the one place that prints an error. An error is one line
//! of standard error — `error: `, the error, then each of its causes after `: ` (what a
//! `.context` added, the operating system's reason) — and the exit code of its kind: 2
//! for what the command was asked (flags, files, configuration), 1 for what went wrong
//! while it worked. Standard error is a pipe or a terminal; should it fail (the reader
//! gone), the error is lost rather than turned into a panic.

use std::io::Write as _;
use std::process::ExitCode;

/// A command's error, and the exit code it ends with.
#[derive(Debug)]
pub struct Failed {
    error: anyhow::Error,
    code: u8,
}

/// How a command ends: its exit code, or an error.
pub type Outcome = Result<ExitCode, Failed>;

impl Failed {
    /// `message` about what the command was asked: exit code 2.
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            error: anyhow::Error::msg(message.into()),
            code: 2,
        }
    }

    /// `message` about what went wrong while working: exit code 1.
    pub fn failure(message: impl Into<String>) -> Self {
        Self {
            error: anyhow::Error::msg(message.into()),
            code: 1,
        }
    }

    /// The line the error is printed as.
    fn line(&self) -> String {
        format!("error: {:#}", self.error)
    }
}

/// An error's kind, given where it happened.
pub trait Fails<T> {
    /// An error in what the command was asked: exit code 2.
    fn usage(self) -> Result<T, Failed>;
    /// An error while the command worked: exit code 1.
    fn failure(self) -> Result<T, Failed>;
}

impl<T, E: Into<anyhow::Error>> Fails<T> for Result<T, E> {
    fn usage(self) -> Result<T, Failed> {
        self.map_err(|e| Failed {
            error: e.into(),
            code: 2,
        })
    }

    fn failure(self) -> Result<T, Failed> {
        self.map_err(|e| Failed {
            error: e.into(),
            code: 1,
        })
    }
}

/// The exit code of `outcome`, its error printed.
pub fn report(outcome: Outcome) -> ExitCode {
    match outcome {
        Ok(code) => code,
        Err(f) => {
            let _ = writeln!(std::io::stderr(), "{}", f.line());
            ExitCode::from(f.code)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    /// The error and every cause, on one line; the code of its kind.
    #[test]
    fn an_error_is_printed_with_its_causes() {
        let e = std::fs::read("/nonexistent/x.toml")
            .context("cannot read /nonexistent/x.toml")
            .context("`--config`")
            .usage()
            .unwrap_err();
        assert_eq!(e.code, 2);
        let line = e.line();
        assert!(
            line.starts_with("error: `--config`: cannot read /nonexistent/x.toml: No such file"),
            "{line}"
        );
        let e = Failed::failure("the run stopped");
        assert_eq!((e.code, e.line().as_str()), (1, "error: the run stopped"));
    }
}
