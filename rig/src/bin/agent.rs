//! The agent process of a rig run, as its own executable (the same as `rig agent`).

use clap::Parser;
use runtime::process::AgentArgs;

/// The agent process of a rig run: joins run `--run-id` over iceoryx2 and runs until the
/// plant announces the end of the run.
#[derive(Parser)]
#[command(name = "agent", version)]
struct Cli {
    #[command(flatten)]
    args: AgentArgs,
}

fn main() -> std::process::ExitCode {
    runtime::process::exit_code(runtime::process::agent::run(&Cli::parse().args))
}
