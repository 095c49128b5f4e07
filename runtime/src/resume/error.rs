//! Why a run cannot be resumed, or its checkpoints not written.

use std::path::PathBuf;

use agent::checkpoint::CheckpointError;

use crate::error::FileError;
use crate::resumable::ResumeError;

/// Why `rig run --resume DIR` refuses a folder ([`super::prepare`]).
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    /// Every trial asked for is done.
    #[error(
        "{}: all {trials} trials of the run are done; nothing to resume (pass `--trials N` with N > {done} to learn on)",
        dir.display()
    )]
    Done {
        /// The run folder.
        dir: PathBuf,
        /// The trials asked for.
        trials: u32,
        /// Rows of `returns.csv`.
        done: u32,
    },
    /// Not even trial 0's start is in the recording.
    #[error("{}: the recording holds no complete trial", dir.display())]
    NoCompleteTrial {
        /// The run folder.
        dir: PathBuf,
    },
    /// A sensor or observer other than the defaults: its state is in no checkpoint.
    #[error(
        "{}: cannot resume a run with `[observer]` sensor {sensor} / observer {observer}: checkpoints hold the agent's state only, not the observer's (its learned model, its filter) nor the sensor's noise stream; start a new run",
        config.display()
    )]
    Observer {
        /// The run's `config.toml`.
        config: PathBuf,
        /// Its sensor.
        sensor: String,
        /// Its observer.
        observer: String,
    },
    /// The run's configuration cannot continue mid-run (delays from a file).
    #[error("{}: {why}", config.display())]
    Config {
        /// The run's `config.toml`.
        config: PathBuf,
        /// Why.
        why: ResumeError,
    },
    /// The newest checkpoint cannot be read.
    #[error("cannot resume: {why}{}", fallback.map_or(String::new(), |t| format!("; remove it to resume from the checkpoint of trial {t}")))]
    Unreadable {
        /// The checkpoint's error.
        why: CheckpointError,
        /// An older checkpoint to resume from instead.
        fallback: Option<u32>,
    },
    /// The checkpoint is of another experiment.
    #[error("cannot resume from {}: {why}", path.display())]
    Foreign {
        /// The checkpoint.
        path: PathBuf,
        /// How it differs.
        why: CheckpointError,
    },
    /// The checkpoint is of another trial or instant than `returns.csv` says.
    #[error(
        "cannot resume: {} is of trial {trial} at {sim_time_s} s, but returns.csv has trial {rows_trial} at {rows_time_s} s",
        path.display()
    )]
    Elsewhere {
        /// The checkpoint.
        path: PathBuf,
        /// Its trial.
        trial: u32,
        /// Its simulated time, s.
        sim_time_s: f64,
        /// The trial `returns.csv` ends with.
        rows_trial: u32,
        /// Its simulated time, s.
        rows_time_s: f64,
    },
    /// `returns.csv` cannot be read.
    #[error("{}: cannot read (is this a `rig run` directory?)", path.display())]
    NoReturns {
        /// `DIR/returns.csv`.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A row of `returns.csv` is not what the rig writes.
    #[error("{}:{line}: {why}", path.display())]
    Row {
        /// `DIR/returns.csv`.
        path: PathBuf,
        /// Its line number.
        line: usize,
        /// What is wrong.
        why: String,
    },
    /// The recording cannot be read.
    #[error("{}: cannot read the run's recording, so the recorded trials cannot be kept", path.display())]
    NoRecording {
        /// `DIR/run.mcap` or `DIR/run.mcap.part`.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The recording is not an MCAP file.
    #[error("{}: not an MCAP recording", path.display())]
    NotMcap {
        /// `DIR/run.mcap` or `DIR/run.mcap.part`.
        path: PathBuf,
        /// The reader's error.
        #[source]
        source: mcap::McapError,
    },
    /// A recorded message of the loop cannot be decoded.
    #[error("run.mcap: unreadable message on {topic}")]
    Message {
        /// Its topic.
        topic: String,
        /// The decoder's error.
        #[source]
        source: serde_json::Error,
    },
    /// The run was made on another plant than the resumed part would run on.
    #[error("{}", if *external {
        format!("{} was run against an external driver; resume it with `--plant external` and the same `--driver`", dir.display())
    } else {
        format!("{} was run with the simulated plant; resume it without `--plant external`", dir.display())
    })]
    OtherPlant {
        /// The run folder.
        dir: PathBuf,
        /// Whether the recorded run was against an external driver.
        external: bool,
    },
}

/// Why a checkpoint could not be written ([`super::CheckpointWriter`]).
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// A file could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The checkpoints' folder is another command's.
    #[error(transparent)]
    Lock(#[from] crate::lock::LockError),
    /// The writer's thread panicked.
    #[error("the checkpoint writer panicked")]
    Panicked,
}
