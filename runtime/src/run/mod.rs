//! `rig run`: one experiment as three processes — plant, observer, agent — over iceoryx2,
//! launched, supervised and recorded by this process.
//!
//! * The supervisor joins the run and subscribes to every topic *before* starting the
//!   processes, which wait for it (`--receivers 2`), so it sees every message.
//! * It records every message to `run.mcap` ([`crate::record`]), streams `returns.csv`
//!   (the format of `rig learn`'s `runs.csv`, one run), shows progress, and checks that no
//!   message was lost (sequence numbers).
//! * A process that exits early or fails, Ctrl-C, or a lost message stops the run: the
//!   other processes are killed, the reason is reported, the recording is finished (so
//!   `run.mcap` stays readable), and the call fails. Each process's output goes to
//!   `DIR/<process>.log`.
//! * With an external driver (`--plant external`, `docs/driver.md`), the supervisor
//!   first waits for the driver's info and checks it against the task, then starts the
//!   plant process as the episode master for that driver (`rig plant --driver ID`), and
//!   records the driver's samples and commands too (`/driver/...`).
//! * With a sensor that does not measure the full state (`[observer] sensor = "angle"`)
//!   it also subscribes to the plant's ground truth ([`wire::Truth`], `rig/<id>/truth`,
//!   which no other process reads), records it as `/plant/truth`, and takes a finite
//!   horizon's terminal reward `τ_N(x_N)` of the true state, as `rig learn` does.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow};
use driver::contract::{DriverInfo, DriverWatch};
use wire::{Action, Bus, Estimate, Measurement, Truth, topic};

use crate::config::ExperimentConfig;
use crate::experiment::TrialRecord;
use crate::learn::{RUNS_HEADER, progress_bar, write_atomic, write_row};
use crate::process::{Scheduling, wire_err};
use crate::record::Recorder;
use crate::resume::{self, ResumePoint};

mod recording;
mod returns;
mod supervisor;

use recording::{Recording, join};
use returns::Returns;
use supervisor::{Children, Continuity, Supervisor};

/// Where and how to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// Run id (default: unique per invocation).
    pub run_id: Option<String>,
    /// Show a progress bar.
    pub progress: bool,
    /// `None`: lockstep; `Some(speed)`: realtime at `speed` × real time (simulated
    /// plant only).
    pub realtime: Option<f64>,
    /// An external driver in place of the simulated plant.
    pub driver: Option<ExternalDriver>,
    /// Continue the run in `out` from its last complete trial ([`crate::resume`]).
    pub resume: bool,
    /// Realtime, simulated plant: the plant writes every sample's timing to this file
    /// (`rig plant --cycles-out`, for `rig latency`).
    pub cycles_out: Option<PathBuf>,
    /// How the three processes are scheduled (`--spin-us`: realtime, simulated plant
    /// only; `--pin-cpus` also pins this process with the observer and the agent).
    pub scheduling: Scheduling,
}

/// An external driver in place of the simulated plant (`rig run --plant external`).
#[derive(Clone, Debug)]
pub struct ExternalDriver {
    /// The driver's id (services `rig/driver/<id>/...`).
    pub id: String,
    /// How long to wait for the driver to appear.
    pub timeout: Duration,
    /// How long one reset may take.
    pub reset_timeout: Duration,
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
    /// The external driver's info, if one was used.
    pub driver: Option<DriverInfo>,
}

/// Runs experiment `cfg` (one run) as three processes and writes the outputs.
pub fn run(cfg: &ExperimentConfig, opts: &RunOptions) -> Result<RunSummary> {
    let mut cfg = cfg.clone();
    cfg.run.runs = 1;
    let run_id = opts
        .run_id
        .clone()
        .unwrap_or_else(|| format!("{}-{}", std::process::id(), wire::now_ns() % 1_000_000_000));
    // Joining a run that is going on would feed its processes a second set of messages.
    let busy = Bus::live_roles(&run_id);
    if !busy.is_empty() {
        return Err(anyhow!(
            "run id {run_id:?} is in use by a run that is going on (its {} running); choose another --run-id",
            match busy.as_slice() {
                [one] => format!("{one} process is"),
                many => format!("{} processes are", many.join(", ")),
            }
        ));
    }
    // Where a resumed run continues; checked before anything is written.
    let point = if opts.resume {
        Some(resume::prepare(&opts.out, &cfg, opts.driver.is_some())?)
    } else {
        None
    };
    if let Some(p) = &point {
        for note in &p.notes {
            eprintln!("note: {note}");
        }
    }
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create output directory {}", opts.out.display()))?;
    let checkpoints = resume::checkpoint_dir(&opts.out);
    if point.is_none() {
        // A new run in an old directory: old checkpoints must not be taken for its own.
        resume::prune(&checkpoints, u32::MAX);
    }
    let config_path = opts.out.join("config.toml");
    write_atomic(&config_path, &cfg.to_toml())?;
    let bus = Bus::join(&run_id, "rig").map_err(wire_err)?;
    let measurements = bus
        .rx::<Measurement>(topic::MEASUREMENT)
        .map_err(wire_err)?;
    let estimates = bus.rx::<Estimate>(topic::ESTIMATE).map_err(wire_err)?;
    let actions = bus.rx::<Action>(topic::ACTION).map_err(wire_err)?;
    let full_state = cfg.observer.sensor == ::observer::config::SensorKind::Full;
    let truths = if full_state {
        None
    } else {
        Some(bus.rx::<Truth>(topic::TRUTH).map_err(wire_err)?)
    };

    let task = std::sync::Arc::new(plant::Task::new(cfg.system));
    let (watch, driver_info) = match &opts.driver {
        Some(d) => {
            let (watch, info) = wait_for_driver(&bus, d, &task, opts.progress)?;
            (Some(watch), Some(info))
        }
        None => (None, None),
    };
    let mut recording = Recording::create(
        &opts.out.join("run.mcap"),
        task.state_dim(),
        task.action_dim(),
    )?;
    recording.realtime = opts.realtime.is_some() || opts.driver.is_some();
    if opts.driver.is_some() {
        recording.add_driver()?;
    }
    if !full_state {
        recording.add_truth()?;
    }
    recording
        .rec
        .attach("config.toml", "application/toml", cfg.to_toml().as_bytes())?;
    let meta: BTreeMap<String, String> = [
        ("run_id", run_id.clone()),
        ("seed", cfg.run.seed.to_string()),
        ("system", cfg.system.to_string()),
        ("algo", cfg.agent.algo.to_string()),
        ("approx", cfg.agent.approx.to_string()),
        ("horizon", cfg.agent.horizon.to_string()),
        (
            "timing",
            match (&opts.driver, &driver_info, opts.realtime) {
                (Some(d), Some(i), _) => format!(
                    "external driver {:?}: period {} ns, time scale {}",
                    d.id, i.period_ns, i.time_scale
                ),
                (_, _, None) => "lockstep".to_string(),
                (_, _, Some(speed)) => format!("realtime, speed {speed}"),
            },
        ),
        ("rig_version", env!("CARGO_PKG_VERSION").to_string()),
        // The reward's weights, so that a reader can recompute a finite horizon's
        // terminal reward τ_N(x_N) = −eᵀQe (Eq. 4.1; tests/python/check_mcap.py).
        ("reward_q", join(&task.reward.q)),
        ("reward_reference", join(&task.reward.reference)),
        (
            "reward_angles",
            join(task.reward.angle_mask.iter().map(|&a| u8::from(a))),
        ),
        (
            "resumed_after_trial",
            point
                .as_ref()
                .map_or("-".to_string(), |p| p.trial.to_string()),
        ),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    recording.rec.metadata("run", &meta)?;
    if let Some(p) = &point {
        copy_recorded(&mut recording.rec, p, &opts.out)?;
    }

    let returns_path = opts.out.join("returns.csv");
    let mut out = BufWriter::new(
        File::create(&returns_path)
            .with_context(|| format!("cannot create {}", returns_path.display()))?,
    );
    writeln!(out, "{RUNS_HEADER}")?;
    let kept = point.as_ref().map_or(&[][..], |p| &p.records[..]);
    for r in kept {
        write_row(&mut out, r)?;
    }
    out.flush()?;
    let (after, sim_time) = point.as_ref().map_or((0, 0.0), |p| (p.trial, p.sim_time_s));
    let returns = Returns {
        out,
        task: task.clone(),
        steps_per_trial: task.steps_per_trial() as u64,
        skipped_samples: task.skipped_samples(after.into(), sim_time),
        horizon: cfg.agent.horizon.of(&task),
        reward: task.reward.clone(),
        pending: None,
        pending_ended: false,
        eval_starts: task.initial_states.len() as u32,
        eval_every: cfg.run.eval_every,
        greedy_trial: 0.0,
        greedy: (0.0, 0),
        records: kept.to_vec(),
    };

    let exe = std::env::current_exe().context("cannot find the rig executable")?;
    let mut children = Children(Vec::new());
    let plant_timing: Vec<String> = match (&opts.driver, opts.realtime) {
        (Some(d), _) => vec![
            "--driver".into(),
            d.id.clone(),
            "--driver-timeout".into(),
            d.timeout.as_secs_f64().to_string(),
            "--reset-timeout".into(),
            d.reset_timeout.as_secs_f64().to_string(),
        ],
        (None, None) => Vec::new(),
        (None, Some(speed)) => vec![
            "--timing".into(),
            "realtime".into(),
            "--speed".into(),
            speed.to_string(),
            "--spin-us".into(),
            opts.scheduling.spin_us.to_string(),
        ],
    };
    let first_seq = point.as_ref().map_or(0, |p| p.first_seq);
    let mut role_args: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    role_args.insert("plant", plant_timing);
    if let (Some(path), Some(_), None) = (&opts.cycles_out, opts.realtime, &opts.driver) {
        role_args
            .get_mut("plant")
            .expect("plant")
            .extend(["--cycles-out".to_string(), path.display().to_string()]);
    }
    let mut agent_args = vec![
        "--checkpoints".to_string(),
        checkpoints.display().to_string(),
    ];
    if let Some(p) = &point {
        if let Some(c) = &p.checkpoint {
            agent_args.extend(["--resume".to_string(), c.display().to_string()]);
        }
        role_args.get_mut("plant").expect("plant").extend([
            "--after-trial".to_string(),
            p.trial.to_string(),
            "--sim-time".to_string(),
            p.sim_time_s.to_string(),
            "--first-seq".to_string(),
            p.first_seq.to_string(),
        ]);
    }
    role_args.insert("agent", agent_args);
    if opts.scheduling.pin_cpus {
        crate::process::pin(crate::process::Cpus::Rest)?;
    }
    for role in ["agent", "observer", "plant"] {
        role_args
            .entry(role)
            .or_default()
            .extend(opts.scheduling.process_args());
    }
    for role in ["agent", "observer", "plant"] {
        let log = opts.out.join(format!("{role}.log"));
        let log_file =
            File::create(&log).with_context(|| format!("cannot create {}", log.display()))?;
        let child = Command::new(&exe)
            .arg(role)
            .args(["--run-id", &run_id, "--receivers", "2", "--config"])
            .arg(&config_path)
            .args(role_args.get(role).map_or(&[][..], |a| &a[..]))
            .stdin(Stdio::null())
            .stdout(log_file.try_clone()?)
            .stderr(log_file)
            .spawn()
            .with_context(|| format!("cannot start the {role} process"))?;
        children.0.push((role, child));
    }

    let evals = cfg.run.trials.checked_div(cfg.run.eval_every).unwrap_or(0);
    let bar = progress_bar(u64::from(cfg.run.trials + evals), opts.progress, "rig run");
    bar.inc(u64::from(
        after + after.checked_div(cfg.run.eval_every).unwrap_or(0),
    ));
    let t0 = Instant::now();
    let mut sup = Supervisor {
        bus,
        measurements,
        estimates,
        actions,
        truths,
        batch: Vec::new(),
        truth_queue: std::collections::VecDeque::new(),
        recording,
        returns,
        children,
        out: opts.out.clone(),
        messages: 0,
        continuity: std::array::from_fn(|_| Continuity { next: first_seq }),
        deadline_misses: 0,
        driver: watch,
        grace: match (&driver_info, opts.realtime) {
            (Some(i), _) => Some(Duration::from_nanos(i.period_ns.saturating_mul(4))),
            (None, Some(speed)) => Some(Duration::from_secs_f64(4.0 * task.ts / speed)),
            (None, None) => None,
        },
    };
    let outcome = sup.supervise(&bar);
    bar.finish_and_clear();
    // Stop the processes first (on failure), then finish the recording either way, so
    // that run.mcap is readable after any outcome.
    drop(std::mem::replace(&mut sup.children, Children(Vec::new())));
    let _ = sup.returns.flush_complete();
    let Supervisor {
        recording,
        returns,
        messages,
        deadline_misses,
        ..
    } = sup;
    let finished = recording.rec.finish();
    outcome?;
    finished?;
    Ok(RunSummary {
        records: returns.records,
        messages,
        wall: t0.elapsed(),
        deadline_misses,
        driver: driver_info,
    })
}

/// Copies the messages a resumed run keeps into its new recording, then removes the old
/// recording (so that only the new one holds them).
fn copy_recorded(rec: &mut Recorder, p: &ResumePoint, out: &Path) -> Result<()> {
    for m in &p.messages {
        if m.topic.starts_with("/driver/") && !rec.has_topic(&m.topic) {
            // An external driver's traffic, recorded before; this part runs without one.
            continue;
        }
        rec.write_encoded(&m.topic, m.log_time, m.publish_time, &m.data)
            .with_context(|| {
                format!(
                    "cannot keep the recorded trials: {} was recorded with another channel layout",
                    out.join("run.mcap").display()
                )
            })?;
    }
    rec.flush()?;
    let old = out.join("run.mcap");
    if old.exists() {
        std::fs::remove_file(&old).with_context(|| format!("cannot remove {}", old.display()))?;
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
    let watch = DriverWatch::open(bus, &d.id).map_err(wire_err)?;
    let first = Duration::from_secs(1).min(d.timeout);
    let info = match driver::contract::wait_info(bus, &watch.info, &d.id, first) {
        Ok(i) => i,
        Err(_) => {
            if verbose {
                eprintln!(
                    "waiting up to {:.0} s for driver {:?} (services {}) ...",
                    d.timeout.as_secs_f64(),
                    d.id,
                    driver::contract::service(&d.id, "*")
                );
            }
            driver::contract::wait_info(bus, &watch.info, &d.id, d.timeout.saturating_sub(first))
                .map_err(wire_err)?
        }
    };
    info.validate()
        .and_then(|()| driver::fits_task(&info, task))
        .map_err(|e| anyhow!("driver {:?} does not fit the task: {e}", d.id))?;
    Ok((watch, info))
}
