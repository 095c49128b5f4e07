//! Resuming a rig run after a crash: `rig run --resume DIR`.
//!
//! While a run goes on, the agent process writes a checkpoint of its learned state at the
//! end of every learning trial ([`agent::checkpoint`], `DIR/checkpoints/trial-NNNNNN.ckpt`,
//! atomically, from a background thread so the control loop never waits for the disk),
//! and the supervisor removes those no resume can need (every one older than the newest
//! checkpoint of a trial complete in `returns.csv` and in the recording written out
//! so far). To resume, [`prepare`] picks the latest trial
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
//! interrupted. A run is done only when its last trial is complete everywhere: one whose
//! last checkpoints were never written (a full disk) has every row of `returns.csv` and
//! still redoes the trials after its newest checkpoint.

use std::path::{Path, PathBuf};

use agent::checkpoint::Checkpoint;

use crate::config::ExperimentConfig;
use crate::experiment::TrialRecord;

mod checkpoints;
mod error;
mod recorded;

pub use crate::record::reader::RecordedMessage;
pub use checkpoints::{
    CheckpointWriter, checkpoint_dir, checkpoint_path, checkpoints, discard_after,
    keep_from_newest, prune,
};
pub use error::{PrepareError, WriteError};
use recorded::{RecordingIndex, index, kept, read_recording, read_returns, same_plant};

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

/// traffic, `/driver/...`, exactly when the run was made against one).
/// Decides where run directory `out` (configuration `cfg`, whose `run.trials` may exceed
/// the original) continues; see the module documentation.
///
/// A run with a sensor or observer other than the defaults cannot be resumed: a
/// checkpoint holds the agent's state only, not the observer's (a learned model, a
/// velocity filter) nor where the sensor's noise stream stands. Nor can a run continue on
/// another plant than it was made on: `external` says whether the resumed part runs
/// against an external driver, and must match the recording (which holds the driver's
pub fn prepare(
    out: &Path,
    cfg: &ExperimentConfig,
    external: bool,
) -> Result<ResumePoint, PrepareError> {
    resumable(out, cfg)?;
    let mut notes = Vec::new();
    let rows = read_returns(&out.join("returns.csv"), &mut notes)?;
    let done = rows.len() as u32;
    let messages = read_recording(out, &mut notes)?;
    let dir = checkpoint_dir(out);
    let available = checkpoints(&dir);
    let (c, first_seq) = last_complete_trial(cfg, &available, done, &index(&messages)?)
        .ok_or_else(|| PrepareError::NoCompleteTrial {
            dir: out.to_path_buf(),
        })?;
    // Done only when complete everywhere: a run stopped as its last checkpoint failed
    // has every row but must redo the trials after its newest checkpoint.
    if c >= cfg.run().trials {
        return Err(PrepareError::Done {
            dir: out.to_path_buf(),
            trials: cfg.run().trials,
            done,
        });
    }
    same_plant(out, &messages, external)?;
    let checkpoint = (c > 0).then(|| checkpoint_path(&dir, c));
    let sim_time_s = if c > 0 {
        rows[c as usize - 1].sim_time_s
    } else {
        0.0
    };
    if let Some(path) = &checkpoint {
        check_checkpoint(path, cfg, (c, sim_time_s), &available)?;
    }
    if c < done {
        notes.push(format!(
            "trials {}..={done} are redone: the last trial complete in the checkpoints and the recording is {c}",
            c + 1
        ));
    }
    Ok(ResumePoint {
        trial: c,
        sim_time_s,
        first_seq,
        checkpoint,
        records: rows[..c as usize].to_vec(),
        messages: kept(messages, first_seq, c),
        notes,
    })
}

/// Refuses a run whose state a checkpoint does not hold all of: an observer or sensor
/// other than the defaults, or delays that cannot continue mid-run.
fn resumable(out: &Path, cfg: &ExperimentConfig) -> Result<(), PrepareError> {
    let config = out.join("config.toml");
    if !cfg.observer().is_default() {
        return Err(PrepareError::Observer {
            config,
            sensor: cfg.observer().sensor.to_string(),
            observer: cfg.observer().observer.to_string(),
        });
    }
    crate::resumable::resumable_delays(cfg).map_err(|why| PrepareError::Config { config, why })
}

/// The last trial, at most `done`, that has a checkpoint (`available`; trial 0 needs
/// none) and whose end, with its greedy evaluations, is complete in the recording; with
/// the sequence number of the sample after it.
fn last_complete_trial(
    cfg: &ExperimentConfig,
    available: &[u32],
    done: u32,
    recorded: &RecordingIndex,
) -> Option<(u32, u64)> {
    let starts = cfg.task().initial_states.len();
    let evals = |t: u32| {
        if cfg.run().eval_every > 0 && t.is_multiple_of(cfg.run().eval_every) {
            starts
        } else {
            0
        }
    };
    available
        .iter()
        .copied()
        .filter(|&t| t <= done)
        .rev()
        .chain(std::iter::once(0))
        .find_map(|c| recorded.end_of(c, evals(c)).map(|q| (c, q)))
}

/// Checks that the checkpoint at `path` is of this experiment and of trial `c` ending at
/// simulated time `sim_time_s`, as `returns.csv` says — the same instant within half a
/// sample period: the agent stamps it as the trial's start plus its samples, returns.csv
/// as whole trials less the samples not run, which round differently when trials end
/// early; names an older one of `available` to fall back to when it cannot be read.
fn check_checkpoint(
    path: &Path,
    cfg: &ExperimentConfig,
    (c, sim_time_s): (u32, f64),
    available: &[u32],
) -> Result<(), PrepareError> {
    let ck = Checkpoint::read(path).map_err(|why| PrepareError::Unreadable {
        why,
        fallback: available.iter().rev().find(|&&t| t < c).copied(),
    })?;
    ck.check_origin(&cfg.origin(0))
        .map_err(|why| PrepareError::Foreign {
            path: path.to_path_buf(),
            why,
        })?;
    let apart = (ck.sim_time_s - sim_time_s).abs();
    if ck.trial != c || apart.is_nan() || apart >= 0.5 * cfg.task().ts {
        return Err(PrepareError::Elsewhere {
            path: path.to_path_buf(),
            trial: ck.trial,
            sim_time_s: ck.sim_time_s,
            rows_trial: c,
            rows_time_s: sim_time_s,
        });
    }
    Ok(())
}
