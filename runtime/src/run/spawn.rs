//! Starting the three processes: each one's command line (`rig plant|observer|agent`),
//! its output to `DIR/<process>.log`.

use std::collections::BTreeMap;
use std::fs::File;
use std::path::Path;
use std::process::{Command, Stdio};

use anyhow::{Context, Result};

use crate::process::Wait;
use crate::resume::ResumePoint;

use super::RunOptions;
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
    if opts.learn_across_gaps {
        plant.extend(["--gaps".to_string(), "learn".to_string()]);
    }
    if let (Some(path), Some(_), None) = (&opts.cycles_out, opts.realtime, &opts.driver) {
        plant.extend(["--cycles-out".to_string(), path.display().to_string()]);
    }
    let mut agent = vec![
        "--checkpoints".to_string(),
        checkpoints.display().to_string(),
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
/// its `args`, their output to `out/<process>.log`; they wait for two receivers each
/// (the next process and the recorder).
pub(super) fn processes(
    run_id: &str,
    config: &Path,
    out: &Path,
    args: &BTreeMap<&'static str, Vec<String>>,
) -> Result<Children> {
    let exe = std::env::current_exe().context("cannot find the rig executable")?;
    let mut children = Children(Vec::new());
    for role in ROLES {
        let log = out.join(format!("{role}.log"));
        let log_file =
            File::create(&log).with_context(|| format!("cannot create {}", log.display()))?;
        let child = Command::new(&exe)
            .arg(role)
            .args(["--run-id", run_id, "--receivers", "2", "--config"])
            .arg(config)
            .args(args.get(role).map_or(&[][..], |a| &a[..]))
            .stdin(Stdio::null())
            .stdout(log_file.try_clone()?)
            .stderr(log_file)
            .spawn()
            .with_context(|| format!("cannot start the {role} process"))?;
        children.0.push((role, child));
    }
    Ok(children)
}
