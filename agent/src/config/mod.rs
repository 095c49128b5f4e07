//! The agent's part of an experiment's configuration: the learner (`algo`, `approx`,
//! `horizon`) and the sections `[learning]`, `[actor]`, `[critic]`, `[model]`, `[vgbp]`,
//! `[sarsa]`, each with the validation of its values — messages name the key and the
//! allowed range.
//!
//! * [`Algo`], [`ApproxKind`], [`HorizonKind`] — the learner, chosen by name.
//! * [`LearningConfig`] — Template 2.1's shared parameters and the exploration.
//! * [`Component`] — one approximator's parameters ([`LlrConfig`], [`RbfConfig`],
//!   [`TilesConfig`], [`LstdConfig`]).
//! * [`VgbpConfig`], [`SarsaConfig`] — the critic-only learners' own settings.
//! * [`AgentConfig`] — all of them, what [`crate::build()`] builds an agent from.
//!
//! The thesis's values are in [`crate::preset`]; the whole experiment (system, `[run]`,
//! `[observer]` and this part), its TOML form and its resolution from preset, file and
//! flags are `runtime::config`'s.

mod component;
mod learner;
mod learning;
mod sarsa;
mod vgbp;

pub use component::{Component, LlrConfig, LstdConfig, LstdPrior, RbfConfig, TilesConfig};
pub(crate) use learner::finite_horizon_unsupported;
pub use learner::{Algo, ApproxKind, HorizonKind};
pub use learning::LearningConfig;
pub use sarsa::SarsaConfig;
pub use vgbp::VgbpConfig;

use plant::Task;
use plant::config::ConfigError;

use component::Slot;

/// The learner's configuration: what an agent is built from.
#[derive(Clone, Debug, PartialEq)]
pub struct AgentConfig {
    /// The algorithm.
    pub algo: Algo,
    /// The approximator of every component.
    pub approx: ApproxKind,
    /// Infinite (discounted) or finite horizon (Chapter 4).
    pub horizon: HorizonKind,
    /// Parameters of Template 2.1 and the exploration.
    pub learning: LearningConfig,
    /// The actor (SAC, MLAC) or reference model (RMAC); none for VGBP and SARSA. With a
    /// finite horizon its input (like the critic's) is the state followed by time.
    pub actor: Option<Component>,
    /// The critic `V(x)` (SARSA: `Q(x, ·)`, one output per action).
    pub critic: Component,
    /// The process model (MLAC, RMAC, VGBP).
    pub model: Option<Component>,
    /// VGBP's action selection.
    pub vgbp: Option<VgbpConfig>,
    /// SARSA's action set and ε-greedy schedule.
    pub sarsa: Option<SarsaConfig>,
}

impl AgentConfig {
    /// Checks every value against its allowed range and `task`'s dimensions, and that the
    /// sections present are those the algorithm has.
    pub fn validate(&self, task: &Task) -> Result<(), ConfigError> {
        if self.horizon == HorizonKind::Finite && !self.algo.has_actor() {
            return Err(finite_horizon_unsupported(self.algo));
        }
        self.learning.validate(self.horizon)?;
        self.algo.check_approx(self.approx)?;
        self.validate_components(task)?;
        self.validate_vgbp(task)?;
        self.validate_sarsa(task)
    }

    /// Actor, critic and process model: present as the algorithm needs them, of the
    /// configured approximator, with one input per state (and action) component.
    fn validate_components(&self, task: &Task) -> Result<(), ConfigError> {
        let (n, m) = (task.state_dim(), task.action_dim());
        let own = [self.approx];
        // Actor, reference model and critic read the state, and time if finite (Eq. 4.6).
        let (dim, what) = if self.horizon == HorizonKind::Finite {
            (n + 1, "state component and time")
        } else {
            (n, "state component")
        };
        let slot = |section, kinds, dim, what| Slot {
            section,
            kinds,
            dim,
            what,
            algo: self.algo,
            approx: self.approx,
        };
        let algo = self.algo;
        match (&self.actor, algo.has_actor()) {
            (None, true) => {
                return Err(ConfigError::new(
                    "actor",
                    format!("{algo} has an actor: an [actor] section is required"),
                ));
            }
            (Some(_), false) => {
                return Err(ConfigError::new(
                    "actor",
                    format!("{algo} has no actor: remove the [actor] section"),
                ));
            }
            (Some(c), true) => c.validate(&slot("actor", &own, dim, what))?,
            (None, false) => {}
        }
        self.critic.validate(&slot("critic", &own, dim, what))?;
        // VGBP's process model is LLR whatever its critic (§6.3.1); the others learn every
        // component with the same approximator.
        let model_kinds: &[ApproxKind] = if algo == Algo::Vgbp {
            &[ApproxKind::Llr, ApproxKind::Rbf]
        } else {
            &own
        };
        match (&self.model, algo.has_model()) {
            (None, true) => Err(ConfigError::new(
                "model",
                format!("{algo} learns a process model: a [model] section is required"),
            )),
            (Some(_), false) => Err(ConfigError::new(
                "model",
                format!("{algo} learns no process model: remove the [model] section"),
            )),
            (Some(c), true) => c.validate(&slot(
                "model",
                model_kinds,
                n + m,
                "state and action component",
            )),
            (None, false) => Ok(()),
        }
    }

    /// `[vgbp]`: present for VGBP only; VGBP also needs a reward strictly concave in the
    /// action.
    fn validate_vgbp(&self, task: &Task) -> Result<(), ConfigError> {
        match (&self.vgbp, self.algo) {
            (None, Algo::Vgbp) => {
                return Err(ConfigError::new("vgbp", "vgbp needs a [vgbp] section"));
            }
            (Some(_), a) if a != Algo::Vgbp => {
                return Err(ConfigError::new(
                    "vgbp",
                    format!("{a} is not vgbp: remove the [vgbp] section"),
                ));
            }
            (Some(v), _) => v.validate()?,
            (None, _) => {}
        }
        if self.algo == Algo::Vgbp && task.reward.p.iter().any(|&p| p <= 0.0) {
            return Err(ConfigError::new(
                "algo",
                format!(
                    "vgbp needs a reward strictly concave in the action (P > 0); {} has P = {:?}",
                    task.name, task.reward.p
                ),
            ));
        }
        Ok(())
    }

    /// `[sarsa]`: present for SARSA only.
    fn validate_sarsa(&self, task: &Task) -> Result<(), ConfigError> {
        match (&self.sarsa, self.algo) {
            (None, Algo::Sarsa) => Err(ConfigError::new("sarsa", "sarsa needs a [sarsa] section")),
            (Some(_), a) if a != Algo::Sarsa => Err(ConfigError::new(
                "sarsa",
                format!("{a} is not sarsa: remove the [sarsa] section"),
            )),
            (Some(c), _) => c.validate(task),
            (None, _) => Ok(()),
        }
    }
}
