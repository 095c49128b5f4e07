//! The plant process: the system, clock and episode master.
//!
//! It runs the trials of the run's schedule ([`::plant::schedule`]) and announces the end
//! of the run; what runs a trial depends on the timing:
//!
//! * `lockstep` — the simulated system ([`::plant::episode::Episode`]); simulated time
//!   advances when the action has arrived (`--timing lockstep`, the default);
//! * `realtime` — the simulated system sampled at absolute deadlines
//!   (`--timing realtime`);
//! * [`external`] — an external driver's system, which is the clock (`--driver ID`).
//!
//! All three publish on the same `link`: measurements (and ground truth) out, actions
//! in.

mod arrivals;
pub mod external;
mod link;
mod lockstep;
mod realtime;

use std::path::Path;
use std::sync::Arc;

use ::observer::config::ObserverMode;
use ::plant::Plant;
use ::plant::episode::Episode;
use ::plant::safety::SafetyCounts;
use ::plant::schedule::{Schedule, Trial};
use anyhow::{Result, bail};

use super::{PlantArgs, STARTUP, Scheduling, wire_err};
use crate::config::ExperimentConfig;
use link::Link;

/// Columns of the plant's per-sample timing file (`--cycles-out`, realtime): the sample's
/// sequence number, its nominal sampling instant, when the plant actually woke for it,
/// and when the plant found the action answering it (0: not within the period — a
/// deadline miss). Monotonic ns.
pub const CYCLES_HEADER: &str = "seq,t_sample_ns,t_woke_ns,t_action_ns";

/// Runs the plant side of a run: every trial of the configuration, greedy evaluation
/// trials where due (one from each of the task's start states), then announces the end
/// of the run. The system is simulated here, or, with `--driver ID`, is an external
/// driver's ([`external`]). A trial that leaves the task's operating range ends early
/// with [`wire::flags::END`] | [`wire::flags::TERMINAL`]; the simulated time counts only
/// samples run.
///
/// What is published is the configured sensor's output (`[observer] sensor`,
/// [`crate::experiment::sensor`], its noise from the run seed exactly as in process); the
/// true state stays here and, when the sensor does not measure all of it, goes out on
/// the evaluation topic [`wire::topic::TRUTH`], for the supervisor alone.
pub fn run(args: &PlantArgs) -> Result<()> {
    schedule_clock(&args.node.scheduling)?;
    let cfg = args.node.config()?;
    if args.driver.is_none() {
        cfg.check_simulated()?;
    }
    let task = Arc::new(cfg.task());
    let run_seed = ::agent::seed::run_seed(cfg.run.seed, args.node.run_index);
    let sensor = crate::experiment::sensor(&task, &cfg.observer, run_seed);
    let link = Link::join(
        args.node.join("plant")?,
        task.clone(),
        sensor,
        args.first_seq,
    )?;
    let linger = super::Linger::open(&link.bus, args.node.receivers)?;
    let mut runner = runner(link, args, &cfg, run_seed)?;
    // A resumed run continues after trial `--after-trial`, whose simulated time tells how
    // many samples the trials before it skipped.
    if !(args.sim_time.is_finite() && args.sim_time >= 0.0) {
        bail!("`--sim-time` {} is not a time", args.sim_time);
    }
    let mut schedule = Schedule::new(task.clone(), cfg.run.trials, cfg.run.eval_every, run_seed);
    schedule.resume(args.after_trial, args.sim_time);
    while let Some(trial) = schedule.next_trial() {
        let skipped = runner.trial(&trial)?;
        for greedy in schedule.end_trial(skipped).into_iter().flatten() {
            runner.trial(&greedy)?;
        }
    }
    eprintln!("safety: {}", runner.safety());
    let link = runner.link();
    // The end of the run, stamped with the run's final simulated time.
    link.shutdown(task.sim_time(cfg.run.trials.into(), schedule.skipped_samples()))?;
    write_timing(link, args)?;
    linger.wait(&link.bus)
}

/// Puts the plant, the clock, one level above the observer and the agent
/// (`--rt-priority`), so that its sampling instant is not held up by their compute on
/// the same core, and where the layout puts it (`--cpus`, `--pin-cpus`).
fn schedule_clock(s: &Scheduling) -> Result<()> {
    super::set_rt_priority(s.rt_priority.map(|p| p.saturating_add(1).min(99)))?;
    s.place(super::Part::Plant)
}

/// Runs trials: the simulation in lockstep or in real time, or an external driver
/// ([`external::Bridge`]).
trait Trials {
    /// Runs `trial`. Returns how many of its samples were not run because it left the
    /// operating range.
    fn trial(&mut self, trial: &Trial) -> Result<usize>;
    /// The run topics.
    fn link(&mut self) -> &mut Link;
    /// How often the plant side's safety measures acted.
    fn safety(&mut self) -> SafetyCounts;
}

/// What runs the trials that `args` and `cfg` ask for, once the peers listen on `link`.
fn runner(
    link: Link,
    args: &PlantArgs,
    cfg: &ExperimentConfig,
    run_seed: u64,
) -> Result<Box<dyn Trials>> {
    if let Some(id) = &args.driver {
        if cfg.observer.mode == ObserverMode::Predictive {
            bail!(
                "predictive timing (`observer.mode = \"predictive\"`) needs the simulated plant: an external driver applies each action as it arrives (use `--observer-mode direct`)"
            );
        }
        return Ok(Box::new(external::Bridge::connect(link, id, args)?));
    }
    link.out
        .wait_for_receivers(args.node.receivers, STARTUP, &link.bus)
        .map_err(wire_err)?;
    let realtime = args.timing == "realtime";
    if realtime
        && !args
            .node
            .wait
            .waiting(super::WaitKind::Block)
            .needs_wake_up()
    {
        bail!(
            "`--wait` without `--wait-us` applies in lockstep only: in real time the plant sleeps until its next sampling instant and must be woken by the action"
        );
    }
    if realtime && (cfg.run.delay_ms != 0.0 || !cfg.run.delay_from.is_empty()) {
        bail!(
            "`run.delay_ms`/`run.delay_from` apply in lockstep only: in real time the delays are real"
        );
    }
    let task = link.task.clone();
    let actuator = crate::experiment::actuator(&task, cfg, run_seed);
    let episode = Episode::new(Plant::new(task.clone()), actuator);
    Ok(if realtime {
        Box::new(realtime::Realtime::new(
            link,
            episode,
            &task,
            args.speed,
            args.spin.spin_us,
            args.cycles_out.is_some(),
        ))
    } else {
        Box::new(lockstep::Lockstep::new(link, episode))
    })
}

/// Writes the run's timing files: every sample's publish-to-action time
/// (`--latency-out`) and, in real time, every sample's timing (`--cycles-out`).
fn write_timing(link: &Link, args: &PlantArgs) -> Result<()> {
    if let Some(path) = &args.latency_out {
        let text: String = link.latencies.iter().map(|ns| format!("{ns}\n")).collect();
        write(path, &text)?;
    }
    if let Some(path) = &args.cycles_out {
        let mut text = String::from(CYCLES_HEADER);
        text.push('\n');
        for c in &link.cycles {
            text.push_str(&format!("{},{},{},{}\n", c[0], c[1], c[2], c[3]));
        }
        write(path, &text)?;
    }
    Ok(())
}

/// Writes `text` to `path`, an error naming the file.
fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}
