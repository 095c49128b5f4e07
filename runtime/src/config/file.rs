//! The experiment file as written: every key where a user writes it — the system and the
//! learner's choices at the top level, then `[run]`, the agent's sections, `[observer]`,
//! and the task when a task file gives it (`[task]`).
//! [`ExperimentConfig`] is read and written through it, so its TOML form is the one
//! every configuration file and `config.toml` has.

use agent::config::{
    AgentConfig, Algo, ApproxKind, Component, HorizonKind, LearningConfig, LqrConfig,
    PlanningConfig, SarsaConfig, VgbpConfig,
};
use observer::config::ObserverConfig;
use plant::config::RunConfig;
use plant::{SystemName, TaskFile};
use serde::{Deserialize, Serialize};

use super::{ExperimentConfig, Sections};

/// The top level of an experiment file, in the order it is written.
#[derive(Serialize, Deserialize)]
// Messages about the whole file name the experiment, not this struct.
#[serde(deny_unknown_fields, rename = "ExperimentConfig")]
pub(super) struct ExperimentFile {
    /// Absent for a task without a simulation (its presets are the pendulum's, by rules:
    /// [`ExperimentConfig::to_toml`] says so in a comment); otherwise the system simulated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) system: Option<SystemName>,
    pub(super) algo: Algo,
    pub(super) approx: ApproxKind,
    /// Absent: infinite.
    #[serde(default)]
    pub(super) horizon: HorizonKind,
    pub(super) run: RunConfig,
    learning: LearningConfig,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    actor: Option<Component>,
    critic: Component,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    model: Option<Component>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vgbp: Option<VgbpConfig>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sarsa: Option<SarsaConfig>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    planning: Option<PlanningConfig>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lqr: Option<LqrConfig>,
    /// Absent: full state, pass-through.
    #[serde(default, skip_serializing_if = "ObserverConfig::is_default")]
    pub(super) observer: ObserverConfig,
    /// Absent: the system's shipped task.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) task: Option<TaskFile>,
}

impl TryFrom<ExperimentFile> for ExperimentConfig {
    type Error = plant::config::ConfigError;

    /// The configuration, its task read and checked.
    fn try_from(l: ExperimentFile) -> Result<Self, Self::Error> {
        let simulated = match &l.task {
            Some(t) => t
                .simulation
                .as_ref()
                .map_or(SystemName::Pendulum, |s| s.system),
            None => SystemName::Pendulum,
        };
        let system = l.system.unwrap_or(simulated);
        let sections = Sections {
            agent: AgentConfig {
                algo: l.algo,
                approx: l.approx,
                horizon: l.horizon,
                learning: l.learning,
                actor: l.actor,
                critic: l.critic,
                model: l.model,
                vgbp: l.vgbp,
                sarsa: l.sarsa,
                planning: l.planning,
                lqr: l.lqr,
            },
            run: l.run,
            observer: l.observer,
        };
        Self::made(system, l.task, sections)
    }
}

impl From<ExperimentConfig> for ExperimentFile {
    fn from(c: ExperimentConfig) -> Self {
        let driven = c.task.as_ref().is_some_and(|t| t.simulation.is_none());
        let sections = Sections {
            agent: c.agent,
            run: c.run,
            observer: c.observer,
        };
        Self::new((!driven).then_some(c.system), sections, c.task)
    }
}

impl ExperimentFile {
    /// The file of `sections` on `system` (absent: a task without a simulation) and
    /// `task` (absent: the system's shipped one).
    pub(super) fn new(
        system: Option<SystemName>,
        Sections {
            agent: a,
            run,
            observer,
        }: Sections,
        task: Option<TaskFile>,
    ) -> Self {
        Self {
            system,
            algo: a.algo,
            approx: a.approx,
            horizon: a.horizon,
            run,
            learning: a.learning,
            actor: a.actor,
            critic: a.critic,
            model: a.model,
            vgbp: a.vgbp,
            sarsa: a.sarsa,
            planning: a.planning,
            lqr: a.lqr,
            observer,
            task,
        }
    }
}
