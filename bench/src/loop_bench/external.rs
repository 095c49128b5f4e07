//! The loop against external drivers in lockstep (`rig bench-loop --external`): `rig run
//! --plant external` against `rig sim-driver --clock lockstep`, the Python example driver
//! (`examples/python_driver/driver.py --clock lockstep`) and the Gymnasium adapter
//! (`examples/gymnasium/adapter.py`, Pendulum-v1), each driver started once and served
//! `--repetitions` runs; the Gymnasium environment's own `env.step` loop in Python
//! (`bench/scripts/env_step.py`, as many steps) is the adapter's yardstick.

use std::path::{Path, PathBuf};
use std::process::Command;

use runtime::config::{Overrides, resolve};

use super::runs::{Timed, timed};
use super::{Kill, LoopError, median, samples_per_run, spawn};

/// Where the external drivers come from.
#[derive(Clone, Debug)]
pub struct ExternalOptions {
    /// The Python with the iceoryx2 bindings (and gymnasium, for the adapter); `None`:
    /// the Rust driver only.
    pub python: Option<PathBuf>,
    /// The repository's root (its `examples/` and `bench/scripts/`).
    pub root: PathBuf,
}

/// One external driver's runs.
#[derive(Clone, Debug)]
pub struct ExternalCase {
    /// What served the runs.
    pub name: &'static str,
    /// Its name in `loop.csv`.
    pub key: &'static str,
    /// `rig run --plant external` against it, per repetition.
    pub runs: Vec<Timed>,
    /// Samples per run.
    pub samples: usize,
    /// The yardstick's time per sample \[µs\], per repetition (each measured right after
    /// the run), if this case has its own (else the built-in `rig run`'s).
    pub yardstick: Vec<f64>,
}

impl ExternalCase {
    /// Median wall time per sample \[µs\].
    pub fn per_sample_us(&self) -> f64 {
        median(&self.runs).wall.as_secs_f64() * 1e6 / self.samples as f64
    }

    /// The median of the yardstick's time per sample \[µs\], if it has one.
    pub fn yardstick_us(&self) -> Option<f64> {
        let mut y = self.yardstick.clone();
        y.sort_by(f64::total_cmp);
        y.get(y.len() / 2).copied()
    }
}

/// A driver kind: its name, its command line (the driver id appended), the run's extra
/// flags.
struct Kind {
    name: &'static str,
    key: &'static str,
    driver: Vec<String>,
    run: Vec<String>,
    task: Option<PathBuf>,
}

fn kinds(exe: &Path, o: &ExternalOptions) -> Vec<Kind> {
    let s = |v: &[&str]| v.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    let path = |p: &str| o.root.join(p).to_string_lossy().into_owned();
    let mut k = vec![Kind {
        name: "rig sim-driver --clock lockstep",
        key: "sim_driver_lockstep",
        driver: vec![
            exe.to_string_lossy().into_owned(),
            "sim-driver".into(),
            "--clock".into(),
            "lockstep".into(),
        ],
        run: Vec::new(),
        task: None,
    }];
    if let Some(py) = &o.python {
        let py = py.to_string_lossy().into_owned();
        k.push(Kind {
            name: "Python driver --clock lockstep",
            key: "python_driver_lockstep",
            driver: vec![
                py.clone(),
                path("examples/python_driver/driver.py"),
                "--clock".into(),
                "lockstep".into(),
            ],
            run: Vec::new(),
            task: None,
        });
        let task = o.root.join("examples/gymnasium/pendulum-v1.toml");
        k.push(Kind {
            name: "Gymnasium adapter, Pendulum-v1",
            key: "gymnasium_adapter",
            driver: vec![
                py,
                path("examples/gymnasium/adapter.py"),
                "--mapping".into(),
                path("examples/gymnasium/pendulum_v1.py"),
            ],
            run: [s(&["--task"]), vec![task.to_string_lossy().into_owned()]].concat(),
            task: Some(task),
        });
        k.last_mut().unwrap().run.extend(s(&["--algo", "sac"]));
    }
    k
}

/// Runs every external case `repetitions` times with `trials` trials, in `out`.
pub fn external_cases(
    exe: &Path,
    out: &Path,
    trials: u32,
    repetitions: usize,
    o: &ExternalOptions,
    progress: &dyn Fn(&str),
) -> Result<Vec<ExternalCase>, LoopError> {
    let mut cases = Vec::new();
    for (i, kind) in kinds(exe, o).into_iter().enumerate() {
        progress(kind.name);
        let id = format!("bench{}-{i}", std::process::id());
        let mut cmd = kind.driver.clone();
        cmd.extend(["--driver-id".to_string(), id.clone()]);
        let log = out.join(format!("driver-{i}.log"));
        let args: Vec<&str> = cmd[1..].iter().map(String::as_str).collect();
        let _driver = Kill(vec![spawn(Path::new(&cmd[0]), &args, &log)?]);
        served(&id, &log)?;
        let cfg = resolve(
            None,
            &Overrides {
                task: kind.task.clone(),
                ..Default::default()
            },
        )?;
        let samples = samples_per_run(&cfg, trials);
        let t = trials.to_string();
        let (mut runs, mut yardstick) = (Vec::new(), Vec::new());
        for r in 0..repetitions.max(1) {
            let dir = out.join(format!("external-{i}-{r}"));
            let d = dir.to_string_lossy();
            let mut a = vec!["run", "--plant", "external", "--driver", &id];
            a.extend(["--trials", &t, "--quiet", "--out", &d]);
            a.extend(kind.run.iter().map(String::as_str));
            runs.push(timed(exe, &a, &dir.with_extension("log"))?);
            if kind.task.is_some() {
                let trial_steps = cfg.task().steps_per_trial() + 1;
                yardstick.push(env_step_us(o, trial_steps, samples)?);
            }
        }
        cases.push(ExternalCase {
            name: kind.name,
            key: kind.key,
            runs,
            samples,
            yardstick,
        });
    }
    Ok(cases)
}

/// Waits until driver `id` publishes its info (started, its imports done), so that the
/// runs' times leave its start out; `log` is its output.
fn served(id: &str, log: &Path) -> Result<(), LoopError> {
    let bus = wire::Bus::join(&format!("benchwait{}", std::process::id()), "rig")?;
    let watch = driver::link::DriverWatch::open(&bus, id)?;
    let timeout = std::time::Duration::from_secs(60);
    driver::link::wait_info(
        &bus,
        &watch.info,
        id,
        timeout,
        false,
        "",
        &wire::Monotonic::host(),
    )
    .map_err(|source| LoopError::NotServed {
        id: id.to_owned(),
        log: log.to_owned(),
        source: Box::new(source),
    })?;
    Ok(())
}

/// `bench/scripts/env_step.py`'s time per step of Pendulum-v1 over (at least) `samples`
/// steps in trials of `trial_steps` \[µs\].
fn env_step_us(o: &ExternalOptions, trial_steps: usize, samples: usize) -> Result<f64, LoopError> {
    let py = o.python.as_ref().ok_or(LoopError::NoPython)?;
    let trials = samples.div_ceil(trial_steps);
    let out = Command::new(py)
        .arg(o.root.join("bench/scripts/env_step.py"))
        .args(["--trials", &trials.to_string()])
        .args(["--trial-steps", &trial_steps.to_string()])
        .output()
        .map_err(LoopError::YardstickStart)?;
    let text = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(LoopError::YardstickFailed(format!(
            "{text}{}",
            String::from_utf8_lossy(&out.stderr)
        )));
    }
    text.split(", ")
        .find_map(|part| part.strip_suffix(" us per step\n"))
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| LoopError::YardstickPrinted(text.into_owned()))
}
