//! The flags that name an external driver (`rig run --plant external`, `rig
//! check-driver`).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use plant::{SystemName, Task};
use runtime::clock::{ClockError, DriverFlags, ExternalDriver};

/// Which task a driver serves: a built-in system, or a task file (`rig sim-driver`, `rig
/// check-driver`).
#[derive(Args)]
pub struct TaskArgs {
    /// A built-in system: pendulum, arm-vertical, arm-horizontal, arm-6.4,
    /// double-integrator.
    #[arg(long, value_enum, default_value = "pendulum")]
    system: SystemName,
    /// A task file (docs/tasks.md) instead of `--system`.
    #[arg(long, value_name = "FILE", conflicts_with = "system")]
    task: Option<PathBuf>,
}

impl TaskArgs {
    /// The task: `--task`'s file, checked, else `--system`'s.
    pub fn task(&self) -> Result<Task> {
        match &self.task {
            Some(path) => Ok(Task::from_file(path)?),
            None => Ok(Task::new(self.system)),
        }
    }

    /// The task as these flags name it (`--task FILE`, `--system NAME`), if given.
    pub fn named(&self) -> Option<String> {
        match &self.task {
            Some(path) => Some(format!("--task {}", path.display())),
            None => {
                (self.system != SystemName::Pendulum).then(|| format!("--system {}", self.system))
            }
        }
    }
}

/// Which external driver, and how long to wait for it (`rig run`: with `--plant
/// external` only).
#[derive(Args)]
pub struct DriverArgs {
    /// The external driver's id: its services are rig/driver/ID/{info,sample,command}.
    /// `rig run` (with `--plant external`) and `rig check-driver`: default the task's
    /// name, e.g. pendulum; `rig latency`: measure against it instead of the simulated
    /// plant.
    #[arg(long, value_name = "ID")]
    pub(crate) driver: Option<String>,
    /// How long to wait for the driver to appear (its first info message), and for each
    /// sample of a driver in lockstep (a simulator's step may take long) [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    pub(crate) driver_timeout: f64,
    /// How long the driver may take for one reset (to bring the system to rest at the
    /// start state and report READY) [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0)]
    pub(crate) reset_timeout: f64,
}

impl DriverArgs {
    /// The driver to run against the task named `task`: its id (default: the task's
    /// name; one a driver id cannot be, with '.', needs `--driver`) and timeouts, checked.
    pub fn resolve(&self, task: &str) -> Result<ExternalDriver, ClockError> {
        let d = self.flags();
        ExternalDriver::named(d.id, task, d.timeouts)
    }

    /// The flags as given, to resolve against the task (`--driver` defaults to its name).
    pub fn flags(&self) -> DriverFlags<'_> {
        DriverFlags {
            id: self.driver.as_deref(),
            timeouts: (self.driver_timeout, self.reset_timeout),
        }
    }
}
