//! Why a node process stopped: the operating system refused its scheduling, a peer or
//! the driver broke the protocol, or an error of the parts it runs.

use std::io;
use std::path::PathBuf;

use agent::checkpoint::CheckpointError;
use plant::config::ConfigError;

use crate::clock::ClockError;
use crate::error::FileError;
use crate::resume::WriteError;

/// A node's result.
pub type Result<T, E = NodeError> = std::result::Result<T, E>;

/// The operating system refused what a scheduling flag asks for.
#[derive(Debug, thiserror::Error)]
pub enum SystemError {
    /// `SCHED_FIFO` refused.
    #[error(
        "cannot run under SCHED_FIFO at --rt-priority {priority}: {os} (needs root, CAP_SYS_NICE or an rtprio limit in /etc/security/limits.conf)"
    )]
    RtPriority {
        /// The priority asked for.
        priority: u8,
        /// The operating system's error.
        os: io::Error,
    },
    /// `mlockall` refused.
    #[error(
        "cannot lock this process's memory (mlockall) for --rt-priority {priority}: {os} (needs root, CAP_IPC_LOCK or a memlock limit in /etc/security/limits.conf)"
    )]
    Mlock {
        /// The priority asked for.
        priority: u8,
        /// The operating system's error.
        os: io::Error,
    },
    /// A layout that sets a CPU apart, on a machine with one CPU online.
    #[error("--cpus {}needs at least two CPUs; 1 is online", layout.map_or(String::new(), |l| format!("{l} ")))]
    OneCpu {
        /// The layout's name, where one was asked for.
        layout: Option<&'static str>,
    },
    /// `sched_setaffinity` refused.
    #[error("cannot pin this process to CPUs {first}–{last} (--cpus): {os}")]
    Pin {
        /// The first CPU of the set.
        first: usize,
        /// The last CPU of the set.
        last: usize,
        /// The operating system's error.
        os: io::Error,
    },
    /// A wake-up limit beyond what the kernel takes.
    #[error("`--cpu-wakeup-us` {us} is out of range: at most {max}")]
    WakeupRange {
        /// The limit asked for, µs.
        us: u32,
        /// The largest the kernel takes, µs.
        max: u32,
    },
    /// The PM QoS device refused the wake-up limit.
    #[error(
        "cannot hold the CPU wake-up latency limit at {us} µs (--cpu-wakeup-us) through {} (needs root and a kernel with PM QoS)",
        device.display()
    )]
    Wakeup {
        /// The limit asked for, µs.
        us: u32,
        /// The device.
        device: PathBuf,
        /// The operating system's error.
        #[source]
        source: io::Error,
    },
}

/// Why a node process (plant, observer, agent) stopped.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// The transport.
    #[error(transparent)]
    Wire(#[from] wire::Error),
    /// The link to the driver.
    #[error(transparent)]
    Driver(#[from] driver::Error),
    /// The operating system refused a scheduling flag.
    #[error(transparent)]
    System(#[from] SystemError),
    /// The node's settings file.
    #[error(transparent)]
    Settings(#[from] super::node::SettingsError),
    /// The run's configuration.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The clock does not fit the configuration.
    #[error(transparent)]
    Clock(#[from] ClockError),
    /// A file the node reads or writes.
    #[error(transparent)]
    File(#[from] FileError),
    /// The checkpoint to resume from.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The checkpoint does not fit this agent.
    #[error("{}: {why}", path.display())]
    Restore {
        /// The checkpoint.
        path: PathBuf,
        /// How it does not fit.
        why: CheckpointError,
    },
    /// A checkpoint not written.
    #[error(transparent)]
    CheckpointWrite(#[from] WriteError),
    /// The driver's sample is not what its info promised.
    #[error("driver {driver:?}: {why}")]
    Sample {
        /// The driver's id.
        driver: String,
        /// What is wrong.
        why: driver::SampleError,
    },
    /// The driver stopped or started measuring velocities mid-run.
    #[error(
        "driver {driver:?} changed what it measures at sample {seq}: velocities {} before, {} now",
        measured(*before),
        measured(*now)
    )]
    MeasuresChanged {
        /// The driver's id.
        driver: String,
        /// The sample.
        seq: u64,
        /// Whether its velocities were NaN before.
        before: bool,
        /// Whether they are NaN now.
        now: bool,
    },
    /// The driver's sample is not READY from the rig's reset.
    #[error(
        "driver {driver:?} left the trial: sample {seq} has status {status:#x} and reset_id {reset_id} (expected READY from reset {expected}); was it restarted or reset by another process?"
    )]
    LeftTrial {
        /// The driver's id.
        driver: String,
        /// The sample.
        seq: u64,
        /// Its status.
        status: u64,
        /// Its reset.
        reset_id: u64,
        /// The reset the rig asked for.
        expected: u64,
    },
    /// A driver measuring positions only, with no observer to estimate the rest.
    #[error(
        "driver {driver:?} measures positions only (its velocities are NaN): run with `--sensor angle` and an observer that estimates them (`--observer finite-difference` or `--observer predictive`)"
    )]
    PositionsOnly {
        /// The driver's id.
        driver: String,
    },
    /// An action for another sample than the one waited for.
    #[error("action for sample {got} arrived while waiting for sample {want}")]
    ActionOutOfTurn {
        /// The action's sample.
        got: u64,
        /// The sample waited for.
        want: u64,
    },
    /// A trial the agent did not expect.
    #[error(
        "the plant started trial {started} where trial {due} was due (a resumed agent continues after its checkpoint's trial)"
    )]
    TrialOutOfTurn {
        /// The trial the plant started.
        started: u64,
        /// The trial due.
        due: u64,
    },
    /// A trial cut short by gaps too often in a row.
    #[error(
        "{trial} was cut short by gaps {cuts} times in a row: the loop does not keep the period (see gaps.csv)"
    )]
    CutTooOften {
        /// The trial, named.
        trial: String,
        /// The cuts in a row.
        cuts: u32,
    },
}

/// How a sample's velocities are, in words.
fn measured(nan: bool) -> &'static str {
    if nan { "NaN" } else { "measured" }
}
