//! `rig config`: the resolved configuration as TOML.

use std::process::ExitCode;

use crate::selection::{Selection, resolve_selection};

/// Runs the command.
pub fn main(sel: &Selection) -> ExitCode {
    match resolve_selection(sel) {
        Ok(cfg) => {
            print!("{}", cfg.to_toml());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
