//! How the supervisor starts the run's processes: a program the application hands over
//! ([`NodeCommand`]); the runtime names none of its own.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One of the run's processes, by what it does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Role {
    Agent,
    Observer,
    Plant,
}

impl Role {
    /// The processes in the order they start: the plant last, once its receivers are up.
    pub(super) const START_ORDER: [Role; 3] = [Role::Agent, Role::Observer, Role::Plant];

    /// The process's name: of its settings file, its log and its messages.
    pub(super) fn name(self) -> &'static str {
        match self {
            Role::Agent => "agent",
            Role::Observer => "observer",
            Role::Plant => "plant",
        }
    }
}

/// The command line that starts each process of a run: `program`, the role's arguments,
/// then the process's settings file ([`crate::process::node`]). The application that
/// links the runtime builds it (`rig`: itself, `rig plant|observer|agent --node FILE`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeCommand {
    /// The program started for every process.
    pub program: PathBuf,
    /// The plant process's arguments before its settings file.
    pub plant: Vec<OsString>,
    /// The observer process's arguments before its settings file.
    pub observer: Vec<OsString>,
    /// The agent process's arguments before its settings file.
    pub agent: Vec<OsString>,
}

impl NodeCommand {
    /// The command that starts process `role` with its settings file `settings`.
    pub(super) fn of(&self, role: Role, settings: &Path) -> Command {
        let args = match role {
            Role::Agent => &self.agent,
            Role::Observer => &self.observer,
            Role::Plant => &self.plant,
        };
        let mut command = Command::new(&self.program);
        command.args(args).arg(settings);
        command
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_role_is_started_with_its_arguments_then_its_settings() {
        let nodes = NodeCommand {
            program: "/opt/loop/bin/node".into(),
            plant: vec!["plant".into(), "--settings".into()],
            observer: vec!["observe".into()],
            agent: vec![],
        };
        let line = |role| {
            let c = nodes.of(role, Path::new("nodes/x.toml"));
            let args: Vec<_> = c.get_args().map(|a| a.to_str().unwrap()).collect();
            (
                c.get_program().to_str().unwrap().to_string(),
                args.join(" "),
            )
        };
        let program = "/opt/loop/bin/node".to_string();
        assert_eq!(
            line(Role::Plant),
            (program.clone(), "plant --settings nodes/x.toml".into())
        );
        assert_eq!(
            line(Role::Observer),
            (program.clone(), "observe nodes/x.toml".into())
        );
        assert_eq!(line(Role::Agent), (program, "nodes/x.toml".into()));
        let names = Role::START_ORDER.map(Role::name);
        assert_eq!(
            names,
            ["agent", "observer", "plant"],
            "the plant starts last"
        );
    }
}
