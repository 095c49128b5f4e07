//! `rig config`: the resolved configuration as TOML.

use std::process::ExitCode;

use crate::exit::{Fails, Outcome};
use crate::selection::{Selection, resolve_selection};

/// Runs the command.
pub fn main(sel: &Selection) -> Outcome {
    let cfg = resolve_selection(sel).usage()?;
    print!("{}", cfg.to_toml());
    Ok(ExitCode::SUCCESS)
}
