//! `rig replay`: the observer and the agent run again, in one process, over a
//! recording's measurements, and reproduce its estimates and actions bit for bit.
//!
//! Everything they consume comes from the run folder's `run.mcap` ([`Recording`]):
//!
//! - the configuration attached (`config.toml`): the task, the learner, the observer and
//!   its timing, the seed — the agent's random streams derive from it, run 0 (`rig run`
//!   runs run 0 of its configuration);
//! - the measurements: what the plant's sensor gave, with the actions applied and when
//!   (`u_applied`, `u_next`), so neither the plant's timing (lockstep, real time, a
//!   driver's clock), nor its delays, nor its sensor noise need to be known again;
//! - a resumed run's recording holds the whole run (the kept trials are copied into
//!   it), so a replay starts at its first sample, from a fresh agent, and passes the
//!   checkpoints the resumed parts started from as the uninterrupted run did.
//!
//! Each measurement goes through the observer process's step
//! ([`crate::process::observer::estimate`]) and the estimate through the agent process's
//! ([`crate::process::agent::AgentNode::action`]); each result is compared with the
//! recorded message of the same sequence number, field by field and bit for bit
//! ([`compare`]). The first difference ends the replay. [`observers`] runs another
//! observer over the same measurements (`rig replay --observer`).

use std::path::PathBuf;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::error::chain;
use crate::process::agent::AgentNode;

pub mod compare;
pub mod observers;
pub mod recording;

use crate::record::channels::{ACTION, ESTIMATE};
pub use compare::Difference;
pub use recording::Recording;

/// The recording format `rig run` writes (metadata `recording_format`) and `rig replay`
/// reads: the loop's channels with `rig.Measurement.v4`'s fields (`u_next`, `delay_s`),
/// the configuration attached, everything the observer and the agent consume recorded or
/// derived from it. Recordings without the key are read when their fields are these.
pub const FORMAT: u32 = 2;

/// Why a recording cannot be replayed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The folder has no recording.
    #[error("{}: no such recording (is this the folder of a `rig run`?)", path.display())]
    NoRecording {
        /// `DIR/run.mcap`.
        path: PathBuf,
    },
    /// The run did not finish: only `run.mcap.part` is there.
    #[error(
        "{}: the run did not finish (only run.mcap.part is there); finish it with `rig run --resume {0}`, then replay it",
        dir.display()
    )]
    Unfinished {
        /// The run folder.
        dir: PathBuf,
    },
    /// The file cannot be read.
    #[error("{}: cannot read: {cause}", path.display())]
    Io {
        /// The recording.
        path: PathBuf,
        /// The operating system's words.
        cause: String,
    },
    /// Not a recording of `rig run`.
    #[error("{}: not a recording of `rig run`: {why}", path.display())]
    Foreign {
        /// The recording.
        path: PathBuf,
        /// What is missing.
        why: String,
    },
    /// A recording of another format.
    #[error("{}: recorded in {found}; rig replay reads recording format {FORMAT} (metadata recording_format = {FORMAT}, rig.Measurement.v4)", path.display())]
    Format {
        /// The recording.
        path: PathBuf,
        /// What it is.
        found: String,
    },
    /// A message that cannot be decoded.
    #[error("{}: message {index} ({topic}) is unreadable: {cause}", path.display())]
    Unreadable {
        /// The recording.
        path: PathBuf,
        /// Its topic.
        topic: String,
        /// Its index in the file.
        index: usize,
        /// Why.
        cause: String,
    },
    /// The configuration attached does not resolve.
    #[error("{0}")]
    Config(String),
    /// The agent refused a replayed estimate.
    #[error("the agent stopped at sample seq {seq}: {cause}")]
    Agent {
        /// The sample.
        seq: u64,
        /// Its words.
        cause: String,
    },
}

/// How a replay ended.
#[derive(Debug, PartialEq)]
pub enum ReplayEnd {
    /// Every estimate and action replayed as recorded.
    Identical {
        /// The messages compared, per topic.
        counts: Vec<(&'static str, usize)>,
    },
    /// The first difference.
    Differs(Difference),
}

/// A progress bar of `samples` samples on standard error, or a hidden one.
pub fn progress_bar(samples: u64, shown: bool) -> ProgressBar {
    let target = if shown {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(samples), target);
    bar.set_style(
        ProgressStyle::with_template("replay [{bar:40}] {pos}/{len} samples, eta {eta}")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    bar
}

/// Replays `rec`'s observer and agent over its measurements, counting samples on
/// `progress`; stops at the first difference.
pub fn replay(rec: &Recording, progress: &ProgressBar) -> Result<ReplayEnd, ReplayError> {
    let cfg = &rec.cfg;
    let task = cfg.task();
    let (n, m) = (task.state_dim(), task.action_dim());
    let mut front = crate::build::front(&task, cfg);
    let mut learner =
        AgentNode::new(cfg, 0, None, None).map_err(|e| ReplayError::Config(chain(&e)))?;
    for x in &rec.measurements {
        progress.inc(1);
        let e = crate::process::observer::estimate(&mut front, x);
        let Some(recorded) = rec.estimates.get(&x.header.seq) else {
            return Ok(ReplayEnd::Differs(Difference::missing(
                ESTIMATE, &e.header, false,
            )));
        };
        if let Some(d) = compare::estimate(ESTIMATE, recorded, &e, n, m) {
            return Ok(ReplayEnd::Differs(d));
        }
        let a = learner
            .action(&e, false)
            .map_err(|err| ReplayError::Agent {
                seq: e.header.seq,
                cause: chain(&err),
            })?;
        let Some(recorded) = rec.actions.get(&x.header.seq) else {
            return Ok(ReplayEnd::Differs(Difference::missing(
                ACTION, &a.header, false,
            )));
        };
        if let Some(d) = compare::action(ACTION, recorded, &a, m) {
            return Ok(ReplayEnd::Differs(d));
        }
    }
    Ok(unmatched(rec).map_or_else(
        || ReplayEnd::Identical {
            counts: vec![(ESTIMATE, rec.estimates.len()), (ACTION, rec.actions.len())],
        },
        ReplayEnd::Differs,
    ))
}

/// A recorded estimate or action of a sample that was never measured.
fn unmatched(rec: &Recording) -> Option<Difference> {
    let measured: std::collections::BTreeSet<u64> =
        rec.measurements.iter().map(|x| x.header.seq).collect();
    if let Some(e) = rec
        .estimates
        .values()
        .find(|e| !measured.contains(&e.header.seq))
    {
        return Some(Difference::missing(ESTIMATE, &e.header, true));
    }
    rec.actions
        .values()
        .find(|a| !measured.contains(&a.header.seq))
        .map(|a| Difference::missing(ACTION, &a.header, true))
}
