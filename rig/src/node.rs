//! The command line of a node (`rig plant|observer|agent`, and the `plant`, `observer`
//! and `agent` executables): only where its settings are.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::exit::{Fails, Outcome};

use clap::Args;
use runtime::process::Settings;

/// Where a node finds its settings.
#[derive(Args)]
pub struct NodeFile {
    /// The node's settings (TOML; docs/run.md, "A node by hand"): the run id, the run's
    /// configuration file and what the node adds. `rig run` writes them to
    /// DIR/nodes/<process>.toml; a node started by hand is given a file written by hand.
    #[arg(long, value_name = "FILE")]
    node: PathBuf,
}

impl NodeFile {
    /// Reads the settings and runs `node` with them (an error: exit code 1).
    pub fn run<S: Settings>(&self, node: fn(&S) -> runtime::process::Result<()>) -> Outcome {
        S::read(&self.node)
            .map_err(Into::into)
            .and_then(|s| node(&s))
            .failure()?;
        Ok(ExitCode::SUCCESS)
    }
}
