//! Starting the three processes: each one's command line (`rig plant|observer|agent`),
//! its output to `DIR/<process>.log`.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};

use anyhow::{Context, Result};

use crate::process::Wait;
use crate::resume::ResumePoint;

use super::RunOptions;
use super::logs::{Log, Logs};
use super::supervisor::Children;

/// The processes in the order they start: the plant last, once its receivers are up.
const ROLES: [&str; 3] = ["agent", "observer", "plant"];

/// What each process adds to the flags every node takes.
pub(super) fn role_args(
    opts: &RunOptions,
    point: Option<&ResumePoint>,
    checkpoints: &Path,
) -> BTreeMap<&'static str, Vec<String>> {
    let mut plant: Vec<String> = match (&opts.driver, opts.realtime) {
        (Some(d), _) => vec![
            "--driver".into(),
            d.id.clone(),
            "--driver-timeout".into(),
            d.timeout.as_secs_f64().to_string(),
            "--reset-timeout".into(),
            d.reset_timeout.as_secs_f64().to_string(),
        ],
        (None, None) => Vec::new(),
        (None, Some(speed)) => vec![
            "--timing".into(),
            "realtime".into(),
            "--speed".into(),
            speed.to_string(),
            "--spin-us".into(),
            opts.spin.spin_us.to_string(),
        ],
    };
    if let (Some(path), Some(_), None) = (&opts.cycles_out, opts.realtime, &opts.driver) {
        plant.extend(["--cycles-out".to_string(), path.display().to_string()]);
    }
    // All kept: the supervisor removes those a resume can no longer need.
    let mut agent = vec![
        "--checkpoints".to_string(),
        checkpoints.display().to_string(),
        "--keep-checkpoints".to_string(),
        "0".to_string(),
    ];
    if let Some(p) = point {
        if let Some(c) = &p.checkpoint {
            agent.extend(["--resume".to_string(), c.display().to_string()]);
        }
        plant.extend([
            "--after-trial".to_string(),
            p.trial.to_string(),
            "--sim-time".to_string(),
            p.sim_time_s.to_string(),
            "--first-seq".to_string(),
            p.first_seq.to_string(),
        ]);
    }
    let mut args = BTreeMap::from([("plant", plant), ("agent", agent), ("observer", Vec::new())]);
    for role in ROLES {
        let a = args.entry(role).or_default();
        a.extend(opts.scheduling.process_args());
        a.extend(Wait::process_args(opts.waiting));
    }
    args
}

/// Starts the three processes of run `run_id` with configuration `config`, each with
/// its `args`, their output to `out/<process>.log` ([`Logs`]); they wait for two
/// receivers each (the next process and the recorder).
pub(super) fn processes(
    run_id: &str,
    config: &Path,
    out: &Path,
    args: &BTreeMap<&'static str, Vec<String>>,
) -> Result<(Children, Logs)> {
    let exe = std::env::current_exe().context("cannot find the rig executable")?;
    let mut children = Children(Vec::new());
    let mut logs = Logs::default();
    for role in ROLES {
        let (log, pipe) = Log::open(&out.join(format!("{role}.log")))?;
        logs.0.push((role, log));
        let mut command = Command::new(&exe);
        in_own_group(&mut command);
        let child = command
            .arg(role)
            .args(["--run-id", run_id, "--receivers", "2", "--config"])
            .arg(config)
            .args(args.get(role).map_or(&[][..], |a| &a[..]))
            .stdin(Stdio::null())
            .stdout(pipe.try_clone()?)
            .stderr(pipe)
            .spawn()
            .with_context(|| format!("cannot start the {role} process"))?;
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
