//! Resuming a rig run after a crash: `rig run --resume DIR`.
//!
//! While a run goes on, the agent process writes a checkpoint of its learned state at the
//! end of every learning trial ([`agent::checkpoint`], `DIR/checkpoints/trial-NNNNNN.ckpt`,
//! atomically, from a background thread so the control loop never waits for the disk),
//! and the supervisor keeps the last two. To resume, [`prepare`] picks the latest trial
//! `C` that is complete everywhere:
//!
//! * `returns.csv` has its row (a row is written only when the trial and its greedy
//!   evaluations are complete),
//! * its checkpoint exists (a corrupt one, or one from another configuration, is an
//!   error, not skipped),
//! * `run.mcap` (or the `run.mcap.part` a killed supervisor leaves) holds every message up
//!   to the end of that trial's evaluations, without gaps.
//!
//! The new run keeps rows `1..=C` and every message up to the end of trial `C` (copied
//! into the new `run.mcap`), and continues with trial `C + 1` from the checkpoint: the
//! plant starts there with the simulated time and the sequence numbers continuing, the
//! agent restores its state. In lockstep the result is bit for bit that of a run never
//! interrupted.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread::JoinHandle;

use agent::checkpoint::Checkpoint;
use anyhow::{Context, Result, anyhow, bail};
use serde::Deserialize;
use wire::flags;

use crate::config::ExperimentConfig;
use crate::experiment::TrialRecord;

/// The checkpoint directory of run directory `out`.
pub fn checkpoint_dir(out: &Path) -> PathBuf {
    out.join("checkpoints")
}

/// The checkpoint file of `trial` in checkpoint directory `dir`.
pub fn checkpoint_path(dir: &Path, trial: u32) -> PathBuf {
    dir.join(format!("trial-{trial:06}.ckpt"))
}

/// The trials of the checkpoint files in `dir`, ascending.
pub fn checkpoints(dir: &Path) -> Vec<u32> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut trials: Vec<u32> = entries
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.strip_prefix("trial-")?
                .strip_suffix(".ckpt")?
                .parse()
                .ok()
        })
        .collect();
    trials.sort_unstable();
    trials
}

/// Removes the checkpoints of trials before `trial`.
pub fn prune(dir: &Path, trial: u32) {
    for t in checkpoints(dir) {
        if t < trial {
            let _ = std::fs::remove_file(checkpoint_path(dir, t));
        }
    }
}

/// Writes checkpoints on a background thread (atomically: [`Checkpoint::write`]) and keeps
/// the two newest. When the disk is slower than the trials, checkpoints queued behind the
/// one being written are skipped, except the newest: the loop never waits, and a resume
/// redoes the few trials after the newest checkpoint written.
pub struct CheckpointWriter {
    tx: Option<mpsc::Sender<Checkpoint>>,
    thread: Option<JoinHandle<Result<()>>>,
}

impl CheckpointWriter {
    /// A writer into `dir` (created if missing).
    pub fn new(dir: &Path) -> Result<Self> {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let (tx, rx) = mpsc::channel::<Checkpoint>();
        let dir = dir.to_owned();
        let thread = std::thread::spawn(move || -> Result<()> {
            let mut previous = None;
            while let Ok(mut c) = rx.recv() {
                // Only the newest of those waiting.
                if let Some(newer) = rx.try_iter().last() {
                    c = newer;
                }
                let path = checkpoint_path(&dir, c.trial);
                c.write(&path)
                    .with_context(|| format!("cannot write checkpoint {}", path.display()))?;
                if let Some(p) = previous.replace(c.trial) {
                    prune(&dir, p);
                }
            }
            Ok(())
        });
        Ok(Self {
            tx: Some(tx),
            thread: Some(thread),
        })
    }

    /// Queues checkpoint `c` (of trial `c.trial`); fails if an earlier write failed.
    pub fn save(&mut self, c: Checkpoint) -> Result<()> {
        let sent = self.tx.as_ref().is_some_and(|tx| tx.send(c).is_ok());
        if !sent {
            return self.finish();
        }
        Ok(())
    }

    /// Waits until every queued checkpoint is written.
    pub fn finish(&mut self) -> Result<()> {
        drop(self.tx.take());
        match self.thread.take() {
            Some(t) => t
                .join()
                .map_err(|_| anyhow!("the checkpoint writer panicked"))?,
            None => Ok(()),
        }
    }
}

/// One message of a recording, as stored.
pub struct RecordedMessage {
    /// Its topic.
    pub topic: String,
    /// Log time \[ns\].
    pub log_time: u64,
    /// Publish time \[ns\].
    pub publish_time: u64,
    /// The JSON message.
    pub data: Vec<u8>,
}

/// Where a resumed run continues, and what it keeps.
pub struct ResumePoint {
    /// The last trial kept (0: none; the run starts afresh).
    pub trial: u32,
    /// Simulated learning time at its end \[s\].
    pub sim_time_s: f64,
    /// Sequence number of the first new sample.
    pub first_seq: u64,
    /// The checkpoint to restore (none when `trial` is 0).
    pub checkpoint: Option<PathBuf>,
    /// The rows of `returns.csv` kept.
    pub records: Vec<TrialRecord>,
    /// The recorded messages kept, in file order.
    pub messages: Vec<RecordedMessage>,
    /// Notes for the user (a recording recovered from a `.part` file, trials redone).
    pub notes: Vec<String>,
}

/// The header fields of a recorded run message.
#[derive(Deserialize)]
struct Head {
    seq: u64,
    #[serde(default)]
    trial: u64,
    #[serde(default)]
    flags: u64,
}

/// Reads the rows of a `returns.csv`.
fn read_returns(path: &Path) -> Result<Vec<TrialRecord>> {
    let mut reader = csv::Reader::from_path(path).with_context(|| {
        format!(
            "{}: cannot read (is this a `rig run` directory?)",
            path.display()
        )
    })?;
    let mut rows = Vec::new();
    for (i, rec) in reader.records().enumerate() {
        let line = i + 2;
        let rec = rec.with_context(|| format!("{}:{line}: unreadable row", path.display()))?;
        let field = |j: usize| rec.get(j).unwrap_or("");
        let num = |j: usize| -> Result<f64> {
            field(j)
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    anyhow!(
                        "{}:{line}: column {} is not a number: {:?}",
                        path.display(),
                        j + 1,
                        field(j)
                    )
                })
        };
        let trial: u32 = field(1).parse().map_err(|_| {
            anyhow!(
                "{}:{line}: trial {:?} is not a trial number",
                path.display(),
                field(1)
            )
        })?;
        if trial as usize != rows.len() + 1 {
            bail!(
                "{}:{line}: trial {trial} where trial {} was expected: the file was edited",
                path.display(),
                rows.len() + 1
            );
        }
        rows.push(TrialRecord {
            run: 0,
            trial,
            sim_time_s: num(2)?,
            ret: num(3)?,
            greedy: if field(4).is_empty() {
                None
            } else {
                Some(num(4)?)
            },
        });
    }
    Ok(rows)
}

/// Reads every message of the recording in `out` that can be read: `run.mcap`, or the
/// `run.mcap.part` a killed supervisor leaves (its completed chunks).
fn read_recording(out: &Path, notes: &mut Vec<String>) -> Result<Vec<RecordedMessage>> {
    let full = out.join("run.mcap");
    let part = out.join("run.mcap.part");
    let path = if full.exists() { full } else { part };
    let bytes = std::fs::read(&path).with_context(|| {
        format!(
            "{}: cannot read the run's recording, so the recorded trials cannot be kept",
            path.display()
        )
    })?;
    let mut messages = Vec::new();
    for m in mcap::MessageStream::new(&bytes)? {
        match m {
            Ok(m) => messages.push(RecordedMessage {
                topic: m.channel.topic.clone(),
                log_time: m.log_time,
                publish_time: m.publish_time,
                data: m.data.into_owned(),
            }),
            Err(e) => {
                notes.push(format!(
                    "{} ends in an unfinished chunk ({e}); kept the {} messages before it",
                    path.display(),
                    messages.len()
                ));
                break;
            }
        }
    }
    Ok(messages)
}

/// Refuses to continue a run on another plant than it was made on: a hardware run
/// finished in the simulator (or the reverse) would mix two systems in one learning
/// curve.
fn same_plant(out: &Path, messages: &[RecordedMessage], external: bool) -> Result<()> {
    let recorded = messages.iter().any(|m| m.topic.starts_with("/driver/"));
    match (recorded, external) {
        (true, false) => bail!(
            "{} was run against an external driver; resume it with `--plant external` and the same `--driver`",
            out.display()
        ),
        (false, true) => bail!(
            "{} was run with the simulated plant; resume it without `--plant external`",
            out.display()
        ),
        _ => Ok(()),
    }
}

/// What the recording holds, per learning trial.
struct Recorded {
    /// Per main topic, the sequence numbers present.
    seqs: [BTreeSet<u64>; 3],
    /// `(seq, trial, flags)` of every measurement, in file order.
    measurements: Vec<(u64, u64, u64)>,
}

const MAIN: [&str; 3] = ["/plant/measurement", "/observer/estimate", "/agent/action"];

fn index(messages: &[RecordedMessage]) -> Result<Recorded> {
    let mut r = Recorded {
        seqs: Default::default(),
        measurements: Vec::new(),
    };
    for m in messages {
        let Some(i) = MAIN.iter().position(|t| *t == m.topic) else {
            continue;
        };
        let h: Head = serde_json::from_slice(&m.data)
            .with_context(|| format!("run.mcap: unreadable message on {}", m.topic))?;
        r.seqs[i].insert(h.seq);
        if i == 0 {
            r.measurements.push((h.seq, h.trial, h.flags));
        }
    }
    Ok(r)
}

impl Recorded {
    /// The first sequence number after trial `c` and its evaluations, if the recording
    /// holds all of them: every sample up to there on all three topics, and the ends of
    /// the learning trial and of its `evals` greedy trials.
    fn end_of(&self, c: u32, evals: usize) -> Option<u64> {
        let c = u64::from(c);
        let inside = |&&(_, t, f): &&(u64, u64, u64)| t <= c && f & flags::SHUTDOWN == 0;
        let q = self
            .measurements
            .iter()
            .filter(inside)
            .map(|m| m.0 + 1)
            .max()
            .unwrap_or(0);
        let ends = self
            .measurements
            .iter()
            .filter(|&&(_, t, f)| t == c && f & flags::END != 0 && f & flags::SHUTDOWN == 0)
            .count();
        let complete = self.seqs.iter().all(|s| s.range(..q).count() as u64 == q);
        (c == 0 || ends == 1 + evals)
            .then_some(q)
            .filter(|_| complete)
    }
}

/// Decides where run directory `out` (configuration `cfg`, whose `run.trials` may exceed
/// the original) continues; see the module documentation.
///
/// A run with a sensor or observer other than the defaults cannot be resumed: a
/// checkpoint holds the agent's state only, not the observer's (a learned model, a
/// velocity filter) nor where the sensor's noise stream stands. Nor can a run continue on
/// another plant than it was made on: `external` says whether the resumed part runs
/// against an external driver, and must match the recording (which holds the driver's
/// traffic, `/driver/...`, exactly when the run was made against one).
pub fn prepare(out: &Path, cfg: &ExperimentConfig, external: bool) -> Result<ResumePoint> {
    if !cfg.observer.is_default() {
        bail!(
            "{}: cannot resume a run with `[observer]` sensor {} / observer {}: checkpoints hold the agent's state only, not the observer's (its learned model, its filter) nor the sensor's noise stream; start a new run",
            out.join("config.toml").display(),
            cfg.observer.sensor,
            cfg.observer.observer
        );
    }
    crate::experiment::resumable_delays(cfg)
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.join("config.toml").display()))?;
    let mut notes = Vec::new();
    let rows = read_returns(&out.join("returns.csv"))?;
    let done = rows.len() as u32;
    if done >= cfg.run.trials {
        bail!(
            "{}: all {} trials of the run are done; nothing to resume (pass `--trials N` with N > {done} to learn on)",
            out.display(),
            cfg.run.trials
        );
    }
    let messages = read_recording(out, &mut notes)?;
    same_plant(out, &messages, external)?;
    let recorded = index(&messages)?;
    let dir = checkpoint_dir(out);
    let starts = plant::Task::new(cfg.system).initial_states.len();
    let evals = |t: u32| {
        if cfg.run.eval_every > 0 && t.is_multiple_of(cfg.run.eval_every) {
            starts
        } else {
            0
        }
    };
    let available = checkpoints(&dir);
    let candidates = available
        .iter()
        .copied()
        .filter(|&t| t <= done)
        .rev()
        .chain(std::iter::once(0));
    let mut chosen = None;
    for c in candidates {
        if let Some(q) = recorded.end_of(c, evals(c)) {
            chosen = Some((c, q));
            break;
        }
    }
    let (c, first_seq) = chosen
        .ok_or_else(|| anyhow!("{}: the recording holds no complete trial", out.display()))?;
    let checkpoint = (c > 0).then(|| checkpoint_path(&dir, c));
    let sim_time_s = if c > 0 {
        rows[c as usize - 1].sim_time_s
    } else {
        0.0
    };
    if let Some(path) = &checkpoint {
        let ck = Checkpoint::read(path).map_err(|e| {
            let older = available.iter().rev().find(|&&t| t < c);
            match older {
                Some(t) => anyhow!(
                    "cannot resume: {e}; remove it to resume from the checkpoint of trial {t}"
                ),
                None => anyhow!("cannot resume: {e}"),
            }
        })?;
        ck.check_origin(&cfg.origin(0))
            .map_err(|e| anyhow!("cannot resume from {}: {e}", path.display()))?;
        if ck.trial != c || ck.sim_time_s.to_bits() != sim_time_s.to_bits() {
            bail!(
                "cannot resume: {} is of trial {} at {} s, but returns.csv has trial {c} at {sim_time_s} s",
                path.display(),
                ck.trial,
                ck.sim_time_s
            );
        }
    }
    if c < done {
        notes.push(format!(
            "trials {}..={done} are redone: the last trial complete in the checkpoints and the recording is {c}",
            c + 1
        ));
    }
    let last_log_time = messages
        .iter()
        .filter(|m| m.topic == MAIN[0])
        .filter_map(|m| {
            let h: Head = serde_json::from_slice(&m.data).ok()?;
            (h.seq < first_seq).then_some(m.log_time)
        })
        .max()
        .unwrap_or(0);
    let keep = |m: &RecordedMessage| -> bool {
        let head = || serde_json::from_slice::<Head>(&m.data).ok();
        if MAIN.contains(&m.topic.as_str()) {
            head().is_some_and(|h| h.seq < first_seq && h.flags & flags::SHUTDOWN == 0)
        } else if m.topic.starts_with("/timing/") {
            head().is_some_and(|h| h.seq < first_seq)
        } else {
            first_seq > 0 && m.log_time <= last_log_time
        }
    };
    let messages = messages.into_iter().filter(keep).collect();
    Ok(ResumePoint {
        trial: c,
        sim_time_s,
        first_seq,
        checkpoint,
        records: rows[..c as usize].to_vec(),
        messages,
        notes,
    })
}
