//! `rig`: run the thesis's learning experiments. One module per command; the work is
//! the `runtime` and `bench` crates'.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod bench_loop;
#[cfg(feature = "bridge")]
mod bridge;
#[cfg(not(feature = "bridge"))]
#[path = "bridge_absent.rs"]
mod bridge;
mod check_driver;
mod config;
mod delay_study;
mod exit;
mod external;
mod latency;
mod learn;
#[cfg(feature = "live")]
mod live;
#[cfg(not(feature = "live"))]
#[path = "live_absent.rs"]
mod live;
mod node;
mod optimal;
mod picture;
mod replay;
mod reproduce;
mod run;
mod selection;
mod sim_driver;
mod tune;

/// Learning controllers of Grondman's thesis "Online Model Learning Algorithms for
/// Actor-Critic Control": run experiments, write learning curves.
#[derive(Parser)]
#[command(name = "rig", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run independent learning experiments in one process, in parallel on all cores,
    /// and write runs.csv, curve.csv, greedy_curve.csv, curve.png/svg and config.toml.
    Learn(learn::Args),
    /// Run a recorded run's observer and agent again, in one process, over its recorded
    /// measurements, and check that they reproduce its estimates and actions bit for bit;
    /// reports the first difference (topic, sample, field, both values) and exits 1 then.
    /// `--observer KIND` compares another observer on the same data.
    Replay(replay::Args),
    /// Run one experiment as three processes — plant, observer, agent — exchanging
    /// measurements, estimates and actions over iceoryx2 shared memory in lockstep;
    /// writes returns.csv, config.toml and one log per process.
    Run(run::Args),
    /// Print the resolved configuration (preset ← --config file ← flags) as TOML, to
    /// start a configuration file from.
    Config(selection::Selection),
    /// Check a running external driver against the driver contract (docs/driver.md):
    /// payload types, advertised limits, reset, sample rate and jitter, step response,
    /// the stale-action watchdog, clamping and rejection of bad actions. Prints one
    /// PASS/FAIL line per check; exits non-zero if any fails.
    CheckDriver(check_driver::Args),
    /// Be a driver (docs/driver.md) for a simulated system, in Rust: a sample every
    /// Ts / SPEED on the monotonic clock, actions applied from their arrival (clamped,
    /// non-finite ones rejected), the watchdog, resets by a PD brake.
    /// The stand-in for a motor driver process (`rig run --plant external`); its code,
    /// the driver kit (`driver`), is the template for one (`driver/examples/motor_driver.rs`).
    /// Runs until Ctrl-C or SIGTERM.
    SimDriver(sim_driver::Args),
    /// Carry one driver's services between two hosts over Zenoh: `rig bridge driver` on
    /// the driver's host, `rig bridge rig` on the rig's (docs/across-hosts.md). In a rig
    /// built with the `bridge` feature: `cargo run --release -p rig --features bridge`.
    Bridge(bridge::Args),
    /// Compute the optimal return of the pendulum swing-up from [π, 0] (one 3 s trial,
    /// Eq. 3.16) by dynamic programming on a grid, run the DP's policy on the plant, and
    /// write its trajectory to DIR/optimal.csv (t, angle, velocity, u, reward).
    Optimal(optimal::Args),
    /// Measure what the three-process loop costs: the default experiment in one process,
    /// as three processes with and without the recorder (wall and CPU time, their
    /// ratios), each lockstep step, and a ping-pong of two processes waiting as the loop
    /// does, blocking on events and busy-polling; writes loop.csv and summary.txt.
    BenchLoop(bench_loop::Args),
    /// Measure the latency budget of the three-process loop in real time (angle sensor,
    /// an observer, the default learner, recorded), against the simulated plant or an
    /// external driver (`--driver`, also across hosts): per hop and per stage percentiles
    /// from every message's timestamps, deadline misses, sample-instant jitter, next to
    /// a raw iceoryx2 ping-pong measured in the same run. Writes DIR/latency.csv (one row
    /// per cycle), DIR/summary.txt, a histogram (DIR/latency.png, .svg) and DIR/run/.
    Latency(latency::Args),
    /// How a sample-to-actuation delay hurts learning and how much predictive timing
    /// recovers: VGBP-LSTD and MLAC/LLR on the pendulum with angle-only sensing and the
    /// predictive estimator, direct vs predictive timing (`--observer-mode`), injected
    /// delays 0, 5, 10, 20 ms. Writes DIR/cells.csv (final greedy return per cell: mean,
    /// sd, 95 % CI), DIR/final_return.png/.svg, DIR/curves-*.png/.svg, DIR/summary.txt
    /// (the table and the acceptance checks at 10 ms, one-sided Welch t-test) and each
    /// cell's `rig learn` output.
    DelayStudy(delay_study::Args),
    /// One side of `rig bench-loop`'s ping-pong.
    #[command(hide = true)]
    Pong(bench_loop::PongArgs),
    /// Regenerate the thesis's learning-curve figures (3.12, 3.17, 3.22, 3.23, 4.4, 5.5,
    /// 5.9, 6.1, 6.5) from the presets with the thesis's numbers of runs, and write
    /// DIR/REPORT.md: per figure the plot (PNG, SVG), "thesis says / we measured" and the
    /// thesis's claims checked against the new data.
    Reproduce(reproduce::Args),
    /// Find the learner configuration that learns a task: a hyperparameter study with
    /// Optuna (TPE sampler, median pruner) over a search space in TOML, on N worker
    /// processes, stored in a file next to the output or shared by several machines
    /// through a PostgreSQL URL; writes the best configuration (for `--config`) and a
    /// report with the best re-run on fresh seeds beside the preset (docs/tune.md).
    /// `rig tune --help` lists its arguments.
    Tune(tune::Args),
    /// The plant process of a run (started by `rig run`, or by hand).
    Plant(node::NodeFile),
    /// The observer process of a run (started by `rig run`, or by hand).
    Observer(node::NodeFile),
    /// The agent process of a run (started by `rig run`, or by hand).
    Agent(node::NodeFile),
}

fn main() -> ExitCode {
    exit::report(match Cli::parse().command {
        Command::Learn(args) => learn::main(&args),
        Command::Run(args) => run::main(&args),
        Command::Replay(args) => replay::main(&args),
        Command::Config(selection) => config::main(&selection),
        Command::CheckDriver(args) => check_driver::main(&args),
        Command::SimDriver(args) => sim_driver::main(&args),
        Command::Bridge(args) => bridge::main(&args),
        Command::Optimal(args) => optimal::main(&args),
        Command::BenchLoop(args) => bench_loop::main(&args),
        Command::Pong(args) => bench_loop::pong(&args),
        Command::Latency(args) => latency::main(&args),
        Command::DelayStudy(args) => delay_study::main(&args),
        Command::Reproduce(args) => reproduce::main(&args),
        Command::Tune(args) => tune::main(&args),
        Command::Plant(node) => node.run(runtime::process::plant::run),
        Command::Observer(node) => node.run(runtime::process::observer::run),
        Command::Agent(node) => node.run(runtime::process::agent::run),
    })
}
