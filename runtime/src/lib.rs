//! The rig's application library: everything `rig` does to run an experiment.
//!
//! - The experiment's [`config`]: the sections of plant, observer and agent composed,
//!   resolved from preset, file and flags, validated, written as TOML.
//! - In one process: [`experiment`] (one run, trial by trial; a greedy trial's
//!   [`response`]) and [`learn`] (runs in parallel, curves and plots through [`report`]).
//! - What the configuration builds around the agent, in process and in the nodes alike:
//!   [`build`] (sensor, observer in its timing, actuator); whether a run is
//!   [`resumable`] from a checkpoint.
//! - The files the commands write: [`output`] (`runs.csv`, responses, atomic writes,
//!   progress bars).
//! - As processes over iceoryx2: the nodes in [`process`] (plant, observer, agent), the
//!   supervisor that starts, watches and records them ([`run`]), the MCAP writer
//!   ([`record`]) and [`resume`] after a crash; [`lock`]: an output folder belongs to one
//!   command; [`replay`]: a recording's observer and agent run again, bit for bit.
//! - The run's [`clock`]: lockstep, real time or an external driver, and its rules.

pub mod build;
pub mod clock;
pub mod config;
pub mod error;
pub mod experiment;
pub mod learn;
pub mod lock;
pub mod output;
pub mod process;
pub mod record;
pub mod replay;
pub mod report;
pub mod response;
pub mod resumable;
pub mod resume;
pub mod run;
