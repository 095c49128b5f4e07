//! The `rig` command's library: the in-process experiment driver ([`experiment`]),
//! `rig learn` ([`learn`]), the pendulum's optimal-control reference ([`optimal`]), and
//! reports — learning-curve statistics and plots
//! ([`report`]).

pub mod delay_study;
pub mod driver;
pub mod experiment;
pub mod latency;
pub mod learn;
pub mod loop_bench;
pub mod optimal;
pub mod process;
pub mod record;
pub mod report;
pub mod reproduce;
pub mod resume;
pub mod run;
