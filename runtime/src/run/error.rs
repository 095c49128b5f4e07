//! Why `rig run` stopped or was refused: each message names the process, the topic or
//! the file, and says how far the run got and how to continue it.

use std::process::ExitStatus;

use crate::clock::ClockError;
use crate::error::{FileError, chain};
use crate::lock::LockError;
use crate::process::SystemError;
use crate::process::node::SettingsError;
use crate::record::RecordError;
use crate::resume::PrepareError;

/// The result of the run's steps.
pub(super) type Result<T, E = RunError> = std::result::Result<T, E>;

/// Why a run was refused, or stopped before its end.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The clock does not fit the configuration or the waiting.
    #[error(transparent)]
    Clock(#[from] ClockError),
    /// The output folder is another command's.
    #[error(transparent)]
    Lock(#[from] LockError),
    /// A run to resume cannot be continued.
    #[error(transparent)]
    Resume(#[from] PrepareError),
    /// An output file could not be created or written.
    #[error(transparent)]
    File(#[from] FileError),
    /// A process's settings could not be written.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The recording could not be written.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The transport failed.
    #[error(transparent)]
    Wire(#[from] wire::Error),
    /// The external driver did not answer, or does not fit the task.
    #[error(transparent)]
    Driver(#[from] driver::Error),
    /// The processes could not be placed or prioritised.
    #[error(transparent)]
    System(#[from] SystemError),
    /// A child process could not be waited for.
    #[error(transparent)]
    Wait(#[from] std::io::Error),
    /// Another run of this id is going on.
    #[error(
        "run id {run_id:?} is in use by a run that is going on (its {running} running); choose another --run-id"
    )]
    RunIdInUse {
        /// The run id.
        run_id: String,
        /// Its processes that run, in words ("plant process is", "plant, agent processes are").
        running: String,
    },
    /// The learner needs the reward's gradient, which the driver does not give.
    #[error(
        "--algo {algo} needs the reward's gradient ∂ρ/∂u, but driver {id:?} (task {task:?}) provides its own reward as numbers: use an actor-critic (--algo sac, mlac or rmac) or serve the task's reward (the Gymnasium adapter's --task-reward)"
    )]
    RewardGradient {
        /// The learner.
        algo: agent::config::Algo,
        /// The driver's id.
        id: String,
        /// The task the driver serves.
        task: String,
    },
    /// A resumed run's old recording does not fit the new one's channels.
    #[error(
        "cannot keep the recorded trials: {} was recorded with another channel layout",
        path.display()
    )]
    Channels {
        /// The old recording.
        path: std::path::PathBuf,
        /// What the recorder refused.
        #[source]
        source: RecordError,
    },
    /// A process could not be started.
    #[error("cannot start the {role} process")]
    Start {
        /// The process.
        role: &'static str,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A message was lost between a process and the recorder.
    #[error("the recorder lost messages on {topic}: expected sample {expected}, got {got}")]
    Lost {
        /// The topic.
        topic: &'static str,
        /// The sequence number expected.
        expected: u64,
        /// The one received.
        got: u64,
    },
    /// A measurement arrived without its ground truth.
    #[error("the recorder lost messages on {topic}: no ground truth for sample {seq}")]
    NoTruth {
        /// The ground truth's topic.
        topic: &'static str,
        /// The measurement's sequence number.
        seq: u64,
    },
    /// The plant sent a sample outside a trial.
    #[error("a sample arrived before any trial started")]
    OutsideTrial,
    /// A process was seen to exit but not found again.
    #[error("a process exited and could not be found again")]
    Vanished,
    /// A process failed at the end of the run.
    #[error("the {role} process failed ({status}); {log}")]
    Failed {
        /// The process.
        role: &'static str,
        /// How it exited.
        status: ExitStatus,
        /// The last lines of its log.
        log: String,
    },
    /// A process did not exit after the end of the run.
    #[error("the {role} process did not exit after the end of the run")]
    Lingered {
        /// The process.
        role: &'static str,
    },
    /// A message could not be handled: the run stopped.
    #[error("{}; {hint}", chain(cause.as_ref()))]
    Stopped {
        /// What went wrong.
        cause: Box<RunError>,
        /// How far the run got and how to continue it.
        hint: String,
    },
    /// Ctrl-C.
    #[error("interrupted: stopped the plant, observer and agent processes; {hint}")]
    Interrupted {
        /// How far the run got and how to continue it.
        hint: String,
    },
    /// A process exited before the run's end.
    #[error("the {role} process exited ({status}) before the run finished; {hint}; {log}")]
    Exited {
        /// The process.
        role: &'static str,
        /// How it exited.
        status: ExitStatus,
        /// How far the run got and how to continue it.
        hint: String,
        /// The last lines of its log.
        log: String,
    },
    /// A process's log could not be written.
    #[error("{hint}; {log}")]
    Log {
        /// How far the run got and how to continue it.
        hint: String,
        /// Why the log could not be written, and its last lines.
        log: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stopped_run_names_the_cause_with_its_reasons_then_how_to_go_on() {
        let cause = RunError::File(FileError {
            action: "cannot write",
            path: "out/returns.csv".into(),
            source: std::io::Error::other("No space left on device"),
        });
        let e = RunError::Stopped {
            cause: Box::new(cause),
            hint: "2 completed trials are in returns.csv".into(),
        };
        assert_eq!(
            e.to_string(),
            "cannot write out/returns.csv: No space left on device; 2 completed trials are in returns.csv"
        );
        // One message: the cause's reasons are in it, not after it again.
        assert!(std::error::Error::source(&e).is_none());
    }
}
