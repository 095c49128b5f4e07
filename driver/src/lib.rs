//! The driver kit: what a process that owns the hardware (or a simulation of it) links
//! to serve the rig, and nothing else — no plotting, recording or thread pool.
//!
//! - [`contract`]: the messages and services of `docs/driver.md` (`DriverInfo`,
//!   `DriverSample`, `DriverCommand`), and the rig's end of them.
//! - [`device`]: the [`Device`] trait a driver implements; [`serve`] runs the contract
//!   for it (clock, commands, resets, watchdog); [`serve_lockstep`] serves a simulation
//!   ([`Lockstep`]) one period per action; [`Simulated`] is any built-in system as a
//!   device (`rig sim-driver`).
//! - [`safety`]: the safety layer every action passes (clamps, rejection, watchdog, range
//!   stop), the same one the simulated plant uses.
//! - [`conformance`]: the check a driver passes (`rig check-driver`), for a driver's own
//!   tests too.
//! - [`fits_task`]: whether a driver's limits fit a task; [`check_info`] checks an info
//!   on its own and against a task.
//! - [`Error`]: what can go wrong on either end, keeping the transport's typed errors;
//!   [`InfoError`], [`SampleError`], [`TaskMismatch`] and [`Unfit`] say what breaks the
//!   contract.
//!
//! `examples/motor_driver.rs` is the template for a hardware driver.

pub mod conformance;
pub mod contract;
pub mod device;
mod error;
mod fits;
mod link;
mod serve;
mod serving;
mod simulated;

pub use device::{Device, Outcome, REST_SAMPLES};
pub use error::{Error, InfoError, SampleError, TaskMismatch, Unfit};
pub use fits::{check_info, fits_task};
pub use plant::safety;
pub use serve::{Lockstep, Served, Serving, serve, serve_lockstep};
pub use simulated::Simulated;
