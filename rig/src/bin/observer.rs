//! The observer process of a rig run, as its own executable (the same as `rig observer`).

use clap::Parser;
use runtime::process::ObserverArgs;

/// The observer process of a rig run: joins run `--run-id` over iceoryx2 and runs until the
/// plant announces the end of the run.
#[derive(Parser)]
#[command(name = "observer", version)]
struct Cli {
    #[command(flatten)]
    args: ObserverArgs,
}

fn main() -> std::process::ExitCode {
    runtime::process::exit_code(runtime::process::observer::run(&Cli::parse().args))
}
