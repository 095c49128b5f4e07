//! `rig bridge` in a rig built without the Zenoh bridge (the `bridge` feature): says how
//! to build one that has it.

use crate::exit::{Failed, Outcome};

use clap::Args as Flags;

#[derive(Flags)]
pub struct Args {
    /// The bridge's arguments (docs/across-hosts.md); this build has no bridge to take them.
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    args: Vec<String>,
}

/// Refuses with the command that builds the bridge; exit code 2, as for a bad argument.
pub fn main(_: &Args) -> Outcome {
    Err(Failed::usage(
        "rig bridge: this rig was built without the Zenoh bridge; build it with the \
         `bridge` feature: cargo run --release -p rig --features bridge -- bridge … \
         (docs/across-hosts.md)",
    ))
}
