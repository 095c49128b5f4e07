//! `rig run`: one experiment as three processes — plant, observer, agent — over
//! iceoryx2, against the simulated plant or an external driver.

use crate::exit::{Fails, Outcome};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, anyhow};
use clap::Args as Flags;
use runtime::clock::{Clock, Timing};
use runtime::config::ExperimentConfig;
use runtime::run::{NodeCommand, RunOptions, RunSummary, run_with};

use crate::external::DriverArgs;
use crate::live::LiveView;
use crate::selection::{Selection, resolve_selection, resume_selection};

#[derive(Flags)]
pub struct Args {
    #[command(flatten)]
    selection: Selection,
    /// Output directory. It is this command's while it runs (DIR/.lock): another `rig
    /// run` or `rig learn` into it is refused, naming this process.
    #[arg(long, value_name = "DIR", default_value = "out/run")]
    out: PathBuf,
    /// Run id shared by the three processes [default: unique per invocation].
    #[arg(long)]
    run_id: Option<String>,
    /// `lockstep`: simulated time advances only when the action for a sample has
    /// arrived (deterministic). `realtime`: the plant samples at absolute deadlines of
    /// Ts / speed; a late action is applied from the moment it arrives, the previous one
    /// held until then, and the miss is counted.
    #[arg(long, value_enum, default_value_t = Timing::Lockstep)]
    timing: Timing,
    /// Realtime only: how many times faster than real time to run (e.g. 10: a 30 ms
    /// sample period takes 3 ms).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    #[command(flatten)]
    scheduling: runtime::process::Scheduling,
    #[command(flatten)]
    spin: runtime::process::Spin,
    #[command(flatten)]
    wait: runtime::process::Wait,
    #[command(flatten)]
    wakeup: runtime::process::Wakeup,
    /// `simulated` (also `sim`): the plant process simulates the system. `external`: a driver someone else
    /// started (docs/driver.md; e.g. examples/python_driver/driver.py) is the system and
    /// the clock; `rig run` waits for it, and the plant process resets it before each
    /// trial and passes its samples and the agent's actions on (`--timing` and `--speed`
    /// do not apply).
    #[arg(long, value_enum, default_value_t = PlantSource::Simulated)]
    plant: PlantSource,
    #[command(flatten)]
    driver: DriverArgs,
    /// Realtime and `--plant external`: what a gap in the loop's timing does — samples
    /// missing, or one reaching the plant more than a period after its instant
    /// (docs/run.md). `cut`: the trial's attempt ends there, nothing learned across it,
    /// and the trial is run again (listed in gaps.csv). `learn`: the trial goes on and
    /// learns across the gap, counted only as deadline misses — for a simulation run
    /// faster than the machine can keep the period.
    #[arg(long, value_enum, default_value_t = GapPolicy::Cut)]
    gaps: GapPolicy,
    /// Continue the run in DIR after a crash, a killed process or Ctrl-C: from its last
    /// trial that is complete in returns.csv, in the agent's checkpoints
    /// (DIR/checkpoints) and in run.mcap. The configuration is DIR/config.toml; of the
    /// experiment flags only `--trials` may be given (to learn on past the original
    /// end). `--timing`, `--speed` and the driver flags apply to the part that is run
    /// now; the plant must be the run's own (a run made against an external driver is
    /// resumed with `--plant external`, a simulated one without). Completed trials stay in
    /// returns.csv and run.mcap.
    #[arg(long, value_name = "DIR", conflicts_with = "out")]
    resume: Option<PathBuf>,
    /// Serve the run live over the Foxglove WebSocket protocol at ADDR (host:port;
    /// without ADDR 127.0.0.1:8765, this host only): every channel of run.mcap, with the
    /// trials' returns (/returns), the loop's latency (/latency) and the system drawn
    /// from its state (/scene). Open docs/live-layout.json in Foxglove or Lichtblick,
    /// live or on the recording.
    /// The loop never waits for a viewer: one too slow misses messages. In a rig built
    /// with the `live` feature (`cargo run --release -p rig --features live`).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = LIVE_ADDR)]
    live: Option<SocketAddr>,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
}

/// Where `--live` serves without an address: this host only.
const LIVE_ADDR: &str = "127.0.0.1:8765";

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    let (cfg, opts) = options(args).usage()?;
    let live = args
        .live
        .map(|addr| LiveView::start(addr, &cfg.task()))
        .transpose()
        .usage()?;
    let (live, tap) = live.unzip();
    if let Some(l) = &live
        && !args.quiet
    {
        eprintln!(
            "live view: ws://{} (open docs/live-layout.json in Foxglove or Lichtblick)",
            l.addr()
        );
    }
    let wakeup = args.wakeup.hold().failure()?;
    let done = run_with(&cfg, &opts, tap);
    drop(wakeup);
    if let Some(l) = live {
        let served = l.close();
        if !args.quiet {
            eprintln!("{served}");
        }
    }
    let s = done.failure()?;
    if !args.quiet {
        print_summary(&cfg, &opts, &s);
    }
    Ok(ExitCode::SUCCESS)
}

/// What the plant process is (`--plant`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PlantSource {
    /// The plant process simulates the system.
    #[value(alias = "sim")]
    Simulated,
    /// A driver started elsewhere is the system and the clock.
    External,
}

/// What a gap in the loop's timing does (`--gaps`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GapPolicy {
    /// The trial's attempt ends at the gap and is run again.
    Cut,
    /// The trial learns across the gap.
    Learn,
}

/// How `rig run` (and `rig latency`) starts the run's processes: this executable's
/// subcommands, `rig plant|observer|agent --node FILE`.
pub fn node_command() -> Result<NodeCommand> {
    let program = std::env::current_exe().context("cannot find the rig executable")?;
    let args = |role: &str| vec![role.into(), "--node".into()];
    Ok(NodeCommand {
        program,
        plant: args("plant"),
        observer: args("observer"),
        agent: args("agent"),
    })
}

/// The experiment and how to run it, from the flags (and, resuming, the run's
/// directory); an error is a usage error.
fn options(args: &Args) -> Result<(ExperimentConfig, RunOptions)> {
    let cfg = match &args.resume {
        Some(dir) => resume_selection(dir, &args.selection),
        None => resolve_selection(&args.selection),
    }?
    .one_run();
    let driver = match args.plant {
        PlantSource::External => Some(args.driver.flags()),
        PlantSource::Simulated if args.driver.driver.is_some() => {
            return Err(anyhow!("`--driver` needs `--plant external`"));
        }
        PlantSource::Simulated => None,
    };
    let clock = Clock::of_flags(
        (args.timing, args.speed),
        (cfg.task().ts, &cfg.task_name()),
        driver,
    )?;
    let (lockstep, external) = (clock.is_lockstep(), clock.is_external());
    let waiting = args.wait.waiting_in(lockstep);
    let checked = clock.check(&cfg, waiting)?;
    let mut scheduling = args.scheduling;
    if let Some(layout) = scheduling.layout() {
        layout.check()?;
    }
    if lockstep {
        scheduling = scheduling.in_lockstep(waiting);
    }
    let opts = RunOptions {
        out: args.resume.clone().unwrap_or_else(|| args.out.clone()),
        resume: args.resume.is_some(),
        run_id: args.run_id.clone(),
        progress: !args.quiet,
        clock,
        checked,
        nodes: node_command()?,
        cycles_out: None,
        scheduling,
        spin: args.spin,
        waiting,
        // Known once the driver's info says which clock it keeps.
        lockstep_waiting: external.then(|| args.wait.waiting_in(true)),
        learn_across_gaps: args.gaps == GapPolicy::Learn,
        scene: Some(crate::picture::scene),
    };
    Ok((cfg, opts))
}

/// What the run did, in a few lines.
fn print_summary(cfg: &ExperimentConfig, opts: &RunOptions, s: &RunSummary) {
    let steps = s.messages as f64 / 3.0;
    let trials = match s.resumed_after {
        Some(after) => format!(
            "{} trials now (resumed after trial {after}), {} in all,",
            s.records.len() - after as usize,
            s.records.len()
        ),
        None => format!("{} trials", s.records.len()),
    };
    println!(
        "{} {}/{} over three processes: {trials} in {:.1} s wall ({:.1} µs per sample)",
        cfg.task_name(),
        cfg.agent().algo,
        cfg.agent().approx,
        s.wall.as_secs_f64(),
        s.wall.as_secs_f64() * 1e6 / steps
    );
    if let (Some(i), Some(d)) = (&s.driver, opts.clock.driver()) {
        println!(
            "  driver {:?} (task {}, {} clock): period {:.3} ms × time scale {}; deadline misses: {} of {} samples",
            d.id,
            i.task_name(),
            if i.lockstep() { "lockstep" } else { "realtime" },
            i.period_ns as f64 * 1e-6,
            i.time_scale,
            s.deadline_misses,
            s.messages / 3
        );
        if i.provides_reward() {
            println!(
                "  rewards and trial endings: the driver's own (returns.csv sums them; run.mcap metadata reward_from = driver)"
            );
        }
    } else if opts.clock.is_realtime() {
        println!(
            "  deadline misses: {} of {} samples",
            s.deadline_misses,
            s.messages / 3
        );
    }
    if !opts.clock.is_lockstep() {
        println!("  trials cut by gaps and redone: {} (gaps.csv)", s.gaps);
    }
    if let Some(g) = s.records.iter().rev().find_map(|r| r.greedy) {
        println!("  last greedy return: {g:.1}");
    }
    println!(
        "  wrote {}/{{returns.csv, run.mcap, config.toml, plant.log, observer.log, agent.log}}",
        opts.out.display()
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, Parser};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    #[test]
    fn the_nodes_are_this_executables_subcommands() {
        let nodes = node_command().unwrap();
        assert_eq!(nodes.program, std::env::current_exe().unwrap());
        for (args, role) in [
            (&nodes.plant, "plant"),
            (&nodes.observer, "observer"),
            (&nodes.agent, "agent"),
        ] {
            assert_eq!(args, &[role, "--node"].map(std::ffi::OsString::from));
        }
    }

    fn parse(flags: &[&str]) -> Result<Args, clap::Error> {
        Cli::try_parse_from(std::iter::once("run").chain(flags.iter().copied())).map(|c| c.args)
    }

    #[test]
    fn plant_and_gaps_are_named_choices() {
        let a = parse(&[]).unwrap();
        assert_eq!((a.plant, a.gaps), (PlantSource::Simulated, GapPolicy::Cut));
        let a = parse(&["--plant", "sim", "--gaps", "learn"]).unwrap();
        assert_eq!(
            (a.plant, a.gaps),
            (PlantSource::Simulated, GapPolicy::Learn)
        );
        let a = parse(&["--plant", "external"]).unwrap();
        assert_eq!(a.plant, PlantSource::External);
        assert!(parse(&["--gaps", "skip"]).is_err());
        assert!(parse(&["--plant", "hardware"]).is_err());
        let help = Cli::command().render_help().to_string();
        assert!(
            help.contains("[possible values: simulated, external]"),
            "{help}"
        );
        assert!(help.contains("[possible values: cut, learn]"), "{help}");
    }
}
