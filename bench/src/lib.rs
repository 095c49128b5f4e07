//! The `rig` command's library: experiment configuration, the in-process experiment
//! driver, and reports (learning curves, plots).

pub mod report;
