//! `rig bench-loop`: the three-process loop against one process and against the
//! transport's limits, and against external drivers in lockstep; and the ping-pong's
//! processes (`rig pong`).

use crate::exit::{Failed, Fails, Outcome};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;
use runtime::process::{CpuLayout, Scheduling, Wait, WaitKind};

#[derive(Flags)]
pub struct Args {
    /// Trials of the default experiment per run.
    #[arg(long, default_value_t = 400, value_parser = clap::value_parser!(u32).range(2..))]
    trials: u32,
    /// Runs of each kind (one process, three processes, three without the recorder),
    /// alternating; medians are reported.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    repetitions: u64,
    /// Round trips timed per ping-pong (after 1000 of warm-up).
    #[arg(long, default_value_t = 20_000, value_parser = clap::value_parser!(u64).range(1..))]
    samples: u64,
    /// How the processes wait (as `rig run` in lockstep).
    #[command(flatten)]
    wait: Wait,
    /// Where the three processes and the recorder run (`shared`, `plant-alone`,
    /// `recorder-alone`; as `rig run --cpus`) [default: as `rig run` places a lockstep
    /// run that waits so].
    #[arg(long, value_enum, value_name = "LAYOUT")]
    cpus: Option<CpuLayout>,
    /// Also time `rig run --plant external` against drivers in lockstep: `rig sim-driver
    /// --clock lockstep` and, with `--python`, the Python example driver and the
    /// Gymnasium adapter (Pendulum-v1, beside its own env.step loop in Python).
    #[arg(long)]
    external: bool,
    /// With `--external`: the Python with iceoryx2 (and gymnasium) for the Python drivers
    /// [default: the Rust driver only].
    #[arg(long, value_name = "PYTHON", requires = "external")]
    python: Option<PathBuf>,
    /// With `--external`: the repository's root, whose examples/ and bench/scripts/ are
    /// run.
    #[arg(long, value_name = "DIR", default_value = ".", requires = "external")]
    root: PathBuf,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/bench-loop")]
    out: PathBuf,
    /// Print nothing but the summary.
    #[arg(long)]
    quiet: bool,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    let waiting = args.wait.waiting_in(true);
    let opts = bench::loop_bench::LoopOptions {
        out: args.out.clone(),
        trials: args.trials,
        repetitions: args.repetitions as usize,
        samples: args.samples as usize,
        waiting,
        layout: Scheduling {
            cpus: args.cpus,
            ..Scheduling::default()
        }
        .lockstep_layout(waiting),
        external: args.external.then(|| bench::loop_bench::ExternalOptions {
            python: args.python.clone(),
            root: args.root.clone(),
        }),
    };
    let progress = |what: &str| {
        if !args.quiet {
            eprintln!("rig bench-loop: {what} ...");
        }
    };
    let r = bench::loop_bench::bench_loop(&opts, &progress).failure()?;
    print!("{}", r.summary());
    println!("wrote {}/{{loop.csv, summary.txt}}", args.out.display());
    if !r.identical {
        return Err(Failed::failure(
            "rig run and rig learn --runs 1 wrote different returns",
        ));
    }
    Ok(ExitCode::SUCCESS)
}

/// One side of the ping-pong (`rig pong`, hidden).
#[derive(Flags)]
pub struct PongArgs {
    /// Run id of the ping-pong.
    #[arg(long)]
    run_id: String,
    /// Pin the echo to the last CPU (the plant's under `--pin-cpus`), the pinger to the
    /// others.
    #[arg(long)]
    pin_cpus: bool,
    /// How to wait for the next message.
    #[command(flatten)]
    wait: Wait,
    /// Be the pinger: time this many round trips.
    #[arg(long, requires = "rtt_out")]
    ping: Option<usize>,
    /// With `--ping`: write the round trips here \[ns, one per line\].
    #[arg(long, value_name = "FILE")]
    rtt_out: Option<PathBuf>,
}

/// Runs one side of the ping-pong.
pub fn pong(args: &PongArgs) -> Outcome {
    let ping = args.ping.zip(args.rtt_out.as_deref());
    bench::loop_bench::pong(
        &args.run_id,
        args.pin_cpus,
        args.wait.waiting(WaitKind::Block),
        ping,
    )
    .failure()?;
    Ok(ExitCode::SUCCESS)
}
