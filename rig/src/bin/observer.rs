//! The observer process of a rig run, as its own executable (the same as `rig observer`).

use clap::Parser;

#[path = "../exit.rs"]
#[allow(dead_code)] // a node fails in one way only
mod exit;
#[path = "../node.rs"]
mod node;

/// The observer process of a rig run: joins the run its settings name over iceoryx2 and
/// runs until the plant announces the end of the run.
#[derive(Parser)]
#[command(name = "observer", version)]
struct Cli {
    #[command(flatten)]
    node: node::NodeFile,
}

fn main() -> std::process::ExitCode {
    exit::report(Cli::parse().node.run(runtime::process::observer::run))
}
