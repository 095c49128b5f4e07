//! The experiment configuration: the system and the sections of the crates that use
//! them — the agent's keys ([`agent::config`]), `[run]` ([`plant::config`]) and
//! `[observer]` ([`observer::config`]) — composed into one [`ExperimentConfig`], its TOML
//! form, and the checks that span sections.
//!
//! A configuration is resolved in layers ([`resolve`]): the preset for (system,
//! algorithm, approximator) — the thesis's tuned values, see [`agent::preset`] — then a
//! user's TOML file, then command-line [`Overrides`]. A key in the user's file that the
//! preset does not have is an error naming the key and the keys that are allowed there.
//!
//! A configuration is checked whole when it is made and whenever a section changes
//! ([`ExperimentConfig::change_agent`], `change_run`, `change_observer`): every
//! configuration there is satisfies every rule, and its learner is resolved once.

mod file;
mod merge;
mod resolve;
#[cfg(test)]
mod task_tests;
#[cfg(test)]
mod tests;

pub use resolve::{Overrides, resolve, resolve_with_choice};

use agent::checkpoint::{self, Origin};
use std::sync::Arc;

use agent::config::{AgentConfig, Algo, ApproxKind, HorizonKind};
use agent::learner::Learner;
use observer::config::{ObserverConfig, ObserverMode};
use plant::config::{ConfigError, RunConfig};
use plant::{SystemName, Task, TaskFile};
use serde::{Deserialize, Serialize};

/// A complete experiment. Its TOML form keeps every key where a user writes it (see
/// `file::ExperimentFile`): the system and the learner's choices at the top level, then
/// `[run]`, the agent's sections and `[observer]` (written only when it is not the
/// default).
///
/// The task is read and checked once, when the configuration is made (from a preset or
/// from TOML); [`ExperimentConfig::task`] hands out that one. The sections are read
/// through accessors and changed through methods that check the whole configuration
/// again and resolve its learner ([`ExperimentConfig::learner`]) anew.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "file::ExperimentFile", into = "file::ExperimentFile")]
pub struct ExperimentConfig {
    /// The system learned on: the built-in system whose presets the learner starts from
    /// and whose task it learns, unless `task` gives another.
    system: SystemName,
    /// The task learned, when a task file gives it (`task = "FILE"` or `[task]`,
    /// `--task`); `None`: `system`'s shipped task file.
    task: Option<TaskFile>,
    /// What the keys resolve to: the task and the learner, checked.
    resolved: Resolved,
    /// The learner: algorithm, approximator, horizon and their sections.
    agent: AgentConfig,
    /// Trials, runs, seed, evaluation, delays.
    run: RunConfig,
    /// Sensor and state observer; the default: full state, pass-through.
    observer: ObserverConfig,
}

impl ExperimentConfig {
    /// The preset for `(system, algo, approx)` with `horizon` ([`agent::preset`]), with
    /// the default sensor and observer, checked.
    pub fn preset(
        system: SystemName,
        algo: Algo,
        approx: ApproxKind,
        horizon: HorizonKind,
    ) -> Result<Self, ConfigError> {
        let preset = agent::preset::preset(system, algo, approx, horizon)?;
        let sections = Sections {
            agent: preset.agent,
            run: preset.run,
            observer: ObserverConfig::default(),
        };
        Self::made(system, None, sections)
    }

    /// The configuration of `sections` on `system` with the task `task` (`None`:
    /// `system`'s shipped one): the task read and checked (an error's key is prefixed
    /// with `task.`), then the whole, and the learner resolved.
    fn made(
        system: SystemName,
        task: Option<TaskFile>,
        sections: Sections,
    ) -> Result<Self, ConfigError> {
        let learned = Arc::new(match &task {
            Some(file) => task_of(file)?,
            None => Task::new(system),
        });
        let learner = Arc::new(sections.check(&learned)?);
        let Sections {
            agent,
            run,
            observer,
        } = sections;
        Ok(Self {
            system,
            task,
            resolved: Resolved {
                task: learned,
                learner,
            },
            agent,
            run,
            observer,
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

    /// The learner's keys: algorithm, approximator, horizon and their sections.
    pub fn agent(&self) -> &AgentConfig {
        &self.agent
    }

    /// `[run]`: trials, runs, seed, evaluation, delays.
    pub fn run(&self) -> &RunConfig {
        &self.run
    }

    /// `[observer]`: sensor, state observer and timing.
    pub fn observer(&self) -> &ObserverConfig {
        &self.observer
    }

    /// Changes the learner's keys with `change`, then checks the whole configuration
    /// and resolves its learner again; an error leaves the configuration as it was.
    pub fn change_agent(
        &mut self,
        change: impl FnOnce(&mut AgentConfig),
    ) -> Result<(), ConfigError> {
        self.change(|s| change(&mut s.agent))
    }

    /// Changes `[run]` with `change`, then checks the whole configuration (the delays
    /// against the task's sampling time); an error leaves it as it was.
    pub fn change_run(&mut self, change: impl FnOnce(&mut RunConfig)) -> Result<(), ConfigError> {
        self.change(|s| change(&mut s.run))
    }

    /// Changes `[observer]` with `change`, then checks the whole configuration (the
    /// observer against the task and the agent's horizon); an error leaves it as it was.
    pub fn change_observer(
        &mut self,
        change: impl FnOnce(&mut ObserverConfig),
    ) -> Result<(), ConfigError> {
        self.change(|s| change(&mut s.observer))
    }

    /// The configuration of one run of this experiment (`run.runs = 1`, as `rig run`
    /// makes): a count always in range, so it needs no new check.
    pub fn one_run(&self) -> Self {
        let mut one = self.clone();
        one.run.runs = 1;
        one
    }

    /// Changes the sections with `change`, checked as when the configuration was made.
    fn change(&mut self, change: impl FnOnce(&mut Sections)) -> Result<(), ConfigError> {
        let mut sections = Sections {
            agent: self.agent.clone(),
            run: self.run.clone(),
            observer: self.observer.clone(),
        };
        change(&mut sections);
        self.resolved.learner = Arc::new(sections.check(&self.resolved.task)?);
        (self.agent, self.run, self.observer) = (sections.agent, sections.run, sections.observer);
        Ok(())
    }

    /// The task learned: `task`'s, else `system`'s shipped one, as read when the
    /// configuration was made.
    pub fn task(&self) -> Arc<Task> {
        self.resolved.task.clone()
    }

    /// The learner the agent's keys describe for the task ([`AgentConfig::resolve`]),
    /// as resolved when the configuration was made or last changed.
    pub fn learner(&self) -> &Learner {
        &self.resolved.learner
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

/// The sections a configuration is made of besides its system and task, before they
/// are checked together.
struct Sections {
    agent: AgentConfig,
    run: RunConfig,
    observer: ObserverConfig,
}

impl Sections {
    /// Checks every value against its allowed range and `task`'s dimensions, section by
    /// section, then what spans sections; the learner the agent's keys describe.
    fn check(&self, task: &Task) -> Result<Learner, ConfigError> {
        self.run.validate(task)?;
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
        self.agent.resolve(task)
    }
}

/// What a configuration's keys resolve to, shared by its copies: the task learned and
/// the learner. It follows from the keys, so it takes no part in comparing
/// configurations.
#[derive(Clone)]
struct Resolved {
    task: Arc<Task>,
    learner: Arc<Learner>,
}

impl PartialEq for Resolved {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for Resolved {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.task.name)
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
