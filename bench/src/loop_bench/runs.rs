//! The default experiment, timed: in one process (`rig learn --runs 1`), as three
//! processes with the recorder (`rig run`), and as the three processes alone.

use std::path::Path;

use std::time::{Duration, Instant};

use runtime::error::AtFile;
use runtime::output::write_atomic;
use runtime::process::{
    AgentSettings, CpuLayout, NodeSettings, ObserverSettings, PlantSettings, Scheduling, Settings,
    Wait,
};
use wire::Waiting;

use super::{Kill, LoopError, spawn};

/// Wall-clock and CPU time of one run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timed {
    /// From start to the last process's exit.
    pub wall: Duration,
    /// User and system time of all its processes.
    pub cpu: Duration,
}

/// User and system time of this process's children that have been waited for (and of
/// their waited-for descendants).
fn children_cpu() -> Duration {
    // SAFETY: getrusage writes into the zeroed struct it is given.
    let ru = unsafe {
        let mut ru = std::mem::zeroed::<libc::rusage>();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru);
        ru
    };
    let t = |tv: libc::timeval| Duration::new(tv.tv_sec as u64, tv.tv_usec as u32 * 1000);
    t(ru.ru_utime) + t(ru.ru_stime)
}

/// Waits for `kids` (named in order), timing them from `t0`.
fn wait_all(
    mut kids: Kill,
    names: &[&str],
    t0: Instant,
    cpu0: Duration,
    log: &Path,
) -> Result<Timed, LoopError> {
    for (c, name) in kids.0.iter_mut().zip(names) {
        let status = c.wait()?;
        if !status.success() {
            return Err(LoopError::Failed {
                name: name.to_string(),
                status,
                log: log.to_owned(),
            });
        }
    }
    let wall = t0.elapsed();
    kids.0.clear();
    Ok(Timed {
        wall,
        cpu: children_cpu().saturating_sub(cpu0),
    })
}

/// One `exe args…` to completion, its output in `log`.
pub(super) fn timed(exe: &Path, args: &[&str], log: &Path) -> Result<Timed, LoopError> {
    let (cpu0, t0) = (children_cpu(), Instant::now());
    let kids = Kill(vec![spawn(exe, args, log)?]);
    wait_all(kids, &[args[0]], t0, cpu0, log)
}

/// `rig learn --runs 1 --threads 1` of the default experiment with `trials` trials into
/// `dir`.
pub fn in_process(exe: &Path, dir: &Path, trials: u32) -> Result<Timed, LoopError> {
    let t = trials.to_string();
    let d = dir.to_string_lossy();
    let args = [
        "learn",
        "--runs",
        "1",
        "--threads",
        "1",
        "--trials",
        &t,
        "--quiet",
        "--out",
        &d,
    ];
    timed(exe, &args, &dir.with_extension("log"))
}

/// `rig run` of the default experiment with `trials` trials into `dir`, its processes
/// waiting as `waiting` says, placed as `layout` says.
pub fn three_processes(
    exe: &Path,
    dir: &Path,
    trials: u32,
    waiting: Waiting,
    layout: CpuLayout,
) -> Result<Timed, LoopError> {
    let t = trials.to_string();
    let d = dir.to_string_lossy();
    let wait = Wait::process_args(waiting);
    let mut args = vec!["run", "--trials", &t, "--quiet", "--out", &d];
    args.extend(wait.iter().map(String::as_str));
    args.extend(["--cpus", layout.name()]);
    timed(exe, &args, &dir.with_extension("log"))
}

/// The plant, observer and agent processes of the default experiment with `trials`
/// trials, started directly (no recorder), waiting as `waiting` says and placed as
/// `layout` says; with every sample's time from publishing the measurement to receiving
/// its action \[ns\], without the first trial.
pub fn unrecorded(
    exe: &Path,
    dir: &Path,
    trials: u32,
    waiting: Waiting,
    layout: CpuLayout,
) -> Result<(Timed, Vec<u64>), LoopError> {
    std::fs::create_dir_all(dir).at("cannot create", dir)?;
    let mut cfg = runtime::config::resolve(None, &Default::default())?;
    cfg.change_run(|r| r.trials = trials)?;
    let config = dir.join("config.toml");
    write_atomic(&config, &cfg.to_toml())?;
    let steps = dir.join("steps_ns.txt");
    let run_id = format!("loop{}-{}", std::process::id(), wire::now_ns() % 1_000_000);
    let scheduling = Scheduling {
        cpus: Some(layout),
        ..Scheduling::default()
    };
    let node = NodeSettings::new(&run_id, &config, scheduling, waiting);
    let plant = PlantSettings {
        latency_out: Some(steps.clone()),
        ..PlantSettings::new(node.clone())
    };
    let settings = |role: &str| dir.join(format!("{role}.toml"));
    AgentSettings::new(node.clone()).write(&settings("agent"))?;
    ObserverSettings { node }.write(&settings("observer"))?;
    plant.write(&settings("plant"))?;
    let (cpu0, t0) = (children_cpu(), Instant::now());
    let mut kids = Kill(Vec::new());
    for role in ["agent", "observer", "plant"] {
        let file = settings(role).to_string_lossy().into_owned();
        let log = dir.join(format!("{role}.log"));
        kids.0.push(spawn(exe, &[role, "--node", &file], &log)?);
    }
    let timed = wait_all(kids, &["agent", "observer", "plant"], t0, cpu0, dir)?;
    let text = std::fs::read_to_string(&steps).at("cannot read", &steps)?;
    let mut ns: Vec<u64> = text.lines().filter_map(|l| l.parse().ok()).collect();
    let per_trial = cfg.task().steps_per_trial() + 1;
    ns.drain(..per_trial.min(ns.len()));
    Ok((timed, ns))
}
