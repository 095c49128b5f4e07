//! The learner a configuration describes, resolved into types: one variant per
//! algorithm, holding exactly its components, each of an approximator the algorithm can
//! use. [`AgentConfig::resolve`](crate::config::AgentConfig::resolve) makes one (or
//! names the key that is wrong); [`crate::build()`] builds the agent from it.

use crate::config::{HorizonKind, LearningConfig, LlrConfig, LstdConfig, RbfConfig};
use crate::config::{LqrConfig, PlanningConfig, SarsaConfig, TilesConfig, VgbpConfig};
use crate::step_size::StepSize;

mod resolve;

/// An approximator with a gradient (§3.5): what a process model, an MLAC or RMAC actor
/// and their critics are.
#[derive(Clone, Debug, PartialEq)]
pub enum Smooth {
    /// Local linear regression.
    Llr(LlrConfig),
    /// Normalised RBF grid.
    Rbf(RbfConfig),
}

/// Any approximator: SAC's actor and critic, tile coding too.
#[derive(Clone, Debug, PartialEq)]
pub enum Plain {
    /// LLR or an RBF grid.
    Smooth(Smooth),
    /// Tile coding (no gradient; SAC never asks for one).
    Tiles(TilesConfig),
}

/// VGBP's critic: TD(λ) on a smooth approximator, or LSTD (§6.4.1).
#[derive(Clone, Debug, PartialEq)]
pub enum VgbpCritic {
    /// TD(λ) on LLR or an RBF grid.
    Td(Smooth),
    /// LSTD(λ) on an RBF grid.
    Lstd(LstdConfig),
}

/// SAC (Algorithm 1): actor and critic.
#[derive(Clone, Debug, PartialEq)]
pub struct SacParts {
    /// The actor `π(x)`.
    pub actor: Plain,
    /// The critic `V(x)`.
    pub critic: Plain,
}

/// MLAC (Algorithm 2) and RMAC (Algorithm 3): actor (RMAC: reference model), critic and
/// process model.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelParts {
    /// MLAC's actor `π(x)`, RMAC's reference model `R(x)`.
    pub actor: Smooth,
    /// The critic `V(x)`.
    pub critic: Smooth,
    /// The process model `f̂(x, u)`.
    pub model: Smooth,
}

/// VGBP (Algorithm 7): critic, process model, action selection.
#[derive(Clone, Debug, PartialEq)]
pub struct VgbpParts {
    /// The critic `V(x)`.
    pub critic: VgbpCritic,
    /// The process model `f̂(x, u)`.
    pub model: Smooth,
    /// `[vgbp]`.
    pub vgbp: VgbpConfig,
}

/// SARSA (§6.2): the Q-function's grid and the action set.
#[derive(Clone, Debug, PartialEq)]
pub struct SarsaParts {
    /// `Q(x, ·)`: an RBF grid, one output per action.
    pub q: RbfConfig,
    /// `[sarsa]`.
    pub sarsa: SarsaConfig,
}

/// The algorithm with its components.
#[derive(Clone, Debug, PartialEq)]
pub enum Algorithm {
    /// Standard actor-critic.
    Sac(SacParts),
    /// Model learning actor-critic.
    Mlac(ModelParts),
    /// Reference model actor-critic.
    Rmac(ModelParts),
    /// Value-gradient based policy.
    Vgbp(VgbpParts),
    /// SARSA(λ).
    Sarsa(SarsaParts),
}

/// A learner, checked against its task: the algorithm with its components, the shared
/// parameters of Template 2.1 and the horizon.
#[derive(Clone, Debug, PartialEq)]
pub struct Learner {
    /// The algorithm and its components.
    pub algorithm: Algorithm,
    /// `[learning]`.
    pub learning: LearningConfig,
    /// Infinite or finite horizon (only SAC, MLAC, RMAC have a finite one).
    pub horizon: HorizonKind,
    /// MLAC's actions planned with its learned model ([`crate::plan`]), if given.
    pub planning: Option<PlanningConfig>,
    /// MLAC's actions near the reference from a regulator of its learned model
    /// ([`crate::lqr`]), if given.
    pub lqr: Option<LqrConfig>,
}

impl Smooth {
    /// The learning rate.
    pub fn alpha(&self) -> f64 {
        match self {
            Smooth::Llr(c) => c.alpha,
            Smooth::Rbf(c) => c.alpha,
        }
    }

    /// The learning rate with its schedule.
    pub fn step_size(&self) -> StepSize {
        match self {
            Smooth::Llr(c) => c.step_size(),
            Smooth::Rbf(c) => c.step_size(),
        }
    }
}

impl Plain {
    /// The learning rate.
    pub fn alpha(&self) -> f64 {
        match self {
            Plain::Smooth(c) => c.alpha(),
            Plain::Tiles(c) => c.alpha,
        }
    }

    /// The learning rate with its schedule.
    pub fn step_size(&self) -> StepSize {
        match self {
            Plain::Smooth(c) => c.step_size(),
            Plain::Tiles(c) => c.step_size(),
        }
    }
}
