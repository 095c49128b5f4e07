//! The built-in systems: their task files, shipped in `plant/tasks/`, and their
//! simulated dynamics.

use super::{SystemName, Task, TaskFile};
use crate::Dynamics;
use crate::double_integrator::DoubleIntegrator;
use crate::pendulum::Pendulum;
use crate::two_link::TwoLink;

/// The task file of a built-in system, as shipped.
pub fn text(system: SystemName) -> &'static str {
    match system {
        SystemName::Pendulum => include_str!("../../tasks/pendulum.toml"),
        SystemName::ArmVertical => include_str!("../../tasks/arm-vertical.toml"),
        SystemName::ArmHorizontal => include_str!("../../tasks/arm-horizontal.toml"),
        SystemName::DoubleIntegrator => include_str!("../../tasks/double-integrator.toml"),
        SystemName::Arm64 => include_str!("../../tasks/arm-6.4.toml"),
    }
}

/// The task of a built-in system, from its shipped file.
pub fn task(system: SystemName) -> Task {
    let path = format!("plant/tasks/{system}.toml");
    TaskFile::parse(text(system), None)
        .and_then(|f| f.task(None))
        .unwrap_or_else(|e| panic!("{path}, shipped with the rig, is invalid: {e}"))
}

/// The simulated dynamics of `system`: Appendix A.1 and A.2, Table 6.3, or the double
/// integrator.
pub fn dynamics(system: SystemName) -> Box<dyn Dynamics> {
    match system {
        SystemName::Pendulum => Box::new(Pendulum::default()),
        SystemName::ArmVertical => Box::new(TwoLink::vertical()),
        SystemName::ArmHorizontal => Box::new(TwoLink::horizontal()),
        SystemName::DoubleIntegrator => Box::new(DoubleIntegrator::default()),
        SystemName::Arm64 => Box::new(TwoLink::manipulator_6_4()),
    }
}
