//! The flags that name an external driver (`rig run --plant external`, `rig
//! check-driver`).

use clap::Args;
use plant::SystemName;
use runtime::run::ExternalDriver;

/// Which external driver, and how long to wait for it (`rig run`: with `--plant
/// external` only).
#[derive(Args)]
pub struct DriverArgs {
    /// The external driver's id: its services are rig/driver/ID/{info,sample,command}
    /// (`rig run`: needs `--plant external`) [default: the system's name, e.g. pendulum].
    #[arg(long, value_name = "ID")]
    pub(crate) driver: Option<String>,
    /// How long to wait for the driver to appear (its first info message) [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    pub(crate) driver_timeout: f64,
    /// How long the driver may take for one reset (to bring the system to rest at the
    /// start state and report READY) [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0)]
    pub(crate) reset_timeout: f64,
}

impl DriverArgs {
    /// The driver to run against `system`'s task: its id (default: the system's name) and
    /// timeouts, checked.
    pub fn resolve(&self, system: SystemName) -> Result<ExternalDriver, String> {
        let id = self
            .driver
            .clone()
            .unwrap_or_else(|| system.as_str().to_string());
        driver::contract::check_id(&id).map_err(|e| format!("`--driver`: {e}"))?;
        Ok(ExternalDriver {
            id,
            timeout: runtime::process::seconds("--driver-timeout", self.driver_timeout)
                .map_err(|e| e.to_string())?,
            reset_timeout: runtime::process::seconds("--reset-timeout", self.reset_timeout)
                .map_err(|e| e.to_string())?,
        })
    }
}
