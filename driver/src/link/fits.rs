//! What the rig requires of a driver for a task (`docs/driver.md`): the same task —
//! name, dimensions, sample time, action limits and content hash.

use crate::contract::DriverInfo;
use crate::error::{Error, TaskMismatch, Unfit};

/// Checks driver `id`'s info on its own ([`DriverInfo::validate`]) and against `task`
/// ([`fits_task`]).
pub fn check_info(id: &str, info: &DriverInfo, task: &Task) -> Result<(), Error> {
    let fits = || -> Result<(), Unfit> {
        info.validate()?;
        Ok(fits_task(info, task)?)
    };
    fits().map_err(|error| Error::Unfit {
        id: id.to_string(),
        error,
    })
}
use plant::Task;

/// Checks that a driver's info fits `task`: the same task name, dimensions, sample time
/// (within 0.01 %), action limits (within 1e-9) and content hash ([`Task::hash`]) — the
/// rig learns the task its file defines, so a driver of another is an error, not a
/// silent change. The error names both sides.
pub fn fits_task(info: &DriverInfo, task: &Task) -> Result<(), TaskMismatch> {
    let name = info.task_name();
    if name != task.name {
        return Err(TaskMismatch::Name {
            served: name.to_string(),
            task: task.name.clone(),
        });
    }
    if info.n_x != task.state_dim() as u64 || info.n_u != task.action_dim() as u64 {
        return Err(TaskMismatch::Dimensions {
            n_x: info.n_x,
            n_u: info.n_u,
            task: task.name.clone(),
            x: task.state_dim(),
            u: task.action_dim(),
        });
    }
    if (info.ts() - task.ts).abs() > 1e-4 * task.ts {
        return Err(TaskMismatch::SampleTime {
            ts: info.ts(),
            period_ns: info.period_ns,
            time_scale: info.time_scale,
            task_ts: task.ts,
        });
    }
    for i in 0..task.action_dim() {
        let (lo, hi) = (task.action_low[i], task.action_high[i]);
        if (info.u_min[i] - lo).abs() > 1e-9 || (info.u_max[i] - hi).abs() > 1e-9 {
            return Err(TaskMismatch::Limits {
                i,
                lo: info.u_min[i],
                hi: info.u_max[i],
                task_lo: lo,
                task_hi: hi,
            });
        }
    }
    if info.task_hash != task.hash() {
        return Err(TaskMismatch::Hash {
            name: name.to_string(),
            served: info.task_hash,
            task: task.hash(),
        });
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
        i.task[..8].copy_from_slice(b"pendulum");
        i.task_hash = Task::new(SystemName::Pendulum).hash();
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
        assert!(
            fits_task(&i, &task)
                .unwrap_err()
                .to_string()
                .contains("limits of u[0]")
        );
        let mut i = pendulum_info();
        i.period_ns = 30_000_000;
        assert!(
            fits_task(&i, &task)
                .unwrap_err()
                .to_string()
                .contains("sample time")
        );
        let arm = Task::new(SystemName::ArmVertical);
        assert_eq!(
            fits_task(&pendulum_info(), &arm).unwrap_err().to_string(),
            "it serves task \"pendulum\", the rig's task is \"arm-vertical\""
        );
        // The same name, dimensions and limits, another reward: the hash tells.
        let mut heavier = Task::new(SystemName::Pendulum);
        heavier.reward.q[0] = 10.0;
        let e = fits_task(&pendulum_info(), &heavier).unwrap_err();
        assert!(matches!(e, TaskMismatch::Hash { .. }), "{e:?}");
        let e = e.to_string();
        assert!(e.contains("the two task files differ"), "{e}");
        assert!(e.contains(&format!("{:016x}", heavier.hash())), "{e}");
    }
}
