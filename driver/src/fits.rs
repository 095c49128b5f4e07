//! What the rig requires of a driver for a task (`docs/driver.md`): the same system,
//! dimensions, sample time and action limits.

use crate::contract::DriverInfo;
use plant::Task;

/// Checks that a driver's info fits `task`: the same system, dimensions, sample time
/// (within 0.01 %) and action limits (within 1e-9) — the rig learns the task as the
/// thesis defines it, so a driver with other limits is an error, not a silent change.
pub fn fits_task(info: &DriverInfo, task: &Task) -> Result<(), String> {
    let name = info.system_name();
    if name != task.name.as_str() {
        return Err(format!(
            "it drives {name:?}, the task is {:?}",
            task.name.as_str()
        ));
    }
    if info.n_x != task.state_dim() as u64 || info.n_u != task.action_dim() as u64 {
        return Err(format!(
            "n_x = {}, n_u = {}; the {} has {} state and {} action components",
            info.n_x,
            info.n_u,
            task.name,
            task.state_dim(),
            task.action_dim()
        ));
    }
    if (info.ts() - task.ts).abs() > 1e-4 * task.ts {
        return Err(format!(
            "sample time {:.6} s (period {} ns × time scale {}); the task's is {} s",
            info.ts(),
            info.period_ns,
            info.time_scale,
            task.ts
        ));
    }
    for i in 0..task.action_dim() {
        let (lo, hi) = (task.action_low[i], task.action_high[i]);
        if (info.u_min[i] - lo).abs() > 1e-9 || (info.u_max[i] - hi).abs() > 1e-9 {
            return Err(format!(
                "limits of u[{i}]: [{}, {}]; the task's are [{lo}, {hi}]",
                info.u_min[i], info.u_max[i]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::SystemName;

    fn pendulum_info() -> DriverInfo {
        let mut i = DriverInfo {
            version: crate::contract::VERSION,
            n_x: 2,
            n_u: 1,
            period_ns: 3_000_000,
            time_scale: 10.0,
            watchdog_periods: 1,
            ..Default::default()
        };
        i.system[..8].copy_from_slice(b"pendulum");
        i.u_min[0] = -3.0;
        i.u_max[0] = 3.0;
        i
    }

    #[test]
    fn a_sped_up_pendulum_driver_fits_and_others_are_named() {
        let task = Task::new(SystemName::Pendulum);
        assert_eq!(fits_task(&pendulum_info(), &task), Ok(()));
        let mut i = pendulum_info();
        i.u_max[0] = 2.5;
        assert!(fits_task(&i, &task).unwrap_err().contains("limits of u[0]"));
        let mut i = pendulum_info();
        i.period_ns = 30_000_000;
        assert!(fits_task(&i, &task).unwrap_err().contains("sample time"));
        let arm = Task::new(SystemName::ArmVertical);
        assert!(
            fits_task(&pendulum_info(), &arm)
                .unwrap_err()
                .contains("\"pendulum\"")
        );
    }
}
