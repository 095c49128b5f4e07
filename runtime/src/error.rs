//! Errors shared by the runtime's modules: a file operation that failed, named by what
//! was done to which file.
//!
//! Each module has its own error type for what can go wrong there; they carry a
//! [`FileError`] for the files they read and write, so that every message names the file
//! and the operating system's reason (`{:#}` prints both).

use std::io;
use std::path::{Path, PathBuf};

/// A file operation that failed: what was done, to which file; the operating system's
/// error is its source.
#[derive(Debug, thiserror::Error)]
#[error("{action} {}", path.display())]
pub struct FileError {
    /// What was done, as the message says it ("cannot write", "creating", …).
    pub action: &'static str,
    /// The file.
    pub path: PathBuf,
    /// The operating system's error.
    #[source]
    pub source: io::Error,
}

/// Names the file and the action of an I/O result's error (a typed `with_context`).
pub trait AtFile<T> {
    /// The result, its error a [`FileError`] of `action` on `path`.
    fn at(self, action: &'static str, path: &Path) -> Result<T, FileError>;
}

impl<T> AtFile<T> for io::Result<T> {
    fn at(self, action: &'static str, path: &Path) -> Result<T, FileError> {
        self.map_err(|source| FileError {
            action,
            path: path.to_path_buf(),
            source,
        })
    }
}

impl<T> AtFile<T> for csv::Result<T> {
    fn at(self, action: &'static str, path: &Path) -> Result<T, FileError> {
        self.map_err(|e| FileError {
            action,
            path: path.to_path_buf(),
            source: e.into(),
        })
    }
}

impl<T> AtFile<T> for mcap::McapResult<T> {
    fn at(self, action: &'static str, path: &Path) -> Result<T, FileError> {
        self.map_err(|e| FileError {
            action,
            path: path.to_path_buf(),
            // Its message and sources unchanged: an I/O error of another kind shows them.
            source: io::Error::other(e),
        })
    }
}

/// `error` and each of its sources, joined by ": " (as anyhow's `{:#}` prints them).
pub fn chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(s) = source {
        text = format!("{text}: {s}");
        source = s.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_error_names_the_action_the_file_and_the_reason() {
        let e = std::fs::read("/nonexistent/file")
            .at("cannot read", Path::new("/nonexistent/file"))
            .unwrap_err();
        assert_eq!(e.to_string(), "cannot read /nonexistent/file");
        let text = chain(&e);
        assert!(
            text.starts_with("cannot read /nonexistent/file: No such file"),
            "{text}"
        );
        assert_eq!(text, format!("{:#}", anyhow::Error::new(e)));
    }

    #[test]
    fn an_mcap_error_keeps_its_message_and_its_sources() {
        let e: mcap::McapResult<()> = Err(mcap::McapError::Io(io::Error::other("disk full")));
        let e = e
            .at("cannot write", Path::new("run.mcap.part"))
            .unwrap_err();
        assert_eq!(
            chain(&e),
            "cannot write run.mcap.part: I/O error from writing, or reading a compression stream: disk full"
        );
    }
}
