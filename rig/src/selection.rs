//! Which experiment: the preset for (system, algorithm, approximator), a TOML file
//! overriding any of its keys, and flags overriding both — shared by `rig learn`, `rig
//! run` and `rig config`.

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;
use runtime::config::{ExperimentConfig, Overrides, resolve, resolve_with_choice};

/// Which experiment: the preset for (system, algorithm, approximator), a TOML file
/// overriding any of its keys, and flags overriding both.
#[derive(Args)]
pub struct Selection {
    /// The experiment flags.
    #[command(flatten)]
    overrides: Overrides,
    /// TOML file overriding preset values; see `rig config` for every key.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

/// The experiment `s` selects: preset ← `--config` file ← flags, validated; the error
/// names the file or says it came from the command line or the preset. Where the task
/// chose the learner (none named, [`agent::preset::by_task`]), one line on stderr says
/// which and why.
pub fn resolve_selection(s: &Selection) -> Result<ExperimentConfig> {
    let text = match &s.config {
        Some(p) => Some(
            std::fs::read_to_string(p).map_err(|e| anyhow!("{}: cannot read: {e}", p.display()))?,
        ),
        None => None,
    };
    let o = Overrides {
        // An absolute path, so that the processes of `rig run` and the recorded
        // configuration find the file wherever they run.
        delay_from: s.overrides.delay_from.as_ref().map(|p| {
            std::path::absolute(p).map_or_else(|_| p.clone(), |a| a.display().to_string())
        }),
        ..s.overrides.clone()
    };
    let (config, choice) = resolve_with_choice(s.config.as_deref().zip(text.as_deref()), &o)
        .map_err(|e| match &e.file {
            Some(_) => anyhow!(e),
            None => anyhow!("{e} (from the command line or the preset)"),
        })?;
    if let Some(choice) = choice {
        eprintln!("{choice}");
    }
    Ok(config)
}

/// The experiment flags given besides `--trials` (which `rig run --resume` refuses).
fn experiment_flags(s: &Selection) -> Vec<&'static str> {
    let o = &s.overrides;
    [
        ("--system", o.system.is_some()),
        ("--task", o.task.is_some()),
        ("--algo", o.algo.is_some()),
        ("--approx", o.approx.is_some()),
        ("--horizon", o.horizon.is_some()),
        ("--runs", o.runs.is_some()),
        ("--seed", o.seed.is_some()),
        ("--eval-every", o.eval_every.is_some()),
        ("--sensor", o.sensor.is_some()),
        ("--observer", o.observer.is_some()),
        ("--delay-ms", o.delay_ms.is_some()),
        ("--delay-from", o.delay_from.is_some()),
        ("--delay-column", o.delay_column.is_some()),
        ("--observer-mode", o.observer_mode.is_some()),
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
        trials: s.overrides.trials,
        ..Overrides::default()
    };
    Ok(resolve(Some((&path, &text)), &o)?)
}
