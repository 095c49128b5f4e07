//! Both ends of the driver contract (`docs/driver.md`), in two halves:
//!
//! - [`kit`]: what a process that owns the hardware (or a simulation of it) links to
//!   serve the rig — the [`Device`] trait a driver implements; [`serve`] runs the
//!   contract for it (clock, commands, resets, watchdog); [`serve_lockstep`] serves a
//!   simulation ([`Lockstep`]) one period per action; [`Simulated`] is any built-in
//!   system as a device (`rig sim-driver`); [`safety`]: the safety layer every action
//!   passes (clamps, rejection, watchdog, range stop), the same one the simulated plant
//!   uses. The kit's items are re-exported here: a driver writes `driver::serve`.
//! - [`link`]: the rig's end — finding the running drivers, waiting for a driver's info,
//!   watching and commanding a driver ([`link::DriverLink`]); whether a driver fits a
//!   task ([`link::fits_task`], [`link::check_info`]); which command serves a task
//!   ([`link::how_to_serve`]); and [`link::conformance`], the check a driver passes
//!   (`rig check-driver`), callable from a driver's own tests too.
//!
//! Shared by both: [`contract`], the messages and services (`DriverInfo`,
//! `DriverSample`, `DriverCommand`); [`Error`], what can go wrong on either end, keeping
//! the transport's typed errors; [`InfoError`], [`SampleError`], [`TaskMismatch`] and
//! [`Unfit`] say what breaks the contract.
//!
//! Either half links `plant`, `wire`, iceoryx2 and `thiserror` only — no plotting,
//! recording or thread pool. `examples/motor_driver.rs` is the template for a hardware
//! driver.

pub mod contract;
mod error;
pub mod kit;
pub mod link;

pub use error::{Error, InfoError, LastSample, SampleError, TaskMismatch, Unfit};
pub use kit::{
    Device, Lockstep, Outcome, REST_SAMPLES, Served, Serving, Simulated, safety, serve,
    serve_lockstep,
};
