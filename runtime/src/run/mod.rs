//! `rig run`: one experiment as three processes — plant, observer, agent — over iceoryx2,
//! launched, supervised and recorded by this process.
//!
//! * The supervisor joins the run and subscribes to every topic *before* starting the
//!   processes, which wait for it (`receivers = 2`), so it sees every message.
//! * It records every message to `run.mcap` ([`crate::record`]), streams `returns.csv`
//!   (the format of `rig learn`'s `runs.csv`, one run), shows progress, and checks that no
//!   message was lost (sequence numbers).
//! * A process that exits early or fails, Ctrl-C, or a lost message stops the run: the
//!   other processes are killed, the reason is reported, the recording is finished (so
//!   `run.mcap` stays readable), and the call fails. Each process's output goes to
//!   `DIR/<process>.log`.
//! * With an external driver (`--plant external`, `docs/driver.md`), the supervisor
//!   first waits for the driver's info and checks it against the task, then starts the
//!   plant process as the episode master for that driver (its clock `Clock::External`), and
//!   records the driver's samples and commands too (`/driver/...`).
//! * With a sensor that does not measure the full state (`[observer] sensor = "angle"`)
//!   it also subscribes to the plant's ground truth ([`wire::Truth`], `rig/<id>/truth`,
//!   which no other process reads), records it as `/plant/truth`, and takes a finite
//!   horizon's terminal reward `τ_N(x_N)` of the true state, as `rig learn` does.
//! * The output folder is this run's while it lasts ([`crate::lock`]).
//! * [`run_with`] hands every message recorded to a [`Tap`] too — a live view — in the
//!   recording's encoding, with the trials' returns and the loop's latency besides.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use driver::contract::DriverInfo;
use driver::link::DriverWatch;
use wire::{Bus, Waiting};

use crate::clock::{Checked, Clock, ClockError, ExternalDriver};
use crate::config::ExperimentConfig;
use crate::error::AtFile;
use crate::experiment::TrialRecord;
use crate::lock::FolderLock;
use crate::output::{progress_bar, write_atomic};
use crate::process::{Scheduling, Spin};
use crate::record::Tap;
use crate::record::channels::RETURNS;
use crate::record::scene::SceneMaker;
use crate::resume;

mod command;
mod error;
mod gaps;
mod logs;
mod recording;
mod retention;
mod returns;
mod spawn;
mod supervisor;

pub use command::NodeCommand;
use error::Result;
pub use error::RunError;
pub use gaps::GAPS_HEADER;
use recording::{About, RecordingWriter};
use returns::Returns;
use supervisor::Supervisor;

/// Where and how to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// Run id (default: unique per invocation).
    pub run_id: Option<String>,
    /// Show a progress bar.
    pub progress: bool,
    /// What moves the run from one sample to the next.
    pub clock: Clock,
    /// The clock checked against the experiment and `waiting`: [`Clock::check`].
    pub checked: Checked,
    /// How each of the three processes is started: the application's program.
    pub nodes: NodeCommand,
    /// Continue the run in `out` from its last complete trial ([`crate::resume`]).
    pub resume: bool,
    /// Realtime, simulated plant: the plant writes every sample's timing to this file
    /// (the plant node's `cycles_out`, for `rig latency`).
    pub cycles_out: Option<PathBuf>,
    /// How the three processes are scheduled; the layout (`--cpus`) places this
    /// process, the recorder, too.
    pub scheduling: Scheduling,
    /// How the plant waits for a sampling instant (realtime, simulated plant only).
    pub spin: Spin,
    /// How the three processes wait for their next message.
    pub waiting: Waiting,
    /// How they wait when an external driver keeps the lockstep clock, in place of
    /// `waiting` (`None`: as that says; `rig run` without `--wait`: polling without end,
    /// as a lockstep run with the simulated plant). Known once the driver's info is read.
    pub lockstep_waiting: Option<Waiting>,
    /// Realtime and external driver: learn across gaps in the loop's timing instead of
    /// cutting the attempt short and running the trial again (`--gaps learn`).
    pub learn_across_gaps: bool,
    /// Draws the system for the recording's `/scene` (`None`: no `/scene`).
    pub scene: Option<SceneMaker>,
}

/// What a run produced.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// The learning trials, as written to `returns.csv`.
    pub records: Vec<TrialRecord>,
    /// Messages received by the supervisor (all topics).
    pub messages: u64,
    /// Wall-clock time of the run.
    pub wall: Duration,
    /// Deadlines the plant missed (realtime and external driver only).
    pub deadline_misses: u64,
    /// Trial attempts cut short by gaps and run again (`gaps.csv`; realtime and
    /// external driver only).
    pub gaps: u64,
    /// The external driver's info, if one was used.
    pub driver: Option<DriverInfo>,
    /// A resumed run: the trial it continued after (`records` begins with the trials
    /// up to it, kept).
    pub resumed_after: Option<u32>,
}

/// Runs experiment `cfg` (one run) as three processes and writes the outputs.
pub fn run(cfg: &ExperimentConfig, opts: &RunOptions) -> Result<RunSummary> {
    run_with(cfg, opts, None)
}

/// [`run`], handing every channel and message recorded to `tap` too (a live view: `rig
/// run --live`; the recording stays as it is).
pub fn run_with(
    cfg: &ExperimentConfig,
    opts: &RunOptions,
    tap: Option<Box<dyn Tap>>,
) -> Result<RunSummary> {
    let cfg = cfg.one_run();
    let run_id = free_run_id(opts)?;
    // A folder this run creates is removed again if the run is refused before it
    // writes anything.
    let created = !opts.resume && !opts.out.exists();
    if !opts.resume {
        std::fs::create_dir_all(&opts.out).at("cannot create output directory", &opts.out)?;
    }
    let _folder = FolderLock::acquire(&opts.out)?;
    let checkpoints = resume::checkpoint_dir(&opts.out);
    if checkpoints.exists() {
        // Not in use by an agent started by hand; free again for this run's agent.
        drop(FolderLock::acquire(&checkpoints)?);
    }
    // Where a resumed run continues; checked before anything is written.
    let point = match opts.resume {
        true => Some(resume::prepare(&opts.out, &cfg, opts.clock.is_external())?),
        false => None,
    };
    for note in point.iter().flat_map(|p| &p.notes) {
        eprintln!("note: {note}");
    }
    let bus = Bus::join(&run_id, "rig")?;
    let task = cfg.task();
    let (watch, driver_info, with_driver) = match opts.clock.driver() {
        Some(d) => match wait_for_driver(&bus, d, &task, opts.progress).and_then(|(watch, info)| {
            check_reward_source(&cfg, &d.id, &info)?;
            Ok((watch, info, driver_options(opts, &info)?))
        }) {
            Ok((watch, info, with)) => (Some(watch), Some(info), Some(with)),
            Err(e) => {
                if created {
                    // Holds only the lock file: a refused run leaves no folder behind.
                    let _ = std::fs::remove_dir_all(&opts.out);
                }
                return Err(e);
            }
        },
        None => (None, None, None),
    };
    let opts = with_driver.as_ref().unwrap_or(opts);
    // Nothing is written before the driver is found and fits. A new run in an old
    // directory: old checkpoints must not be taken for its own; a resumed run's after its
    // resume point are of trials it redoes.
    resume::discard_after(&checkpoints, point.as_ref().map_or(0, |p| p.trial));
    let config_path = opts.out.join("config.toml");
    write_atomic(&config_path, &cfg.to_toml())?;
    let about = About {
        cfg: &cfg,
        task: &task,
        run_id: &run_id,
        timing: opts.clock.describe(task.ts, driver_info.as_ref()),
        realtime: !opts.clock.is_lockstep(),
        driver: opts.clock.is_external(),
        driver_reward: driver_info.is_some_and(|i| i.provides_reward()),
        point: point.as_ref(),
        scene: opts.scene,
    };
    let mut recording = RecordingWriter::open(&opts.out, &about)?;
    if let Some(tap) = tap {
        recording.live(tap);
    }
    let returns = Returns::create(
        &opts.out.join("returns.csv"),
        &cfg,
        task.clone(),
        point.as_ref(),
    )?;
    let grace = match (&driver_info, opts.clock.period()) {
        (Some(i), _) => Some(Duration::from_nanos(i.period_ns.saturating_mul(4))),
        (None, period) => period.map(|p| 4 * p),
    };
    let gaps = gaps::GapLog::create(&opts.out.join("gaps.csv"), point.as_ref())?;
    let first_seq = point.as_ref().map_or(0, |p| p.first_seq);
    let mut sup = Supervisor::new(
        bus,
        recording,
        (returns, gaps),
        &opts.out,
        first_seq,
        watch,
        grace,
    )?;
    if let Some(d) = opts.clock.driver() {
        sup.resume_flags = format!(" --plant external --driver {}", d.id);
    }
    sup.rows_recorded = point.as_ref().map_or(0, |p| {
        p.messages.iter().filter(|m| m.topic == RETURNS).count()
    });

    let nodes = spawn::Nodes::new((&run_id, &config_path), opts, point.as_ref(), &checkpoints);
    (sup.children, sup.logs) = spawn::processes(&opts.out, &nodes, &opts.nodes)?;
    // Placed after the processes started: they place themselves, from anywhere.
    opts.scheduling.place(crate::process::Part::Recorder)?;
    let lockstep = match &opts.clock {
        Clock::External(_) => driver_info.is_some_and(|i| i.lockstep()),
        clock => clock.is_lockstep(),
    };
    if lockstep {
        crate::process::batch_thread();
    }

    let after = point.as_ref().map_or(0, |p| p.trial);
    let evals = |trials: u32| trials.checked_div(cfg.run().eval_every).unwrap_or(0);
    let bar = progress_bar(
        u64::from(cfg.run().trials + evals(cfg.run().trials)),
        opts.progress,
        "rig run",
    );
    bar.inc(u64::from(after + evals(after)));
    let t0 = Instant::now();
    let outcome = sup.supervise(&bar);
    bar.finish_and_clear();
    let gaps = sup.gaps.now;
    let (records, messages, deadline_misses) = sup.finish(outcome)?;
    // Every trial is complete everywhere: the last one's checkpoint is what a resume
    // (`--trials N`, to learn on) needs.
    resume::keep_from_newest(&checkpoints, records.last().map_or(0, |r| r.trial));
    Ok(RunSummary {
        records,
        messages,
        wall: t0.elapsed(),
        deadline_misses,
        gaps,
        driver: driver_info,
        resumed_after: point.as_ref().map(|p| p.trial),
    })
}

/// The run id of `opts`, or a new one; refused when a run of that id is going on
/// (joining it would feed its processes a second set of messages).
fn free_run_id(opts: &RunOptions) -> Result<String> {
    let run_id = opts
        .run_id
        .clone()
        .unwrap_or_else(|| format!("{}-{}", std::process::id(), wire::now_ns() % 1_000_000_000));
    let busy = Bus::live_roles(&run_id);
    if !busy.is_empty() {
        let running = match busy.as_slice() {
            [one] => format!("{one} process is"),
            many => format!("{} processes are", many.join(", ")),
        };
        return Err(RunError::RunIdInUse { run_id, running });
    }
    Ok(run_id)
}

/// The options of a run against a driver whose info is `info`: with a driver that keeps
/// the lockstep clock, the processes wait as [`RunOptions::lockstep_waiting`] says and,
/// unless `--cpus` said, are placed as a lockstep run that waits so
/// ([`CpuLayout::lockstep`]); polling without end is refused with a driver in real time.
fn driver_options(opts: &RunOptions, info: &DriverInfo) -> Result<RunOptions, ClockError> {
    let mut with = opts.clone();
    if info.lockstep()
        && let Some(w) = opts.lockstep_waiting
    {
        with.waiting = w;
        with.scheduling = with.scheduling.in_lockstep(w);
    }
    Clock::check_driver_waiting(info, with.waiting)?;
    Ok(with)
}

/// Refuses a learner that needs the reward's gradient with a driver that provides the
/// reward as numbers only.
fn check_reward_source(cfg: &ExperimentConfig, id: &str, info: &DriverInfo) -> Result<()> {
    let algo = cfg.agent().algo;
    if info.provides_reward() && algo.needs_reward_gradient() {
        return Err(RunError::RewardGradient {
            algo,
            id: id.to_owned(),
            task: info.task_name().to_string(),
        });
    }
    Ok(())
}

/// Waits for driver `d`'s info (saying so after a second of silence when `verbose`)
/// and checks that the driver fits `task`; returns a watch on its traffic (to record it)
/// and its info.
fn wait_for_driver(
    bus: &Bus,
    d: &ExternalDriver,
    task: &plant::Task,
    verbose: bool,
) -> Result<(DriverWatch, DriverInfo)> {
    let watch = DriverWatch::open(bus, &d.id)?;
    let serve = driver::link::how_to_serve(task, &d.id, None);
    let info = driver::link::wait_info(
        bus,
        &watch.info,
        &d.id,
        d.timeout,
        verbose,
        &serve,
        &wire::Monotonic::host(),
    )?;
    driver::link::check_info(&d.id, &info, task)?;
    Ok((watch, info))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::process::CpuLayout;
    use driver::contract::clock;
    use wire::FOREVER;

    fn options(waiting: Waiting, lockstep_waiting: Option<Waiting>) -> RunOptions {
        RunOptions {
            out: PathBuf::from("out"),
            run_id: None,
            progress: false,
            clock: Clock::External(ExternalDriver {
                id: "pendulum".into(),
                timeout: Duration::from_secs(1),
                reset_timeout: Duration::from_secs(1),
            }),
            checked: Checked(()),
            nodes: NodeCommand {
                program: "node".into(),
                plant: vec![],
                observer: vec![],
                agent: vec![],
            },
            resume: false,
            cycles_out: None,
            scheduling: Scheduling {
                rt_priority: None,
                pin_cpus: false,
                cpus: None,
            },
            spin: Spin::default(),
            waiting,
            lockstep_waiting,
            learn_across_gaps: false,
            scene: None,
        }
    }

    fn info(clock: u64) -> DriverInfo {
        DriverInfo {
            clock,
            ..Default::default()
        }
    }

    #[test]
    fn a_driver_in_lockstep_is_polled_as_a_lockstep_run_and_one_in_real_time_is_not() {
        let polls = Waiting::Yield(FOREVER);
        let opts = options(Waiting::Block, Some(polls));
        let with = driver_options(&opts, &info(clock::LOCKSTEP)).unwrap();
        assert_eq!(with.waiting, polls);
        assert_eq!(with.scheduling.cpus, Some(CpuLayout::lockstep(polls)));
        let with = driver_options(&opts, &info(clock::REALTIME)).unwrap();
        assert_eq!(with.waiting, Waiting::Block);
        assert_eq!(with.scheduling.cpus, None);
        // `--cpus` given stays.
        let mut placed = opts.clone();
        placed.scheduling.cpus = Some(CpuLayout::Shared);
        let with = driver_options(&placed, &info(clock::LOCKSTEP)).unwrap();
        assert_eq!(with.scheduling.cpus, Some(CpuLayout::Shared));
        // Polling without end asked for against a driver in real time is refused.
        let opts = options(polls, None);
        assert!(driver_options(&opts, &info(clock::LOCKSTEP)).is_ok());
        let e = driver_options(&opts, &info(clock::REALTIME)).unwrap_err();
        assert!(matches!(e, ClockError::Unwoken), "{e}");
    }
}
