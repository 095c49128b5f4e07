//! What can go wrong between the rig and a driver: the driver's id, its services, its
//! info, its samples, and the task it serves. The transport's typed errors are kept
//! ([`Error::Wire`], [`Error::Transport`]).

use std::time::Duration;

/// An error of the driver kit, on either end of the contract.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A transport error on the rig's end.
    #[error(transparent)]
    Wire(#[from] wire::Error),
    /// A transport error of the driver's process, naming the driver.
    #[error("driver {id:?}: {error}")]
    Transport {
        /// The driver id.
        id: String,
        /// What went wrong on the transport.
        error: wire::Error,
    },
    /// A driver id with characters other than letters, digits, '-' and '_'.
    #[error("driver id {0:?}: use letters, digits, '-' and '_' only")]
    Id(String),
    /// A second driver process of the same id: the service's one publisher is taken.
    #[error("another driver {id:?} is running: {service} has its one publisher already")]
    AlreadyServed {
        /// The driver id.
        id: String,
        /// The service whose publisher is taken.
        service: String,
    },
    /// A driver that speaks another protocol version: its services carry other payloads
    /// (`found` describes them).
    #[error(
        "driver {id:?} speaks another protocol version than this rig's {speaks} ({service}: {found}): update the driver to protocol version {speaks} (docs/driver.md)"
    )]
    OtherVersion {
        /// The driver id.
        id: String,
        /// The service whose payload differs.
        service: String,
        /// What the service carries.
        found: String,
        /// The rig's version.
        speaks: u64,
    },
    /// A second rig process commanding the same driver.
    #[error("driver {id:?} is in use: another rig process is commanding it ({service})")]
    InUse {
        /// The driver id.
        id: String,
        /// The command service, whose publisher is taken.
        service: String,
    },
    /// No info from the driver in time; `hint` names the drivers that are running, and
    /// `serve` says how to start one.
    #[error(
        "no driver {id:?}: nothing published on {service} within {:.0} s ({hint}); {serve}",
        .timeout.as_secs_f64()
    )]
    NoInfo {
        /// The driver id.
        id: String,
        /// The info service.
        service: String,
        /// How long the rig waited.
        timeout: Duration,
        /// The drivers running on this host, in words.
        hint: String,
        /// How to start the driver.
        serve: String,
    },
    /// The driver stopped publishing samples.
    #[error(
        "driver {id:?} stopped: no sample on {service} for {:.1} s",
        .silence.as_secs_f64()
    )]
    Stopped {
        /// The driver id.
        id: String,
        /// The sample service.
        service: String,
        /// How long no sample came.
        silence: Duration,
    },
    /// A sample that breaks the contract.
    #[error("driver {id:?}: {error}")]
    Sample {
        /// The driver id.
        id: String,
        /// What is wrong with the sample.
        error: SampleError,
    },
    /// A reset not done in time; `last` is the last sample.
    #[error(
        "driver {id:?} did not finish the reset within {:.0} s (last sample {}: status {:#x}, reset_id {}, x = {:?}){}",
        .timeout.as_secs_f64(), .last.seq, .last.status, .last.reset_id, .last.x,
        .said.as_deref().map(|s| format!("; the driver's side says: {s}")).unwrap_or_default()
    )]
    ResetTimeout {
        /// The driver id.
        id: String,
        /// How long the rig waited.
        timeout: Duration,
        /// The last sample.
        last: Box<LastSample>,
        /// What the driver's side last said of this rig's commands (across hosts: who
        /// holds the driver), if anything.
        said: Option<String>,
    },
    /// A driver whose info breaks the contract or does not fit the rig's task.
    #[error("driver {id:?} does not fit the task: {error}")]
    Unfit {
        /// The driver id.
        id: String,
        /// What does not fit.
        error: Unfit,
    },
    /// A device whose time scale is not a positive finite number.
    #[error("time scale {0}: must be positive and finite")]
    TimeScale(f64),
    /// A task without a built-in simulation, given to [`crate::Simulated`].
    #[error("task {0:?} has no [simulation]: there is nothing to simulate")]
    NoSimulation(String),
    /// The vertical arm, which cannot rest at its start state against gravity.
    #[error(
        "the simulated arm-vertical cannot rest at its start state [-1.1, 1, 0, 0]: gravity needs 5.5 N m at joint 1, beyond the ±1 N m limit"
    )]
    CannotRest,
    /// A simulation speed outside (0, 1000].
    #[error("--speed {0}: must be in (0, 1000]")]
    Speed(f64),
    /// An encoder of zero counts per revolution.
    #[error("--counts-per-rev 0: must be at least 1")]
    NoCounts,
}

/// What an error says of a driver's last sample.
#[derive(Clone, Debug, PartialEq)]
pub struct LastSample {
    /// Its sequence number.
    pub seq: u64,
    /// Its status bits.
    pub status: u64,
    /// The reset it belongs to.
    pub reset_id: u64,
    /// Its state, `n_x` components.
    pub x: Vec<f64>,
}

impl Error {
    /// Wraps a transport error of driver `id`'s process, naming the driver.
    pub fn transport(id: &str) -> impl Fn(wire::Error) -> Error + '_ {
        move |error| Error::Transport {
            id: id.to_string(),
            error,
        }
    }
}

/// Why a driver's info does not fit the rig's task ([`crate::link::check_info`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Unfit {
    /// The info breaks the contract.
    #[error(transparent)]
    Info(#[from] InfoError),
    /// The info describes another task.
    #[error(transparent)]
    Task(#[from] TaskMismatch),
}

/// What is wrong with a driver's info (`DriverInfo::validate`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InfoError {
    /// Another protocol version.
    #[error("protocol version {found} (this rig speaks {speaks})")]
    Version {
        /// The driver's version.
        found: u64,
        /// The rig's version.
        speaks: u64,
    },
    /// Dimensions beyond the message sizes.
    #[error("n_x = {n_x}, n_u = {n_u}: must be 1..={max_x} and 1..={max_u}")]
    Dimensions {
        /// State components.
        n_x: u64,
        /// Action components.
        n_u: u64,
        /// The most state components a message holds.
        max_x: usize,
        /// The most action components a message holds.
        max_u: usize,
    },
    /// A zero period or a time scale that is not positive and finite.
    #[error(
        "period_ns = {period_ns}, time_scale = {time_scale}: both must be positive (and finite)"
    )]
    Period {
        /// The period \[ns\].
        period_ns: u64,
        /// The time scale.
        time_scale: f64,
    },
    /// Action limits that are not finite or not ordered.
    #[error("limits of u[{i}]: [{lo}, {hi}]: must be finite with u_min < u_max")]
    Limits {
        /// The action component.
        i: usize,
        /// Its lower limit.
        lo: f64,
        /// Its upper limit.
        hi: f64,
    },
    /// An unknown clock.
    #[error("clock = {found}: must be {realtime} (realtime) or {lockstep} (lockstep)")]
    Clock {
        /// The driver's clock.
        found: u64,
        /// The real-time clock's number.
        realtime: u64,
        /// The lockstep clock's number.
        lockstep: u64,
    },
    /// A watchdog other than one period.
    #[error(
        "watchdog_periods = {found}: protocol version {version} requires 1 (the safe action within two periods of the last action)"
    )]
    Watchdog {
        /// The driver's watchdog \[periods\].
        found: u64,
        /// The protocol version.
        version: u64,
    },
    /// Unknown bits in `provides`.
    #[error(
        "provides = {found}: must be 0 or {reward} (the samples carry the reward and the endings)"
    )]
    Provides {
        /// The driver's bits.
        found: u64,
        /// The reward's bit.
        reward: u64,
    },
}

/// What is wrong with a driver's sample (`DriverSample::validate`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// Dimensions other than the info's.
    #[error(
        "sample {seq}: n_x = {n_x}, n_u = {n_u}, but the driver's info says {info_n_x} and {info_n_u}"
    )]
    Dimensions {
        /// The sample's sequence number.
        seq: u64,
        /// The sample's state components.
        n_x: u64,
        /// The sample's action components.
        n_u: u64,
        /// The info's state components.
        info_n_x: u64,
        /// The info's action components.
        info_n_u: u64,
    },
    /// A value that is not finite; `hint` explains NaN velocities.
    #[error("sample {seq}: {name}[{i}] = {value}{hint}")]
    NotFinite {
        /// The sample's sequence number.
        seq: u64,
        /// `x` or `u_applied`.
        name: &'static str,
        /// The component.
        i: usize,
        /// Its value.
        value: f64,
        /// An explanation, or empty.
        hint: &'static str,
    },
    /// A reward that is not finite from a driver that provides the reward.
    #[error(
        "sample {seq}: reward = {reward}: a driver that provides the reward sends a finite one"
    )]
    Reward {
        /// The sample's sequence number.
        seq: u64,
        /// The reward.
        reward: f64,
    },
    /// Ending bits (or a reward) that do not fit what the driver provides.
    #[error(
        "sample {seq}: ending = {ending}, reward = {reward}: {}",
        if *provided { "ending must be 0, 1 (terminated) or 2 (truncated)" } else { "both must be 0 from a driver whose info does not provide the reward" }
    )]
    Ending {
        /// The sample's sequence number.
        seq: u64,
        /// The ending bits.
        ending: u64,
        /// The reward.
        reward: f64,
        /// Whether the driver's info provides the reward.
        provided: bool,
    },
}

/// How a driver's info differs from the rig's task ([`crate::link::fits_task`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TaskMismatch {
    /// Another task name.
    #[error("it serves task {served:?}, the rig's task is {task:?}")]
    Name {
        /// The driver's task.
        served: String,
        /// The rig's task.
        task: String,
    },
    /// Other dimensions.
    #[error("n_x = {n_x}, n_u = {n_u}; the {task} has {x} state and {u} action components")]
    Dimensions {
        /// The driver's state components.
        n_x: u64,
        /// The driver's action components.
        n_u: u64,
        /// The rig's task.
        task: String,
        /// The task's state components.
        x: usize,
        /// The task's action components.
        u: usize,
    },
    /// Another sample time.
    #[error(
        "sample time {ts:.6} s (period {period_ns} ns × time scale {time_scale}); the task's is {task_ts} s"
    )]
    SampleTime {
        /// The driver's sample time \[s\].
        ts: f64,
        /// The driver's period \[ns\].
        period_ns: u64,
        /// The driver's time scale.
        time_scale: f64,
        /// The task's sample time \[s\].
        task_ts: f64,
    },
    /// Other action limits.
    #[error("limits of u[{i}]: [{lo}, {hi}]; the task's are [{task_lo}, {task_hi}]")]
    Limits {
        /// The action component.
        i: usize,
        /// The driver's lower limit.
        lo: f64,
        /// The driver's upper limit.
        hi: f64,
        /// The task's lower limit.
        task_lo: f64,
        /// The task's upper limit.
        task_hi: f64,
    },
    /// The same name but another task file.
    #[error(
        "it serves task {name:?} with hash {served:016x}, the rig's task {name:?} has hash {task:016x}: the two task files differ (reward, start states, ranges or operating range)"
    )]
    Hash {
        /// The task's name.
        name: String,
        /// The driver's hash.
        served: u64,
        /// The rig's hash.
        task: u64,
    },
}
