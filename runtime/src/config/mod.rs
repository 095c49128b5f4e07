//! The experiment configuration: the system and the sections of the crates that use
//! them — the agent's keys ([`agent::config`]), `[run]` ([`plant::config`]) and
//! `[observer]` ([`observer::config`]) — composed into one [`ExperimentConfig`], its TOML
//! form, and the checks that span sections.
//!
//! A configuration is resolved in layers ([`resolve`]): the preset for (system,
//! algorithm, approximator) — the thesis's tuned values, see [`agent::preset`] — then a
//! user's TOML file, then command-line [`Overrides`]. A key in the user's file that the
//! preset does not have is an error naming the key and the keys that are allowed there.

mod layout;
mod merge;
mod resolve;
#[cfg(test)]
mod task_tests;
#[cfg(test)]
mod tests;

pub use resolve::{Overrides, resolve};

use agent::checkpoint::{self, Origin};
use std::sync::Arc;

use agent::config::{AgentConfig, Algo, ApproxKind, HorizonKind};
use agent::learner::Learner;
use observer::config::{ObserverConfig, ObserverMode};
use plant::config::{ConfigError, RunConfig};
use plant::{SystemName, Task, TaskFile};
use serde::{Deserialize, Serialize};

/// A complete experiment. Its TOML form keeps every key where a user writes it (see
/// `layout`): the system and the learner's choices at the top level, then `[run]`, the
/// agent's sections and `[observer]` (written only when it is not the default).
///
/// The task is read and checked once, when the configuration is made (from a preset,
/// from TOML, or [`ExperimentConfig::on_task`]); [`ExperimentConfig::task`] hands out
/// that one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "layout::Layout", into = "layout::Layout")]
pub struct ExperimentConfig {
    /// The system learned on: the built-in system whose presets the learner starts from
    /// and whose task it learns, unless `task` gives another.
    system: SystemName,
    /// The task learned, when a task file gives it (`task = "FILE"` or `[task]`,
    /// `--task`); `None`: `system`'s shipped task file.
    task: Option<TaskFile>,
    /// The task learned, checked: `task`'s, else `system`'s.
    learned: Learned,
    /// The learner: algorithm, approximator, horizon and their sections.
    pub agent: AgentConfig,
    /// Trials, runs, seed, evaluation, delays.
    pub run: RunConfig,
    /// Sensor and state observer; the default: full state, pass-through.
    pub observer: ObserverConfig,
}

impl ExperimentConfig {
    /// The preset for `(system, algo, approx)` with `horizon` ([`agent::preset`]), with
    /// the default sensor and observer.
    pub fn preset(
        system: SystemName,
        algo: Algo,
        approx: ApproxKind,
        horizon: HorizonKind,
    ) -> Result<Self, ConfigError> {
        let preset = agent::preset::preset(system, algo, approx, horizon)?;
        Ok(Self::from_preset(system, preset))
    }

    /// `preset` on `system`'s task, with the default sensor and observer.
    pub fn from_preset(system: SystemName, preset: agent::preset::Preset) -> Self {
        Self {
            system,
            task: None,
            learned: Learned(Arc::new(Task::new(system))),
            agent: preset.agent,
            run: preset.run,
            observer: ObserverConfig::default(),
        }
    }

    /// The configuration on `system` with the task `task` (`None`: `system`'s shipped
    /// one), which is checked here; an error's key is prefixed with `task.`.
    pub fn on_task(self, system: SystemName, task: Option<TaskFile>) -> Result<Self, ConfigError> {
        let learned = match &task {
            Some(file) => task_of(file)?,
            None => Task::new(system),
        };
        Ok(Self {
            system,
            task,
            learned: Learned(Arc::new(learned)),
            ..self
        })
    }

    /// The system learned on (see [`ExperimentConfig::task`] for the task).
    pub fn system(&self) -> SystemName {
        self.system
    }

    /// The task file, when one gives the task; `None`: the system's shipped task.
    pub fn task_file(&self) -> Option<&TaskFile> {
        self.task.as_ref()
    }

    /// Checks every value against its allowed range and the system's dimensions, section
    /// by section, then what spans sections.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let task = self.task();
        self.run.validate(&task)?;
        self.observer.validate()?;
        if task.simulation.is_none() && self.observer.uses_known_model() {
            return Err(ConfigError::new(
                "observer.model",
                format!(
                    "\"known\" integrates the task's simulation, and task \"{}\" has none: use \"learned\"",
                    task.name
                ),
            ));
        }
        if self.observer.mode == ObserverMode::Predictive
            && self.agent.horizon == HorizonKind::Finite
        {
            return Err(ConfigError::new(
                "observer.mode",
                "\"predictive\" needs an infinite horizon (a finite-horizon agent's time index would be one sample off the plant's)",
            ));
        }
        self.agent.validate(&task)
    }

    /// The task learned: `task`'s, else `system`'s shipped one, as read when the
    /// configuration was made.
    pub fn task(&self) -> Arc<Task> {
        self.learned.0.clone()
    }

    /// The learner the agent's keys describe for the task ([`AgentConfig::resolve`]).
    pub fn learner(&self) -> Result<Learner, ConfigError> {
        self.agent.resolve(&self.learned.0)
    }

    /// Checks that the rig can simulate the task (`rig learn`, the simulated plant); the
    /// error says to learn it against its driver.
    pub fn check_simulated(&self) -> Result<(), ConfigError> {
        match &self.task {
            Some(f) if f.simulation.is_none() => Err(ConfigError::new(
                "task",
                format!(
                    "\"{}\" has no [simulation]: the rig cannot simulate it; learn it against its driver (rig run --plant external --task FILE)",
                    f.name
                ),
            )),
            _ => Ok(()),
        }
    }

    /// The name of the task learned.
    pub fn task_name(&self) -> String {
        match &self.task {
            Some(f) => f.name.clone(),
            None => self.system.to_string(),
        }
    }

    /// The configuration as TOML; for a task without a simulation, a first comment says
    /// where its presets come from (it has no `system`).
    pub fn to_toml(&self) -> String {
        let toml = toml::to_string(self).expect("a configuration always serialises");
        match &self.task {
            Some(t) if t.simulation.is_none() => format!(
                "# Task \"{}\" has no [simulation]: its learner's presets are the pendulum's, carried over by rules (docs/tasks.md, \"Learner presets by rules\").\n{toml}",
                t.name
            ),
            _ => toml,
        }
    }

    /// What a checkpoint of run `run` of this experiment belongs to: its fingerprint is
    /// that of the TOML form without the keys that only say how long and how often to run
    /// (`run.trials`, `run.runs`, `run.eval_every`), so a run can be resumed with more
    /// trials.
    pub fn origin(&self, run: u32) -> Origin {
        let mut c = self.clone();
        c.run.trials = 0;
        c.run.eval_every = 0;
        c.run.runs = 0;
        let a = &self.agent;
        Origin {
            system: self.task_name(),
            learner: format!("{}/{}/{}", a.algo, a.approx, a.horizon),
            seed: self.run.seed,
            run,
            fingerprint: checkpoint::fingerprint(
                toml::to_string(&c).expect("serialises").as_bytes(),
            ),
        }
    }
}

/// The task learned, shared by the configuration's copies. It follows from `system` and
/// `task`, so it takes no part in comparing configurations.
#[derive(Clone)]
struct Learned(Arc<Task>);

impl PartialEq for Learned {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for Learned {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0.name)
    }
}

/// The task of a `[task]` table, checked; an error's key is prefixed with `task.`.
pub(super) fn task_of(file: &TaskFile) -> Result<Task, ConfigError> {
    file.task(None).map_err(|mut e| {
        e.key = if e.key.is_empty() {
            "task".into()
        } else {
            format!("task.{}", e.key)
        };
        e
    })
}
