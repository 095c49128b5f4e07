//! `rig tune`: a hyperparameter study over a task's learner configuration, with Optuna.
//!
//! The study is the field's own tool, in Python (`tune/rig_tune`, docs/tune.md); this
//! command only starts it, with this `rig` binary as the one it runs, so that there is
//! one entry point. Every argument goes to the study's own command line (`rig tune
//! --help` is its help).

use crate::exit::{Failed, Outcome};
use std::ffi::OsString;
use std::os::unix::process::CommandExt;
use std::path::PathBuf;
use std::process::Command;

/// The study's arguments, passed on as they are.
#[derive(clap::Args)]
#[command(disable_help_flag = true)]
pub struct Args {
    /// Arguments of the study (`rig tune --help` lists them).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    args: Vec<OsString>,
}

/// Where the study's Python package lives: `RIG_TUNE_DIR`, else the source tree's `tune/`.
fn package_dir() -> PathBuf {
    std::env::var_os("RIG_TUNE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../tune")))
}

/// Replaces this process with the study (so that Ctrl-C and the exit status are its own).
pub fn main(args: &Args) -> Outcome {
    let dir = package_dir();
    if !dir.join("rig_tune").is_dir() {
        return Err(Failed::usage(format!(
            "rig tune needs the study's Python package, {}/rig_tune (the source tree's tune/ folder; set RIG_TUNE_DIR to where it is)",
            dir.display()
        )));
    }
    let python = std::env::var_os("RIG_PYTHON").unwrap_or_else(|| "python3".into());
    let mut path = OsString::from(&dir);
    if let Some(old) = std::env::var_os("PYTHONPATH") {
        path.push(":");
        path.push(old);
    }
    let mut cmd = Command::new(&python);
    cmd.arg("-m").arg("rig_tune").args(&args.args);
    cmd.env("PYTHONPATH", path);
    if let Ok(rig) = std::env::current_exe() {
        cmd.env("RIG_BIN", rig);
    }
    let e = cmd.exec();
    Err(Failed::usage(format!(
        "cannot start {} for rig tune: {e} (set RIG_PYTHON to a Python with tune/requirements.txt installed)",
        PathBuf::from(python).display()
    )))
}
