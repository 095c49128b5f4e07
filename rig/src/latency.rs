//! `rig latency`: the latency budget of the three-process loop in real time.

use crate::exit::{Fails, Outcome};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as Flags;
use observer::config::{ObserverKind, ObserverMode};
use runtime::clock::Clock;

use crate::external::DriverArgs;

#[derive(Flags)]
pub struct Args {
    /// Samples (cycles) to time, at least (whole 3 s trials are run).
    #[arg(long, default_value_t = 10_000)]
    cycles: usize,
    /// Sampling period [ms] of the simulated plant (the pendulum's Ts is 30 ms; a
    /// shorter period runs the simulation faster than real time) [default: 30]. With
    /// `--driver`, the driver's own period applies.
    #[arg(long, value_name = "MS", conflicts_with = "driver")]
    period_ms: Option<f64>,
    // `--driver ID`: against an external driver (docs/driver.md), on this host or across
    // hosts behind `rig bridge rig` (docs/across-hosts.md), instead of the simulated
    // plant: the stages run from the driver's sample to the command answering it, with
    // the link's share where there is one (docs/latency.md).
    #[command(flatten)]
    driver: DriverArgs,
    /// The driver's task file (docs/tasks.md) [default: the pendulum].
    #[arg(long, value_name = "FILE", requires = "driver")]
    task: Option<PathBuf>,
    /// State observer on the angle encoder: finite-difference or predictive.
    #[arg(long, default_value = "predictive", value_enum)]
    observer: ObserverKind,
    /// Timing: predictive (the plant applies the action answering sample k at the next
    /// sample instant t_{k+1}; a deadline miss when it has not arrived by then; needs
    /// `--observer predictive` and the simulated plant) or direct (applied when it
    /// arrives, within the interval) [default: predictive; direct with `--driver`].
    #[arg(long, value_enum)]
    observer_mode: Option<ObserverMode>,
    /// Raw ping-pong round trips for the baseline.
    #[arg(long, default_value_t = 20_000)]
    raw_samples: usize,
    #[command(flatten)]
    scheduling: runtime::process::Scheduling,
    #[command(flatten)]
    spin: runtime::process::Spin,
    /// How the processes wait for their next message (`--wait-us` is needed with
    /// `spin` and `yield` in real time) [default: block].
    #[command(flatten)]
    wait: runtime::process::Wait,
    #[command(flatten)]
    wakeup: runtime::process::Wakeup,
    /// Measure at `--period-ms`, then at periods shortened 1.5 × each (DIR/period-MS/),
    /// until one misses a deadline; writes DIR/sweep.csv and names the fastest period
    /// sustained for `--cycles` cycles without a miss (simulated plant only).
    #[arg(long, conflicts_with = "driver")]
    sweep: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/latency")]
    out: PathBuf,
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    // `--driver` has no default here: without it, the simulated plant.
    let clock = match args.driver.driver.as_ref() {
        Some(_) => args
            .driver
            .resolve("")
            .map(Clock::External)
            .map_err(anyhow::Error::from),
        None => bench::latency::period(args.period_ms.unwrap_or(30.0))
            .map(|period| Clock::Realtime { period })
            .map_err(anyhow::Error::from),
    };
    let clock = clock.failure()?;
    let mode = args.observer_mode.unwrap_or(match clock {
        Clock::External(_) => ObserverMode::Direct,
        _ => ObserverMode::Predictive,
    });
    let nodes = crate::run::node_command().failure()?;
    let opts = bench::latency::LatencyOptions {
        cycles: args.cycles,
        clock,
        nodes,
        task: args.task.clone(),
        out: args.out.clone(),
        observer: args.observer,
        mode,
        raw_samples: args.raw_samples,
        scheduling: args.scheduling,
        spin: args.spin,
        waiting: args.wait.waiting(runtime::process::WaitKind::Block),
        wakeup: args.wakeup,
        verbose: true,
    };
    let done = if args.sweep {
        bench::latency::sweep(&opts, 1.5).map(|points| {
            match points.iter().rev().find(|p| p.report.misses == 0) {
                Some(p) => println!(
                    "fastest period without a deadline miss in {} cycles: {} ms",
                    p.report.cycles, p.period_ms
                ),
                None => println!("every period measured missed a deadline"),
            }
            println!("wrote {0}/sweep.csv and {0}/period-*/", args.out.display());
        })
    } else {
        bench::latency::latency(&opts)
            .map(|_| println!("wrote {}", bench::latency::describe(&args.out)))
    };
    done.failure()?;
    Ok(ExitCode::SUCCESS)
}
