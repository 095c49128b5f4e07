//! Why `rig bench-loop` (or its ping-pong, `rig pong`) could not measure.

use std::path::PathBuf;
use std::process::ExitStatus;

use plant::config::ConfigError;
use runtime::error::FileError;
use runtime::process::SystemError;
use runtime::process::node::SettingsError;

/// What stopped a measurement of the loop.
#[derive(Debug, thiserror::Error)]
pub enum LoopError {
    /// The default experiment's configuration.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// An output or a measured file could not be read or written.
    #[error(transparent)]
    File(#[from] FileError),
    /// A process's settings could not be written.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The process could not be placed.
    #[error(transparent)]
    System(#[from] SystemError),
    /// The ping-pong's transport failed.
    #[error(transparent)]
    Wire(#[from] wire::Error),
    /// The driver's services could not be opened.
    #[error(transparent)]
    Driver(#[from] driver::Error),
    /// A process could not be waited for, or its output not be passed on.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The rig's own executable, which runs the processes, was not found.
    #[error("cannot find the rig executable")]
    Executable(#[source] std::io::Error),
    /// A process could not be started.
    #[error("cannot start {program}")]
    Start {
        /// Its first argument (the command).
        program: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A process measured failed.
    #[error("{name} failed ({status}); see {}", log.display())]
    Failed {
        /// The process (the command).
        name: String,
        /// How it exited.
        status: ExitStatus,
        /// Its log.
        log: PathBuf,
    },
    /// The ping-pong received another message than it sent.
    #[error("ping-pong out of step: sent {sent}, got {got}")]
    OutOfStep {
        /// The sequence number sent.
        sent: usize,
        /// The one received.
        got: u64,
    },
    /// A process of the ping-pong failed.
    #[error("the ping-pong's {name} process failed ({status}); see its log in {}", dir.display())]
    PingPong {
        /// The process: echo or ping.
        name: &'static str,
        /// How it exited.
        status: ExitStatus,
        /// The folder of its log.
        dir: PathBuf,
    },
    /// A line of the round trips that is not an integer.
    #[error("{}: bad line {line:?}", path.display())]
    BadLine {
        /// The file.
        path: PathBuf,
        /// The line.
        line: String,
        /// Why it is not a number.
        #[source]
        source: std::num::ParseIntError,
    },
    /// A driver measured did not publish its info.
    #[error("driver {id:?} did not start; see {}", log.display())]
    NotServed {
        /// The driver's id.
        id: String,
        /// Its log.
        log: PathBuf,
        /// What the wait saw.
        #[source]
        source: Box<driver::Error>,
    },
    /// The Gymnasium yardstick needs a Python.
    #[error("no Python")]
    NoPython,
    /// The Gymnasium yardstick could not be started.
    #[error("cannot start bench/scripts/env_step.py")]
    YardstickStart(#[source] std::io::Error),
    /// The Gymnasium yardstick failed: its output.
    #[error("bench/scripts/env_step.py failed: {0}")]
    YardstickFailed(String),
    /// The Gymnasium yardstick printed no time per step: its output.
    #[error("bench/scripts/env_step.py printed {0:?}")]
    YardstickPrinted(String),
}
