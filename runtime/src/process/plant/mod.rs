//! The plant process: the system, clock and episode master.
//!
//! It runs the trials of the run's schedule ([`::plant::schedule`]) and announces the end
//! of the run; what runs a trial depends on the timing:
//!
//! * [`Clock::Lockstep`] — the simulated system ([`::plant::episode::Episode`]);
//!   simulated time advances when the action has arrived (the default);
//! * [`Clock::Realtime`] — the simulated system sampled at absolute deadlines;
//! * [`Clock::External`] — an external driver's system, which is the clock
//!   ([`external`]).
//!
//! All three publish on the same `link`: measurements (and ground truth) out, actions
//! in.

mod arrivals;
pub mod external;
mod link;
mod lockstep;
mod realtime;

use std::path::Path;

use crate::error::AtFile;
use crate::process::{NodeError, Result};
use ::plant::Plant;
use ::plant::episode::Episode;
use ::plant::safety::SafetyCounts;
use ::plant::schedule::{Schedule, Trial};

use super::node::Continuation;
use super::{PlantSettings, STARTUP, Scheduling};
use crate::clock::Clock;
use crate::config::ExperimentConfig;
use link::Link;

/// Columns of the plant's per-sample timing file (`cycles_out`, realtime): the sample's
/// sequence number, its nominal sampling instant, when the plant actually woke for it,
/// and when the plant found the action answering it (0: not within the period — a
/// deadline miss). Monotonic ns.
pub const CYCLES_HEADER: &str = "seq,t_sample_ns,t_woke_ns,t_action_ns";

/// Runs the plant side of a run: every trial of the configuration, greedy evaluation
/// trials where due (one from each of the task's start states), then announces the end
/// of the run. The system is simulated here, or, with [`Clock::External`], is an
/// external driver's ([`external`]). The clock's rules are checked first
/// ([`Clock::check`]). A trial that leaves the task's operating range ends early
/// with [`wire::flags::END`] | [`wire::flags::TERMINAL`]; the simulated time counts only
/// samples run.
///
/// What is published is the configured sensor's output (`[observer] sensor`,
/// [`crate::build::sensor`], its noise from the run seed exactly as in process); the
/// true state stays here and, when the sensor does not measure all of it, goes out on
/// the evaluation topic [`wire::topic::TRUTH`], for the supervisor alone.
pub fn run(args: &PlantSettings) -> Result<()> {
    schedule_clock(&args.node.scheduling)?;
    let cfg = args.node.experiment()?;
    // Checked where `rig run` set the run up; a node started by hand checks it here.
    if args.checked.is_none() {
        args.clock.check(&cfg, args.node.waiting())?;
    }
    let task = cfg.task();
    let run_seed = ::agent::seed::run_seed(cfg.run().seed, args.node.run_index);
    let sensor = crate::build::sensor(&task, cfg.observer(), run_seed);
    let resume = args.resume.unwrap_or(Continuation {
        after_trial: 0,
        sim_time: 0.0,
        first_seq: 0,
    });
    let link = Link::join(
        (args.node.join("plant")?, wire::Monotonic::host()),
        task.clone(),
        sensor,
        resume.first_seq,
    )?;
    let linger = super::Linger::open(&link.bus, args.node.receivers)?;
    let mut runner = runner(link, args, &cfg, run_seed)?;
    let mut schedule = Schedule::new(
        task.clone(),
        cfg.run().trials,
        cfg.run().eval_every,
        run_seed,
    );
    // A resumed run continues after trial `after_trial`, whose simulated time tells how
    // many samples the trials before it skipped.
    schedule.resume(resume.after_trial, resume.sim_time);
    while let Some(trial) = schedule.next_trial() {
        let skipped = whole(runner.as_mut(), &trial)?;
        for greedy in schedule.end_trial(skipped).into_iter().flatten() {
            whole(runner.as_mut(), &greedy)?;
        }
    }
    eprintln!("safety: {}", runner.safety());
    let link = runner.link();
    // The end of the run, stamped with the run's final simulated time.
    link.shutdown(task.sim_time(cfg.run().trials.into(), schedule.skipped_samples()))?;
    write_timing(link, args)?;
    linger.wait(&link.bus)
}

/// Puts the plant, the clock, one level above the observer and the agent
/// (`rt_priority`), so that its sampling instant is not held up by their compute on
/// the same core, and where the layout puts it (`cpus`).
fn schedule_clock(s: &Scheduling) -> Result<()> {
    super::set_rt_priority(s.rt_priority.map(|p| p.saturating_add(1).min(99)))?;
    Ok(s.place(super::Part::Plant)?)
}

/// Attempts of one trial cut by gaps in a row after which the run stops.
pub const MAX_CUTS: u32 = 20;

/// Runs `trial` until an attempt is not cut short by a gap (at most [`MAX_CUTS`] are);
/// returns how many of its samples were not run because it left the operating range.
fn whole(runner: &mut dyn Trials, trial: &Trial) -> Result<usize> {
    for cuts in 1.. {
        match runner.trial(trial)? {
            Ended::Done(skipped) => return Ok(skipped),
            Ended::Cut if cuts == MAX_CUTS => {
                return Err(NodeError::CutTooOften {
                    trial: trial_name(trial),
                    cuts,
                });
            }
            Ended::Cut => {}
        }
    }
    unreachable!("the loop returns")
}

/// "learning trial 12", "greedy trial after trial 10".
fn trial_name(t: &Trial) -> String {
    match t.greedy {
        true => format!("the greedy trial after trial {}", t.number),
        false => format!("learning trial {}", t.number),
    }
}

/// How an attempt at a trial ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ended {
    /// It ran to its end; the samples it did not run (it left the operating range).
    Done(usize),
    /// A gap cut it short ([`wire::flags::GAP`]): the trial is run again.
    Cut,
}

/// The loop losing its timing before a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Gap {
    /// Samples missing before it.
    pub(super) missing: u64,
    /// From the previous sample's instant to its own \[ns\].
    pub(super) span_ns: u64,
    /// How long after its instant it reached (or was taken by) the plant process \[ns\].
    pub(super) late_ns: u64,
    /// The sample before the last was still unanswered a period after its deadline
    /// (realtime: the watchdog's limit passed without the agent's action).
    pub(super) unanswered: bool,
}

impl Gap {
    /// Says so in the plant's log: `trial`'s attempt cut at sample `step`.
    pub(super) fn cut(self, trial: &Trial, step: usize) -> Ended {
        let why = if self.unanswered {
            "no answer for a period after its deadline".to_string()
        } else {
            format!(
                "{} samples missing, {:.1} ms since the previous instant, the sample {:.1} ms late",
                self.missing,
                self.span_ns as f64 * 1e-6,
                self.late_ns as f64 * 1e-6
            )
        };
        eprintln!(
            "{} cut short at sample {step} by a gap ({why}): run again",
            trial_name(trial)
        );
        Ended::Cut
    }
}

/// Runs trials: the simulation in lockstep or in real time, or an external driver
/// ([`external::ExternalPlant`]).
trait Trials {
    /// Runs an attempt at `trial`.
    fn trial(&mut self, trial: &Trial) -> Result<Ended>;
    /// The run topics.
    fn link(&mut self) -> &mut Link;
    /// How often the plant side's safety measures acted.
    fn safety(&mut self) -> SafetyCounts;
}

/// What runs the trials that `args` and `cfg` ask for, once the peers listen on `link`.
fn runner(
    link: Link,
    args: &PlantSettings,
    cfg: &ExperimentConfig,
    run_seed: u64,
) -> Result<Box<dyn Trials>> {
    let period = match &args.clock {
        Clock::External(d) => {
            let external = external::ExternalPlant::connect(link, d, args)?;
            return Ok(Box::new(external.cutting_gaps(!args.learn_across_gaps)));
        }
        Clock::Lockstep => None,
        Clock::Realtime { period } => Some(*period),
    };
    link.out
        .wait_for_receivers(args.node.receivers, STARTUP, &link.bus)?;
    let task = link.task.clone();
    let actuator = crate::build::actuator(&task, cfg, run_seed);
    let episode = Episode::new(Plant::new(task.clone()), actuator);
    let time = link.time.clone();
    Ok(match period {
        Some(period) => Box::new(
            realtime::RealtimePlant::new(
                (link, episode),
                (task.ts, period),
                time,
                args.spin.spin_us,
                args.cycles_out.is_some(),
            )
            .cutting_gaps(!args.learn_across_gaps),
        ),
        None => Box::new(lockstep::LockstepPlant::new(link, episode)),
    })
}

/// Writes the run's timing files: every sample's publish-to-action time
/// (`latency_out`) and, in real time, every sample's timing (`cycles_out`).
fn write_timing(link: &Link, args: &PlantSettings) -> Result<()> {
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
    Ok(std::fs::write(path, text).at("cannot write", path)?)
}
