//! Resolution: preset ← file ← command line, into a validated [`ExperimentConfig`].

use std::path::Path;

use agent::config::{Algo, ApproxKind, EvictionRule, HorizonKind, LstdPrior};
use agent::preset::by_task::{self, Choice};
use observer::config::{ObserverConfig, ObserverKind, ObserverMode, ObserverModel, SensorKind};
use plant::config::{ConfigError, RunConfig};
use plant::{SystemName, TaskFile};

use super::file::ExperimentFile;
use super::merge::{add_optional_sections, add_schedule_keys, check_choice, choose, merge};
use super::{ExperimentConfig, Sections};

/// Command-line choices and overrides, applied over preset and file: the experiment
/// flags of `rig learn`, `rig run` and `rig config`.
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// System to learn on: pendulum (§3.6, §6.4.1), arm-vertical (Case I, §5.3),
    /// arm-horizontal (Case II, §5.4), arm-6.4 (the manipulator of §6.4.2: ±0.1 N m,
    /// ±1.2 rad operating range, four start states) or double-integrator (LQR check)
    /// [default: pendulum].
    #[cfg_attr(feature = "cli", arg(long, value_enum))]
    pub system: Option<SystemName>,
    /// A task file: the system as the rig needs to know it — states, actions and their
    /// bounds, sampling time, trial, start states, reward, operating range (see
    /// docs/tasks.md; the built-in systems' files are in plant/tasks/). Its
    /// `[simulation]` names the built-in system it runs on and whose learner presets it
    /// takes (the configuration's `task` key).
    #[cfg_attr(feature = "cli", arg(long, value_name = "FILE"))]
    pub task: Option<std::path::PathBuf>,
    /// Algorithm: sac (Algorithm 1), mlac (Algorithm 2), rmac (Algorithm 3), vgbp
    /// (Algorithm 7) or sarsa (§6.2) [default: mlac].
    #[cfg_attr(feature = "cli", arg(long, value_enum))]
    pub algo: Option<Algo>,
    /// Function approximator: llr, rbf, tiles (sac only) or lstd (vgbp only: an LSTD
    /// critic on RBFs with an LLR process model); sarsa uses rbf [default: llr].
    #[cfg_attr(feature = "cli", arg(long, value_enum))]
    pub approx: Option<ApproxKind>,
    /// Horizon of the cost function. `infinite`: discounted rewards without end
    /// (Chapters 3, 5, 6). `finite`: a trial is the horizon — its return is the rewards
    /// plus a terminal reward τ_N = −xᵀQx of the final state, and actor and critic take
    /// time as an extra input (Chapter 4, Eq. 4.6; sac, mlac, rmac with rbf: SAC-FH,
    /// MLAC-FH, RMAC-FH, Algorithms 4–6, with the parameters of §4.4) [default:
    /// infinite].
    #[cfg_attr(feature = "cli", arg(long, value_enum))]
    pub horizon: Option<HorizonKind>,
    /// Trials per run [preset: 400 for the pendulum (vgbp, sarsa: 200; finite horizon:
    /// 600), 600 for the arms (vgbp, sarsa: 200)].
    #[cfg_attr(feature = "cli", arg(long))]
    pub trials: Option<u32>,
    /// Independent runs [preset: 30 for the pendulum (vgbp, sarsa, finite horizon: 20),
    /// 20 for the arm].
    #[cfg_attr(feature = "cli", arg(long))]
    pub runs: Option<u32>,
    /// Seed of every random stream of every run [preset: 1].
    #[cfg_attr(feature = "cli", arg(long))]
    pub seed: Option<u64>,
    /// A greedy evaluation trial (no exploration, no learning) after every N trials; 0
    /// disables [preset: 10; vgbp, sarsa: 5; vgbp on arm-6.4: 4]. With several start
    /// states (arm-6.4) the evaluation runs from each and reports the mean.
    #[cfg_attr(feature = "cli", arg(long))]
    pub eval_every: Option<u32>,
    /// What the plant's sensor measures: full (the state) or angle (an encoder: angles
    /// quantised to `observer.counts_per_rev`, default 4096, plus optional Gaussian noise
    /// `observer.noise_std`; velocities must be estimated) [default: full].
    #[cfg_attr(feature = "cli", arg(long, value_enum))]
    pub sensor: Option<SensorKind>,
    /// State observer: pass-through (full sensor only), finite-difference (backward
    /// difference, low-pass `observer.filter`) or predictive (model prediction corrected by
    /// the measured angle; `observer.model` = learned (LLR) or known (RK4 of the plant),
    /// velocity gain `observer.gain`) [default: pass-through].
    #[cfg_attr(feature = "cli", arg(long, value_enum))]
    pub observer: Option<ObserverKind>,
    /// Sample-to-actuation delay [ms], in [0, Ts): over each sample period the previous
    /// action stays in effect this long, then the new one — deterministic, for delay
    /// studies (`run.delay_ms`; lockstep only) [default: 0].
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "MS", conflicts_with = "delay_from")
    )]
    pub delay_ms: Option<f64>,
    /// A recorded distribution of sample-to-actuation delays: a CSV file (header row, one
    /// delay per row) — e.g. `rig latency`'s latency.csv or a real driver's recording.
    /// Each sample's delay is drawn from it with the run seed (its own stream) and applied
    /// as `--delay-ms` is; every value must be in [0, Ts) (`run.delay_from`; lockstep
    /// only; exclusive with `--delay-ms`).
    #[cfg_attr(feature = "cli", arg(long, value_name = "FILE"))]
    pub delay_from: Option<String>,
    /// The column of `--delay-from` holding the delays; the unit is the name's suffix
    /// (_s, _ms, _us, _ns; latency.csv's sample_to_actuation is ns) (`run.delay_column`)
    /// [default: delay_ms, else sample_to_actuation].
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "NAME", requires = "delay_from")
    )]
    pub delay_column: Option<String>,
    /// Timing: direct (the agent acts on x̂_k; its action takes effect within the interval,
    /// after the delay) or predictive (the agent acts on the observer's prediction
    /// x̂_{k+1|k}; its action is applied at the next sample instant, so a delay below Ts
    /// does not reach the plant; needs `--observer predictive`) (`observer.mode`)
    /// [default: direct].
    #[cfg_attr(feature = "cli", arg(long, value_enum))]
    pub observer_mode: Option<ObserverMode>,
}

impl Overrides {
    /// Sets the values given on the command line (all but the choices of preset) in the
    /// sections they belong to.
    fn apply(&self, run: &mut RunConfig, observer: &mut ObserverConfig) {
        if let Some(v) = self.trials {
            run.trials = v;
        }
        if let Some(v) = self.runs {
            run.runs = v;
        }
        if let Some(v) = self.seed {
            run.seed = v;
        }
        if let Some(v) = self.eval_every {
            run.eval_every = v;
        }
        if let Some(v) = self.delay_ms {
            run.delay_ms = v;
        }
        if let Some(v) = &self.delay_from {
            run.delay_from.clone_from(v);
        }
        if let Some(v) = &self.delay_column {
            run.delay_column.clone_from(v);
        }
        if let Some(v) = self.sensor {
            observer.sensor = v;
        }
        if let Some(v) = self.observer {
            observer.observer = v;
        }
        if let Some(v) = self.observer_mode {
            observer.mode = v;
        }
    }
}

/// Which preset: the system and the learner, and a task the rig does not simulate, whose
/// preset the pendulum's gives by rules.
struct PresetChoice {
    system: SystemName,
    driven: Option<plant::Task>,
    algo: Algo,
    approx: ApproxKind,
    horizon: HorizonKind,
    /// No learner was named (no `algo`, `approx`, `horizon`, `[lqr]` or `[planning]`, by
    /// file or flag) for a task file that is not one of the thesis's own: the task
    /// chooses it ([`agent::preset::by_task`]).
    by_task: Option<plant::Task>,
    /// The task file given by `--task`.
    task_file: Option<std::path::PathBuf>,
}

/// The keys of a configuration file that name a learner: with none of them (and no
/// `--algo`, `--approx`, `--horizon`), a task the rig does not simulate gets the learner
/// [`agent::preset::by_task`] chooses.
const LEARNER_KEYS: [&str; 5] = ["algo", "approx", "horizon", "lqr", "planning"];

impl PresetChoice {
    /// The command line's choices, else the file's top-level keys, else the defaults
    /// (the pendulum, MLAC, LLR, infinite horizon); with a task file, the system is the
    /// one it simulates.
    fn of(user: &toml::Table, o: &Overrides, task: Option<&TaskFile>) -> Result<Self, ConfigError> {
        let pick = |key: &str| -> Result<Option<String>, ConfigError> {
            match user.get(key) {
                None => Ok(None),
                Some(toml::Value::String(s)) => Ok(Some(s.clone())),
                Some(v) => Err(ConfigError::new(key, format!("{v} must be a string"))),
            }
        };
        let system = choose("system", o.system, pick("system")?, SystemName::Pendulum)?;
        let explicit = o.system.is_some() || user.contains_key("system");
        let driven = match task {
            Some(t) if t.simulation.is_none() => Some(super::task_of(t)?),
            _ => None,
        };
        let named = o.algo.is_some()
            || o.approx.is_some()
            || o.horizon.is_some()
            || LEARNER_KEYS.iter().any(|k| user.contains_key(*k));
        Ok(Self {
            by_task: match task {
                Some(t) if !named && !is_thesis_task(t) => Some(super::task_of(t)?),
                _ => None,
            },
            task_file: o.task.clone(),
            system: match task {
                Some(t) => simulated_system(t, explicit.then_some(system))?,
                None => system,
            },
            driven,
            algo: choose("algo", o.algo, pick("algo")?, Algo::Mlac)?,
            approx: choose("approx", o.approx, pick("approx")?, ApproxKind::Llr)?,
            horizon: choose(
                "horizon",
                o.horizon,
                pick("horizon")?,
                HorizonKind::Infinite,
            )?,
        })
    }

    /// The preset as a TOML table with every key a user may set: also those it does not
    /// write when they have their default values; and the task's choice of learner, if it
    /// made it.
    fn table(&self) -> Result<(toml::Table, Option<Choice>), ConfigError> {
        let (algo, approx, horizon) = (self.algo, self.approx, self.horizon);
        let (preset, choice) = match (&self.by_task, &self.driven) {
            (Some(task), _) => {
                // The task's own keys are at fault: its file, when `--task` gave one.
                let (preset, choice) = by_task::learner(task).map_err(|mut e| {
                    e.file.clone_from(&self.task_file);
                    e
                })?;
                (preset, Some(choice))
            }
            (None, None) => (
                agent::preset::preset(self.system, algo, approx, horizon)?,
                None,
            ),
            (None, Some(task)) => (agent::preset::for_task(task, algo, approx, horizon)?, None),
        };
        let sections = Sections {
            agent: preset.agent,
            run: preset.run,
            observer: ObserverConfig::default(),
        };
        let layout = ExperimentFile::new(Some(self.system), sections, None);
        let mut table = toml::Table::try_from(&layout).expect("a preset always serialises");
        // The observer section is written only when it differs from the default; a user's
        // file may still set any of its keys.
        table.entry("observer").or_insert_with(|| {
            toml::Value::Table(
                toml::Table::try_from(ObserverConfig::default()).expect("serialises"),
            )
        });
        // So are the optional keys of `[run]`.
        if let Some(toml::Value::Table(run)) = table.get_mut("run") {
            for key in ["delay_from", "delay_column"] {
                run.entry(key)
                    .or_insert_with(|| toml::Value::String(String::new()));
            }
        }
        // And an LSTD critic's prior.
        if let Some(toml::Value::Table(critic)) = table.get_mut("critic")
            && critic.contains_key("initial_a")
        {
            critic
                .entry("prior")
                .or_insert_with(|| toml::Value::String("zero".into()));
        }
        Ok((table, choice))
    }
}

/// Whether `task` is one of the thesis's own, shipped in `plant/tasks/` (its presets are
/// the thesis's, whatever the task would choose).
fn is_thesis_task(task: &TaskFile) -> bool {
    task.simulation
        .as_ref()
        .is_some_and(|sim| plant::task::builtin::task(sim.system).file == *task)
}

/// The built-in system whose presets a task file's learner starts from: the one it
/// simulates, else the pendulum, whose presets [`agent::preset::rules`] carry over. The
/// error names a system given beside the task (`explicit`) that differs.
fn simulated_system(
    task: &TaskFile,
    explicit: Option<SystemName>,
) -> Result<SystemName, ConfigError> {
    let (system, why) = match &task.simulation {
        Some(sim) => (sim.system, "simulates"),
        None => (SystemName::Pendulum, "takes its presets from (by rules)"),
    };
    match explicit {
        Some(s) if s != system => Err(ConfigError::new(
            "system",
            format!(
                "\"{s}\" differs from the system task \"{}\" {why}, \"{system}\": give one of --system and --task",
                task.name
            ),
        )),
        _ => Ok(system),
    }
}

/// The task file an experiment runs on, and removes the `task` key from `user`:
/// `--task`, else the file's `task` — a path relative to the file's folder, or a `[task]`
/// table — else none. A task read from its own file is checked here, so that an error
/// names that file.
fn task_file(
    user: &mut toml::Table,
    o: &Overrides,
    file: Option<&Path>,
) -> Result<Option<TaskFile>, ConfigError> {
    let read = |path: &Path| {
        let f = TaskFile::read(path)?;
        f.task(Some(path))?;
        Ok(Some(f))
    };
    let key = user.remove("task");
    if let Some(path) = &o.task {
        return read(path);
    }
    match key {
        None => Ok(None),
        Some(toml::Value::String(s)) => {
            let folder = file.and_then(Path::parent).unwrap_or(Path::new(""));
            read(&folder.join(s))
        }
        Some(toml::Value::Table(t)) => toml::Value::Table(t)
            .try_into()
            .map(Some)
            .map_err(|e: toml::de::Error| ConfigError::new("task", e.message())),
        Some(v) => Err(ConfigError::new(
            "task",
            format!("{v} must be a task file's path or a [task] table"),
        )),
    }
}

/// Resolves preset ← file ← overrides into a validated configuration.
pub fn resolve(
    file: Option<(&Path, &str)>,
    o: &Overrides,
) -> Result<ExperimentConfig, ConfigError> {
    resolve_with_choice(file, o).map(|(config, _)| config)
}

/// [`resolve`], and the learner the task chose when none was named (a task the rig does
/// not simulate, [`agent::preset::by_task`]): what `rig` says in one line.
pub fn resolve_with_choice(
    file: Option<(&Path, &str)>,
    o: &Overrides,
) -> Result<(ExperimentConfig, Option<Choice>), ConfigError> {
    let path = file.map(|(p, _)| p.to_path_buf());
    let with_file = |mut e: ConfigError| {
        if e.file.is_none() {
            e.file = path.clone();
        }
        e
    };
    let mut user: toml::Table = match file {
        Some((_, text)) => toml::from_str(text).map_err(|e| {
            with_file(ConfigError::new(
                "",
                format!("not valid TOML: {}", e.message()),
            ))
        })?,
        None => toml::Table::new(),
    };
    let task = task_file(&mut user, o, path.as_deref()).map_err(with_file)?;
    let choice = PresetChoice::of(&user, o, task.as_ref()).map_err(with_file)?;
    let (mut merged, chosen) = choice.table().map_err(with_file)?;
    add_optional_sections(&mut merged, &mut user);
    add_schedule_keys(&mut merged, &mut user).map_err(with_file)?;
    merge(&mut merged, user, "").map_err(with_file)?;
    check_choices(&merged).map_err(with_file)?;
    let mut layout: ExperimentFile = toml::Value::Table(merged)
        .try_into()
        .map_err(|e: toml::de::Error| with_file(ConfigError::new("", e.message())))?;
    (layout.system, layout.task) = (Some(choice.system), task);
    (layout.algo, layout.approx, layout.horizon) = (choice.algo, choice.approx, choice.horizon);
    o.apply(&mut layout.run, &mut layout.observer);
    let config = ExperimentConfig::try_from(layout).map_err(with_file)?;
    Ok((config, chosen))
}

/// Checks the spellings of the choice keys in sections (`[observer]`, an LLR memory's
/// eviction, an LSTD critic's prior), so that a wrong one is reported with its key and the allowed values.
fn check_choices(merged: &toml::Table) -> Result<(), ConfigError> {
    check_choice::<SensorKind>(merged, "observer", "sensor")?;
    check_choice::<ObserverKind>(merged, "observer", "observer")?;
    check_choice::<ObserverModel>(merged, "observer", "model")?;
    check_choice::<ObserverMode>(merged, "observer", "mode")?;
    for section in ["actor", "critic", "model"] {
        check_choice::<EvictionRule>(merged, section, "eviction")?;
    }
    check_choice::<LstdPrior>(merged, "critic", "prior")
}
