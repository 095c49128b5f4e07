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
//! * [`AgentConfig`] — all of them; `crate::learner` resolves them against a task
//!   ([`AgentConfig::resolve`]) into the typed learner [`crate::build()`] builds an agent
//!   from.
//!
//! The thesis's values are in [`crate::preset`]; the whole experiment (system, `[run]`,
//! `[observer]` and this part), its TOML form and its resolution from preset, file and
//! flags are `runtime::config`'s.

mod component;
mod learner;
mod learning;
mod lqr;
mod planning;
mod sarsa;
mod vgbp;

pub use component::{
    Component, EvictionRule, LlrConfig, LstdConfig, LstdPrior, RbfConfig, TilesConfig,
};
pub(crate) use learner::finite_horizon_unsupported;
pub use learner::{Algo, ApproxKind, HorizonKind};
pub use learning::LearningConfig;
pub use lqr::{FitAt, LqrConfig};
pub use planning::{PlanningConfig, PlanningMethod};
pub use sarsa::SarsaConfig;
pub use vgbp::VgbpConfig;

pub(crate) use component::Slot;

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
    /// MLAC's actions planned with its learned model ([`crate::plan`]); absent: the
    /// actor's, as the thesis has it.
    pub planning: Option<PlanningConfig>,
    /// MLAC's actions near the reference from a regulator of its learned model
    /// ([`crate::lqr`]); absent: the actor's (or the planner's).
    pub lqr: Option<LqrConfig>,
}
