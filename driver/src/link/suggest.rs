//! Which command serves a task: what the rig suggests when no driver answers.

use plant::{SystemName, Task};

use crate::kit::Simulated;

/// How to start a driver `id` for `task`, or why the rig has none: the Python example
/// driver and `rig sim-driver` serve the pendulum, `rig sim-driver` every other built-in
/// simulation it can hold at rest; a task without a simulation only the driver written
/// for it. `task_arg` is how the command line named the task (`--task FILE`,
/// `--system NAME`); `None`: the built-in system's `--system`, or a task file's
/// `--task FILE`.
pub fn how_to_serve(task: &Task, id: &str, task_arg: Option<&str>) -> String {
    let Some(sim) = &task.simulation else {
        return format!(
            "the rig has no driver for task \"{}\", which has no [simulation]: start the one written for it (docs/your-own-rig.md)",
            task.name
        );
    };
    if let Err(e) = Simulated::brake_gains(sim.system) {
        return format!(
            "`rig sim-driver` cannot serve task \"{}\" ({e}): start a driver of your own (docs/your-own-rig.md)",
            task.name
        );
    }
    let builtin = task.hash() == Task::new(sim.system).hash();
    let pendulum = sim.system == SystemName::Pendulum;
    let named = match (task_arg, builtin) {
        (Some(a), _) => format!(" {a}"),
        (None, true) if pendulum => String::new(),
        (None, true) => format!(" --system {}", sim.system),
        (None, false) => " --task FILE".to_string(),
    };
    let rust = format!("`rig sim-driver{named} --driver-id {id}`");
    if !pendulum {
        return format!("start one, e.g. {rust} (docs/driver.md)");
    }
    // The Python example serves the pendulum's task files (`--task`), its own by default.
    let python = if named.starts_with(" --task") {
        named.as_str()
    } else {
        ""
    };
    format!(
        "start one, e.g. `python3 examples/python_driver/driver.py{python} --driver-id {id}` or {rust} (docs/driver.md)"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_of_task_is_served_by_its_own_command_or_none() {
        let pendulum = how_to_serve(&Task::pendulum(), "p", None);
        assert!(
            pendulum.contains("`python3 examples/python_driver/driver.py --driver-id p`")
                && pendulum.contains("`rig sim-driver --driver-id p`"),
            "{pendulum}"
        );
        let arm = how_to_serve(&Task::new(SystemName::Arm64), "a", None);
        assert!(
            arm.contains("`rig sim-driver --system arm-6.4 --driver-id a`"),
            "{arm}"
        );
        assert!(!arm.contains("python"), "{arm}");
        let vertical = how_to_serve(&Task::new(SystemName::ArmVertical), "v", None);
        assert!(
            vertical.contains("cannot serve") && !vertical.contains("e.g."),
            "{vertical}"
        );
        let mut file =
            plant::TaskFile::parse(plant::task::builtin::text(SystemName::Arm64), None).unwrap();
        file.name = "mine".into();
        let mine = file.task(None).unwrap();
        let s = how_to_serve(&mine, "mine", Some("--task my.toml"));
        assert!(
            s.contains("`rig sim-driver --task my.toml --driver-id mine`"),
            "{s}"
        );
        file.simulation = None;
        let driven = how_to_serve(&file.task(None).unwrap(), "mine", None);
        assert!(
            driven.contains("has no [simulation]") && !driven.contains("e.g."),
            "{driven}"
        );
    }
}
