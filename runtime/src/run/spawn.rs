//! Starting the three processes: each one's settings (`DIR/nodes/<role>.toml`,
//! [`crate::process::node`]), its command line (the run options' [`NodeCommand`]), its
//! output to `DIR/<process>.log`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use super::command::{NodeCommand, Role};
use super::error::{Result, RunError};
use crate::error::AtFile;

use crate::process::node::Continuation;
use crate::process::{AgentSettings, NodeSettings, ObserverSettings, PlantSettings, Settings};
use crate::resume::ResumePoint;

use super::RunOptions;
use super::logs::{Log, Logs};
use super::supervisor::Children;

/// The three processes' settings, of run `run_id` on configuration `config`; each waits
/// for two receivers (the next process and the recorder).
pub(super) struct Nodes {
    plant: PlantSettings,
    observer: ObserverSettings,
    agent: AgentSettings,
}

impl Nodes {
    /// The settings `opts` and, resuming, `point` give the processes; the agent's
    /// checkpoints go to `checkpoints`.
    pub(super) fn new(
        (run_id, config): (&str, &Path),
        opts: &RunOptions,
        point: Option<&ResumePoint>,
        checkpoints: &Path,
    ) -> Self {
        let node = NodeSettings {
            receivers: 2,
            ..NodeSettings::new(run_id, config, opts.scheduling, opts.waiting)
        };
        let plant = PlantSettings {
            clock: opts.clock.clone(),
            checked: Some(opts.checked),
            spin: opts.spin,
            learn_across_gaps: opts.learn_across_gaps,
            cycles_out: opts.cycles_out.clone().filter(|_| opts.clock.is_realtime()),
            resume: point.map(|p| Continuation {
                after_trial: p.trial,
                sim_time: p.sim_time_s,
                first_seq: p.first_seq,
            }),
            ..PlantSettings::new(node.clone())
        };
        // All kept: the supervisor removes those a resume can no longer need.
        let agent = AgentSettings {
            checkpoints: Some(checkpoints.to_owned()),
            keep_checkpoints: 0,
            resume: point.and_then(|p| p.checkpoint.clone()),
            ..AgentSettings::new(node.clone())
        };
        let observer = ObserverSettings { node };
        Self {
            plant,
            observer,
            agent,
        }
    }

    /// Writes each process's settings into `out/nodes/`; returns the files by role, in
    /// the order the processes start.
    fn write(&self, out: &Path) -> Result<[(Role, PathBuf); 3]> {
        let dir = out.join("nodes");
        std::fs::create_dir_all(&dir).at("cannot create", &dir)?;
        let file = |role: Role| dir.join(format!("{}.toml", role.name()));
        self.agent.write(&file(Role::Agent))?;
        self.observer.write(&file(Role::Observer))?;
        self.plant.write(&file(Role::Plant))?;
        Ok(Role::START_ORDER.map(|role| (role, file(role))))
    }
}

/// Starts the three processes as `command` says, with settings `nodes` (written to
/// `out/nodes/`), their output to `out/<process>.log` ([`Logs`]).
pub(super) fn processes(
    out: &Path,
    nodes: &Nodes,
    command: &NodeCommand,
) -> Result<(Children, Logs)> {
    let mut children = Children(Vec::new());
    let mut logs = Logs::default();
    for (role, settings) in nodes.write(out)? {
        let role_name = role.name();
        let (log, pipe) = Log::open(&out.join(format!("{role_name}.log")))?;
        logs.0.push((role, log));
        let mut command = command.of(role, &settings);
        in_own_group(&mut command);
        let child = command
            .stdin(Stdio::null())
            .stdout(pipe.try_clone()?)
            .stderr(pipe)
            .spawn()
            .map_err(|source| RunError::Start {
                role: role_name,
                source,
            })?;
        // The command, dropped, closes this process's copy of the pipe's writing end:
        // the log's relay ends when the process does.
        drop(command);
        children.0.push((role, child));
    }
    Ok((children, logs))
}

/// Starts `command` in a process group of its own, so that Ctrl-C at a terminal reaches
/// the supervisor only, which stops the processes once it has recorded what they sent
/// ([`super::supervisor::Children::freeze`]); and so that it is told to stop (SIGTERM)
/// when the supervisor dies.
fn in_own_group(command: &mut Command) {
    use std::os::unix::process::CommandExt;
    command.process_group(0);
    // SAFETY: between fork and exec the closure calls `prctl`, an async-signal-safe
    // system call on this process only, and allocates nothing.
    unsafe {
        command.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}
