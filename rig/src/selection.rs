//! Which experiment: the preset for (system, algorithm, approximator), a TOML file
//! overriding any of its keys, and flags overriding both — shared by `rig learn`, `rig
//! run` and `rig config`.

use std::path::PathBuf;

use agent::config::{Algo, ApproxKind, HorizonKind};
use anyhow::{Result, anyhow};
use clap::Args;
use observer::config::{ObserverKind, ObserverMode, SensorKind};
use plant::SystemName;
use plant::config::Choice;
use runtime::config::{ExperimentConfig, Overrides, resolve};

/// Which experiment: the preset for (system, algorithm, approximator), a TOML file
/// overriding any of its keys, and flags overriding both.
#[derive(Args)]
pub struct Selection {
    /// System to learn on: pendulum (§3.6, §6.4.1), arm-vertical (Case I, §5.3),
    /// arm-horizontal (Case II, §5.4), arm-6.4 (the manipulator of §6.4.2: ±0.1 N m,
    /// ±1.2 rad operating range, four start states) or double-integrator (LQR check)
    /// [default: pendulum].
    #[arg(long, value_parser = SystemName::parse)]
    system: Option<SystemName>,
    /// A task file: the system as the rig needs to know it — states, actions and their
    /// bounds, sampling time, trial, start states, reward, operating range (see
    /// docs/tasks.md; the built-in systems' files are in plant/tasks/). Its
    /// `[simulation]` names the built-in system it runs on and whose learner presets it
    /// takes (the configuration's `task` key).
    #[arg(long, value_name = "FILE")]
    task: Option<PathBuf>,
    /// Algorithm: sac (Algorithm 1), mlac (Algorithm 2), rmac (Algorithm 3), vgbp
    /// (Algorithm 7) or sarsa (§6.2) [default: mlac].
    #[arg(long, value_parser = Algo::parse)]
    algo: Option<Algo>,
    /// Function approximator: llr, rbf, tiles (sac only) or lstd (vgbp only: an LSTD
    /// critic on RBFs with an LLR process model); sarsa uses rbf [default: llr].
    #[arg(long, value_parser = ApproxKind::parse)]
    approx: Option<ApproxKind>,
    /// Horizon of the cost function. `infinite`: discounted rewards without end
    /// (Chapters 3, 5, 6). `finite`: a trial is the horizon — its return is the rewards
    /// plus a terminal reward τ_N = −xᵀQx of the final state, and actor and critic take
    /// time as an extra input (Chapter 4, Eq. 4.6; sac, mlac, rmac with rbf: SAC-FH,
    /// MLAC-FH, RMAC-FH, Algorithms 4–6, with the parameters of §4.4) [default:
    /// infinite].
    #[arg(long, value_parser = HorizonKind::parse)]
    horizon: Option<HorizonKind>,
    /// Trials per run [preset: 400 for the pendulum (vgbp, sarsa: 200; finite horizon:
    /// 600), 600 for the arms (vgbp, sarsa: 200)].
    #[arg(long)]
    trials: Option<u32>,
    /// Independent runs [preset: 30 for the pendulum (vgbp, sarsa, finite horizon: 20),
    /// 20 for the arm].
    #[arg(long)]
    runs: Option<u32>,
    /// Seed of every random stream of every run [preset: 1].
    #[arg(long)]
    seed: Option<u64>,
    /// A greedy evaluation trial (no exploration, no learning) after every N trials; 0
    /// disables [preset: 10; vgbp, sarsa: 5; vgbp on arm-6.4: 4]. With several start
    /// states (arm-6.4) the evaluation runs from each and reports the mean.
    #[arg(long)]
    eval_every: Option<u32>,
    /// What the plant's sensor measures: full (the state) or angle (an encoder: angles
    /// quantised to `observer.counts_per_rev`, default 4096, plus optional Gaussian noise
    /// `observer.noise_std`; velocities must be estimated) [default: full].
    #[arg(long, value_parser = SensorKind::parse)]
    sensor: Option<SensorKind>,
    /// State observer: pass-through (full sensor only), finite-difference (backward
    /// difference, low-pass `observer.filter`) or predictive (model prediction corrected by
    /// the measured angle; `observer.model` = learned (LLR) or known (RK4 of the plant),
    /// velocity gain `observer.gain`) [default: pass-through].
    #[arg(long, value_parser = ObserverKind::parse)]
    observer: Option<ObserverKind>,
    /// Sample-to-actuation delay [ms], in [0, Ts): over each sample period the previous
    /// action stays in effect this long, then the new one — deterministic, for delay
    /// studies (`run.delay_ms`; lockstep only) [default: 0].
    #[arg(long, value_name = "MS", conflicts_with = "delay_from")]
    delay_ms: Option<f64>,
    /// A recorded distribution of sample-to-actuation delays: a CSV file (header row, one
    /// delay per row) — e.g. `rig latency`'s latency.csv or a real driver's recording.
    /// Each sample's delay is drawn from it with the run seed (its own stream) and applied
    /// as `--delay-ms` is; every value must be in [0, Ts) (`run.delay_from`; lockstep
    /// only; exclusive with `--delay-ms`).
    #[arg(long, value_name = "FILE")]
    delay_from: Option<PathBuf>,
    /// The column of `--delay-from` holding the delays; the unit is the name's suffix
    /// (_s, _ms, _us, _ns; latency.csv's sample_to_actuation is ns) (`run.delay_column`)
    /// [default: delay_ms, else sample_to_actuation].
    #[arg(long, value_name = "NAME", requires = "delay_from")]
    delay_column: Option<String>,
    /// Timing: direct (the agent acts on x̂_k; its action takes effect within the interval,
    /// after the delay) or predictive (the agent acts on the observer's prediction
    /// x̂_{k+1|k}; its action is applied at the next sample instant, so a delay below Ts
    /// does not reach the plant; needs `--observer predictive`) (`observer.mode`)
    /// [default: direct].
    #[arg(long, value_parser = ObserverMode::parse)]
    observer_mode: Option<ObserverMode>,
    /// TOML file overriding preset values; see `rig config` for every key.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

/// The experiment `s` selects: preset ← `--config` file ← flags, validated; the error
/// names the file or says it came from the command line or the preset.
pub fn resolve_selection(s: &Selection) -> Result<ExperimentConfig> {
    let text = match &s.config {
        Some(p) => Some(
            std::fs::read_to_string(p).map_err(|e| anyhow!("{}: cannot read: {e}", p.display()))?,
        ),
        None => None,
    };
    let o = Overrides {
        system: s.system,
        task: s.task.clone(),
        algo: s.algo,
        approx: s.approx,
        horizon: s.horizon,
        trials: s.trials,
        runs: s.runs,
        seed: s.seed,
        eval_every: s.eval_every,
        sensor: s.sensor,
        observer: s.observer,
        delay_ms: s.delay_ms,
        // An absolute path, so that the processes of `rig run` and the recorded
        // configuration find the file wherever they run.
        delay_from: s
            .delay_from
            .as_ref()
            .map(|p| std::path::absolute(p).unwrap_or_else(|_| p.clone()))
            .map(|p| p.display().to_string()),
        delay_column: s.delay_column.clone(),
        observer_mode: s.observer_mode,
    };
    resolve(s.config.as_deref().zip(text.as_deref()), &o).map_err(|e| match &e.file {
        Some(_) => anyhow!(e),
        None => anyhow!("{e} (from the command line or the preset)"),
    })
}

/// The experiment flags given besides `--trials` (which `rig run --resume` refuses).
fn experiment_flags(s: &Selection) -> Vec<&'static str> {
    [
        ("--system", s.system.is_some()),
        ("--task", s.task.is_some()),
        ("--algo", s.algo.is_some()),
        ("--approx", s.approx.is_some()),
        ("--horizon", s.horizon.is_some()),
        ("--runs", s.runs.is_some()),
        ("--seed", s.seed.is_some()),
        ("--eval-every", s.eval_every.is_some()),
        ("--sensor", s.sensor.is_some()),
        ("--observer", s.observer.is_some()),
        ("--delay-ms", s.delay_ms.is_some()),
        ("--delay-from", s.delay_from.is_some()),
        ("--delay-column", s.delay_column.is_some()),
        ("--observer-mode", s.observer_mode.is_some()),
        ("--config", s.config.is_some()),
    ]
    .into_iter()
    .filter_map(|(flag, given)| given.then_some(flag))
    .collect()
}

/// The configuration of a run to resume: `DIR/config.toml`, with `--trials` if given.
pub fn resume_selection(dir: &std::path::Path, s: &Selection) -> Result<ExperimentConfig> {
    let flags = experiment_flags(s);
    if !flags.is_empty() {
        return Err(anyhow!(
            "`--resume` continues the run with its own configuration ({}); {} cannot change it (only `--trials` can)",
            dir.join("config.toml").display(),
            flags.join(", ")
        ));
    }
    let path = dir.join("config.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        anyhow!(
            "{}: cannot read ({e}); is {} a `rig run` directory?",
            path.display(),
            dir.display()
        )
    })?;
    let o = Overrides {
        trials: s.trials,
        ..Overrides::default()
    };
    Ok(resolve(Some((&path, &text)), &o)?)
}
