//! The files the rig's commands write, and how: atomically, with progress shown.
//!
//! - [`runs`]: `runs.csv` (one row per learning trial), the curves and final greedy
//!   returns computed from its rows;
//! - [`responses`]: `responses.csv` (each run's final greedy time response) and
//!   `observer.csv` (the acted-on error per state component).

use std::path::Path;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

pub mod responses;
pub mod runs;

use crate::error::{AtFile, FileError};

/// Writes `text` to `path` atomically (temporary file, then rename).
pub fn write_atomic(path: &Path, text: &str) -> Result<(), FileError> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).at("cannot write", &tmp)?;
    std::fs::rename(&tmp, path).at("cannot rename over it", path)
}

/// A progress bar of `len` trials on stderr (hidden when `enabled` is false, or when
/// stderr is not a terminal).
pub fn progress_bar(len: u64, enabled: bool, label: &str) -> ProgressBar {
    let target = if enabled {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(len), target);
    let template = format!(
        "{{spinner}} {label} [{{bar:40}}] {{pos}}/{{len}} trials, {{per_sec}}, eta {{eta}}"
    );
    bar.set_style(
        ProgressStyle::with_template(&template)
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar
}
