//! The plant process of a rig run, as its own executable (the same as `rig plant`).

use clap::Parser;
use runtime::process::PlantArgs;

/// The plant process of a rig run: joins run `--run-id` over iceoryx2 and runs until the
/// plant announces the end of the run.
#[derive(Parser)]
#[command(name = "plant", version)]
struct Cli {
    #[command(flatten)]
    args: PlantArgs,
}

fn main() -> std::process::ExitCode {
    runtime::process::exit_code(runtime::process::plant::run(&Cli::parse().args))
}
