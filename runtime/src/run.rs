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
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use ::agent::horizon::Horizon;
use anyhow::{Context, Result, anyhow, bail};
use driver::contract::{DriverCommand, DriverInfo, DriverSample, DriverWatch};
use indicatif::ProgressBar;
use wire::{Action, Bus, Estimate, Header, Measurement, Truth, flags, topic};

use crate::config::ExperimentConfig;
use crate::experiment::TrialRecord;
use crate::learn::{RUNS_HEADER, progress_bar, write_atomic, write_row};
use crate::process::{Scheduling, wire_err};
use crate::record::{ChannelId, Field, FieldKind, Recorder, Value};
use crate::resume::{self, ResumePoint};

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

/// How long the supervisor watches after a process exits early, to see which process
/// caused the stop (the others follow within milliseconds).
const CAUSE_WINDOW: Duration = Duration::from_millis(100);

/// Builds `returns.csv` rows from the plant's measurements.
struct Returns {
    out: BufWriter<File>,
    task: std::sync::Arc<plant::Task>,
    steps_per_trial: u64,
    /// Samples not run because trials ended early (left the operating range).
    skipped_samples: u64,
    /// Adds `τ_N(x_N)` of a finite horizon's last measurement to the return (Eq. 4.1).
    horizon: Horizon,
    reward: plant::QuadraticReward,
    pending: Option<TrialRecord>,
    /// Whether the pending learning trial has ended.
    pending_ended: bool,
    /// Greedy evaluation trials after a learning trial, when due (one per start state).
    eval_starts: u32,
    /// A greedy evaluation after every this-many trials (0: none).
    eval_every: u32,
    /// The running greedy trial's reward sum.
    greedy_trial: f64,
    /// Sum of the returns of the greedy trials after the pending trial, and their count.
    greedy: (f64, u32),
    records: Vec<TrialRecord>,
}

impl Returns {
    /// Accounts for the sample with header `h` and reward `reward`; `x` is its state for
    /// a finite horizon's terminal reward. From the plant's measurements: the true state
    /// (the measurement's `y` with full-state sensing); with [`flags::ESTIMATED_REWARD`]
    /// from the observer's estimates instead: their rewards and `x̂`.
    fn sample(&mut self, h: &wire::Header, reward: f64, x: &[f64]) -> Result<()> {
        let f = h.flags;
        let greedy = f & flags::GREEDY != 0;
        if f & flags::SHUTDOWN != 0 || (f & flags::START != 0 && !greedy) {
            self.flush()?;
        }
        if f & flags::SHUTDOWN != 0 {
            return Ok(());
        }
        if f & flags::START != 0 {
            if greedy {
                self.greedy_trial = 0.0;
            } else {
                self.greedy = (0.0, 0);
                self.pending_ended = false;
                self.pending = Some(TrialRecord {
                    run: 0,
                    trial: h.trial as u32,
                    sim_time_s: 0.0,
                    ret: 0.0,
                    greedy: None,
                });
            }
            return Ok(());
        }
        let pending = self
            .pending
            .as_mut()
            .ok_or_else(|| anyhow!("a sample arrived before any trial started"))?;
        let end = f & flags::END != 0;
        let final_reward = if end {
            self.horizon.final_reward(&self.reward, x)
        } else {
            0.0
        };
        if greedy {
            // One greedy trial per start state: the greedy return is their mean.
            self.greedy_trial += reward;
            if end {
                self.greedy_trial += final_reward;
                self.greedy.0 += self.greedy_trial;
                self.greedy.1 += 1;
                pending.greedy = Some(self.greedy.0 / f64::from(self.greedy.1));
            }
        } else {
            pending.ret += reward;
            if end {
                self.pending_ended = true;
                pending.ret += final_reward;
                self.skipped_samples += self.steps_per_trial.saturating_sub(h.step);
                pending.sim_time_s = self
                    .task
                    .sim_time(pending.trial.into(), self.skipped_samples);
            }
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<()> {
        if let Some(r) = self.pending.take() {
            write_row(&mut self.out, &r)?;
            self.out.flush()?;
            self.records.push(r);
        }
        Ok(())
    }

    /// After a failure: writes the pending trial only if it is complete — the learning
    /// trial and its greedy evaluations (a resumed run redoes an incomplete one).
    fn flush_complete(&mut self) -> Result<()> {
        let complete = self.pending.as_ref().is_some_and(|p| {
            let due = self.eval_every > 0 && p.trial.is_multiple_of(self.eval_every);
            self.pending_ended && self.greedy.1 == if due { self.eval_starts } else { 0 }
        });
        if complete {
            self.flush()?;
        }
        Ok(())
    }
}

/// The MCAP recording: one channel per topic, and one `/timing/...` channel per topic
/// for the wall-clock timestamps, which differ from run to run by nature. Log time is
/// simulated time.
struct Recording {
    rec: Recorder,
    measurement: ChannelId,
    estimate: ChannelId,
    action: ChannelId,
    /// `/plant/truth`, with a sensor that does not measure the full state.
    truth: Option<ChannelId>,
    t_measurement: ChannelId,
    t_estimate: ChannelId,
    t_action: ChannelId,
    /// `/driver/sample` and `/driver/command`, with an external driver.
    driver: Option<(ChannelId, ChannelId)>,
    n: usize,
    m: usize,
    values: Vec<Value>,
    /// Log time: simulated time (lockstep) or the plant's sample time (realtime).
    realtime: bool,
    /// The current sample's plant sample time (monotonic ns).
    t_sample_ns: u64,
}

/// `a,b,c`: values in Rust's shortest round-trip form, which a reader parses exactly.
fn join<T: std::fmt::Display>(values: impl IntoIterator<Item = T>) -> String {
    values
        .into_iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

fn header_fields(extra: Vec<Vec<Field>>) -> Vec<Field> {
    let mut f: Vec<Field> = ["seq", "trial", "step", "flags"]
        .iter()
        .map(|n| Field::integer(n))
        .collect();
    f.push(Field::number("t_sim"));
    f.extend(extra.into_iter().flatten());
    f
}

fn timing_fields(names: &[&str]) -> Vec<Field> {
    std::iter::once(Field::integer("seq"))
        .chain(names.iter().map(|n| Field::integer(n)))
        .collect()
}

impl Recording {
    fn create(path: &Path, n: usize, m: usize) -> Result<Self> {
        let mut rec = Recorder::create(path)?;
        let state = |name| {
            vec![
                vec![Field::number("reward")],
                Field::array(name, n, FieldKind::Number),
                Field::array("u_applied", m, FieldKind::Number),
            ]
        };
        let mut measured = state("y");
        measured.push(Field::array("u_next", m, FieldKind::Number));
        measured.push(vec![Field::number("delay_s")]);
        let measurement = rec.channel(
            "/plant/measurement",
            "rig.Measurement",
            &header_fields(measured),
        )?;
        let estimate = rec.channel(
            "/observer/estimate",
            "rig.Estimate",
            &header_fields(state("x")),
        )?;
        let action = rec.channel(
            "/agent/action",
            "rig.Action",
            &header_fields(vec![Field::array("u", m, FieldKind::Number)]),
        )?;
        let stamps = ["t_sample_ns", "t_received_ns", "t_publish_ns"];
        let t_measurement = rec.channel(
            "/timing/plant/measurement",
            "rig.Timing.Measurement",
            &timing_fields(&["t_sample_ns", "t_publish_ns"]),
        )?;
        let t_estimate = rec.channel(
            "/timing/observer/estimate",
            "rig.Timing.Estimate",
            &timing_fields(&stamps),
        )?;
        let t_action = rec.channel(
            "/timing/agent/action",
            "rig.Timing.Action",
            &timing_fields(&stamps),
        )?;
        Ok(Self {
            rec,
            measurement,
            estimate,
            action,
            truth: None,
            t_measurement,
            t_estimate,
            t_action,
            driver: None,
            n,
            m,
            values: Vec::new(),
            realtime: false,
            t_sample_ns: 0,
        })
    }

    /// Starts a message with the header fields; returns its log time (simulated, ns).
    fn header(&mut self, h: &Header) -> u64 {
        self.values.clear();
        self.values.extend([
            Value::Int(h.seq),
            Value::Int(h.trial),
            Value::Int(h.step),
            Value::Int(h.flags),
            Value::Num(h.t_sim),
        ]);
        if self.realtime {
            self.t_sample_ns
        } else {
            (h.t_sim * 1e9).round() as u64
        }
    }

    fn write(
        &mut self,
        ch: ChannelId,
        t: u64,
        timing: ChannelId,
        seq: u64,
        stamps: &[u64],
    ) -> Result<()> {
        self.rec.write(ch, t, t, &self.values)?;
        self.values.clear();
        self.values.push(Value::Int(seq));
        self.values.extend(stamps.iter().map(|&s| Value::Int(s)));
        self.rec.write(timing, t, t, &self.values)
    }

    fn nums(&mut self, v: &[f64]) {
        self.values.extend(v.iter().map(|&x| Value::Num(x)));
    }

    fn measurement(&mut self, msg: &Measurement) -> Result<()> {
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&[msg.reward]);
        self.nums(&msg.y[..self.n]);
        self.nums(&msg.u_applied[..self.m]);
        self.nums(&msg.u_next[..self.m]);
        self.nums(&[msg.delay_s]);
        self.write(
            self.measurement,
            t,
            self.t_measurement,
            msg.header.seq,
            &[msg.t_sample_ns, msg.t_publish_ns],
        )
    }

    /// Adds the channel of the plant's ground truth.
    fn add_truth(&mut self) -> Result<()> {
        let fields = header_fields(vec![Field::array("x", self.n, FieldKind::Number)]);
        self.truth = Some(self.rec.channel("/plant/truth", "rig.Truth", &fields)?);
        Ok(())
    }

    /// Records the ground truth of a sample, with the log time of its measurement.
    fn truth(&mut self, msg: &Truth) -> Result<()> {
        let Some(ch) = self.truth else {
            return Ok(());
        };
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&msg.x[..self.n]);
        self.rec.write(ch, t, t, &self.values)
    }

    fn estimate(&mut self, msg: &Estimate) -> Result<()> {
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&[msg.reward]);
        self.nums(&msg.x[..self.n]);
        self.nums(&msg.u_applied[..self.m]);
        self.write(
            self.estimate,
            t,
            self.t_estimate,
            msg.header.seq,
            &[msg.t_sample_ns, msg.t_received_ns, msg.t_publish_ns],
        )
    }

    /// Adds the channels of an external driver's samples and commands.
    fn add_driver(&mut self) -> Result<()> {
        let (n, m) = (self.n, self.m);
        let ints =
            |names: &[&str]| -> Vec<Field> { names.iter().map(|f| Field::integer(f)).collect() };
        let mut sample = ints(&["seq", "t_sample_ns", "status", "reset_id", "last_command"]);
        sample.extend(Field::array("x", n, FieldKind::Number));
        sample.extend(Field::array("u_applied", m, FieldKind::Number));
        sample.extend(ints(&["clamped", "rejected", "watchdog_trips"]));
        let mut command = ints(&["seq", "kind", "sample_seq", "t_publish_ns"]);
        command.extend(Field::array("u", m, FieldKind::Number));
        command.extend(Field::array("x0", n, FieldKind::Number));
        let s = self
            .rec
            .channel("/driver/sample", "rig.DriverSample", &sample)?;
        let c = self
            .rec
            .channel("/driver/command", "rig.DriverCommand", &command)?;
        self.driver = Some((s, c));
        Ok(())
    }

    fn driver_sample(&mut self, s: &DriverSample) -> Result<()> {
        let Some((ch, _)) = self.driver else {
            return Ok(());
        };
        self.values.clear();
        self.values
            .extend([s.seq, s.t_sample_ns, s.status, s.reset_id, s.last_command].map(Value::Int));
        self.nums(&s.x[..self.n]);
        self.nums(&s.u_applied[..self.m]);
        self.values
            .extend([s.clamped, s.rejected, s.watchdog_trips].map(Value::Int));
        self.rec
            .write(ch, s.t_sample_ns, s.t_sample_ns, &self.values)
    }

    fn driver_command(&mut self, c: &DriverCommand) -> Result<()> {
        let Some((_, ch)) = self.driver else {
            return Ok(());
        };
        self.values.clear();
        self.values
            .extend([c.seq, c.kind, c.sample_seq, c.t_publish_ns].map(Value::Int));
        self.nums(&c.u[..self.m]);
        self.nums(&c.x0[..self.n]);
        self.rec
            .write(ch, c.t_publish_ns, c.t_publish_ns, &self.values)
    }

    fn action(&mut self, msg: &Action) -> Result<()> {
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&msg.u[..self.m]);
        self.write(
            self.action,
            t,
            self.t_action,
            msg.header.seq,
            &[msg.t_sample_ns, msg.t_received_ns, msg.t_publish_ns],
        )
    }
}

/// Checks that a topic's sequence numbers arrive without gaps.
#[derive(Default)]
struct Continuity {
    next: u64,
}

impl Continuity {
    fn check(&mut self, topic: &str, seq: u64) -> Result<()> {
        if seq != self.next {
            bail!(
                "the recorder lost messages on {topic}: expected sample {}, got {seq}",
                self.next
            );
        }
        self.next = seq + 1;
        Ok(())
    }
}

/// The child processes; killed when dropped.
struct Children(Vec<(&'static str, Child)>);

impl Drop for Children {
    fn drop(&mut self) {
        for (_, c) in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn log_tail(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(5)..].join("\n")
}

/// Everything the supervision loop works on.
struct Supervisor {
    bus: Bus,
    measurements: wire::Rx<Measurement>,
    estimates: wire::Rx<Estimate>,
    actions: wire::Rx<Action>,
    /// The plant's ground truth, with a sensor that does not measure the full state.
    truths: Option<wire::Rx<Truth>>,
    /// Measurements drained, waiting for their ground truth to be drained too.
    batch: Vec<Measurement>,
    /// Ground truth drained ahead of its measurement.
    truth_queue: std::collections::VecDeque<Truth>,
    recording: Recording,
    returns: Returns,
    children: Children,
    out: PathBuf,
    messages: u64,
    continuity: [Continuity; 3],
    deadline_misses: u64,
    /// The external driver's traffic, recorded.
    driver: Option<DriverWatch>,
    /// Realtime and external driver: how long to go on recording after a process died,
    /// so that the recording shows the plant's reaction (its watchdog, or the driver's,
    /// applying the safe action within two periods).
    grace: Option<Duration>,
}

impl Supervisor {
    /// Records everything waiting; returns whether the run's end came by.
    fn drain(&mut self, bar: &ProgressBar) -> Result<bool> {
        let mut done = false;
        if let Some(a) = self
            .actions
            .recv_timeout(Duration::from_millis(2))
            .map_err(wire_err)?
        {
            done |= self.action(a)?;
        }
        while let Some(a) = self.actions.try_recv().map_err(wire_err)? {
            done |= self.action(a)?;
        }
        // The plant publishes a sample's ground truth before its measurement: drained
        // after the measurements, the truth of each of them is in.
        self.batch.clear();
        while let Some(m) = self.measurements.try_recv().map_err(wire_err)? {
            self.batch.push(m);
        }
        if let Some(t) = &self.truths {
            while let Some(x) = t.try_recv().map_err(wire_err)? {
                self.truth_queue.push_back(x);
            }
        }
        let batch = std::mem::take(&mut self.batch);
        for m in &batch {
            self.continuity[0].check(topic::MEASUREMENT, m.header.seq)?;
            self.deadline_misses = self.deadline_misses.max(m.deadline_misses);
            self.recording.measurement(m)?;
            self.messages += 1;
            if m.header.flags & flags::END != 0 {
                bar.inc(1);
            }
            let n = m.n_x as usize;
            // The rewards are the observer's: the estimates feed returns.csv.
            let estimated = m.header.flags & flags::ESTIMATED_REWARD != 0;
            if self.truths.is_some() && m.header.flags & flags::SHUTDOWN == 0 {
                let t = self
                    .truth_queue
                    .pop_front()
                    .filter(|t| t.header == m.header);
                let Some(t) = t else {
                    bail!(
                        "the recorder lost messages on {}: no ground truth for sample {}",
                        topic::TRUTH,
                        m.header.seq
                    );
                };
                self.recording.truth(&t)?;
                if !estimated {
                    self.returns.sample(&m.header, m.reward, &t.x[..n])?;
                }
            } else if !estimated {
                self.returns.sample(&m.header, m.reward, &m.y[..n])?;
            }
        }
        self.batch = batch;
        while let Some(e) = self.estimates.try_recv().map_err(wire_err)? {
            self.continuity[1].check(topic::ESTIMATE, e.header.seq)?;
            self.recording.estimate(&e)?;
            self.messages += 1;
            if e.header.flags & flags::ESTIMATED_REWARD != 0 {
                self.returns
                    .sample(&e.header, e.reward, &e.x[..e.n_x as usize])?;
            }
        }
        if let Some(d) = &self.driver {
            while d.info.try_recv().map_err(wire_err)?.is_some() {}
            while let Some(s) = d.samples.try_recv().map_err(wire_err)? {
                self.recording.driver_sample(&s)?;
            }
            while let Some(c) = d.commands.try_recv().map_err(wire_err)? {
                self.recording.driver_command(&c)?;
            }
        }
        Ok(done)
    }

    fn action(&mut self, a: Action) -> Result<bool> {
        self.continuity[2].check(topic::ACTION, a.header.seq)?;
        self.recording.action(&a)?;
        self.messages += 1;
        Ok(a.header.flags & flags::SHUTDOWN != 0)
    }

    /// A process that has exited, if any: its role, exit status and log file.
    fn exited(&mut self) -> Result<Option<(&'static str, std::process::ExitStatus, PathBuf)>> {
        for (role, child) in &mut self.children.0 {
            if let Some(status) = child.try_wait()? {
                return Ok(Some((*role, status, self.out.join(format!("{role}.log")))));
            }
        }
        Ok(None)
    }

    /// Of the processes that have exited, the one that caused the others to: killed by a
    /// signal rather than stopped by an error (a process whose peer dies stops with one).
    fn cause(&mut self) -> Result<(&'static str, std::process::ExitStatus, PathBuf)> {
        use std::os::unix::process::ExitStatusExt;
        let mut first = None;
        for (role, child) in &mut self.children.0 {
            if let Some(status) = child.try_wait()? {
                let found = (*role, status, self.out.join(format!("{role}.log")));
                if status.signal().is_some() {
                    return Ok(found);
                }
                first.get_or_insert(found);
            }
        }
        first.ok_or_else(|| anyhow!("a process exited and could not be found again"))
    }

    /// Waits for every process to exit after the end of the run.
    fn reap(&mut self) -> Result<()> {
        let deadline = Instant::now() + Duration::from_secs(10);
        for (role, child) in &mut self.children.0 {
            loop {
                if let Some(status) = child.try_wait()? {
                    if !status.success() {
                        let log = self.out.join(format!("{role}.log"));
                        bail!(
                            "the {role} process failed ({status}); last lines of {}:\n{}",
                            log.display(),
                            log_tail(&log)
                        );
                    }
                    break;
                }
                if Instant::now() > deadline {
                    bail!("the {role} process did not exit after the end of the run");
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
        self.children.0.clear();
        Ok(())
    }

    /// How far the run got, and how to continue it.
    fn resume_hint(&self) -> String {
        format!(
            "{} completed trials are in returns.csv; continue with `rig run --resume {}`",
            self.returns.records.len(),
            self.out.display()
        )
    }

    fn supervise(&mut self, bar: &ProgressBar) -> Result<()> {
        loop {
            if self.drain(bar)? {
                break;
            }
            if self.bus.interrupted() {
                bail!(
                    "interrupted: stopped the plant, observer and agent processes; {}",
                    self.resume_hint()
                );
            }
            if let Some((_, status, _)) = self.exited()? {
                // A process that ends cleanly after its last message can be seen to exit
                // before that message is read: look once more.
                if status.success() && self.drain(bar)? {
                    break;
                }
                // Go on recording for a while: the plant's reaction (realtime), and the
                // peers' exits, to tell the cause from its consequences.
                let end = Instant::now() + self.grace.unwrap_or_default().max(CAUSE_WINDOW);
                let mut done = false;
                while Instant::now() < end {
                    // Errors here are consequences of the death reported below.
                    match self.drain(bar) {
                        Ok(false) => {}
                        Ok(true) => {
                            done = true;
                            break;
                        }
                        Err(_) => break,
                    }
                }
                if done && self.cause().is_ok_and(|(_, s, _)| s.success()) {
                    // The run's end came after all: processes exit as it passes.
                    break;
                }
                let (role, status, log) = self.cause()?;
                bail!(
                    "the {role} process exited ({status}) before the run finished; {}; last lines of {}:\n{}",
                    self.resume_hint(),
                    log.display(),
                    log_tail(&log)
                );
            }
        }
        self.reap()?;
        self.returns.flush()
    }
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
