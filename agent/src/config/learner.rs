//! The learner: which algorithm, which approximator, which horizon (the keys `algo`,
//! `approx`, `horizon`).

use plant::Task;
use plant::config::ConfigError;

use crate::horizon::Horizon;

plant::choice! {
    /// The learning algorithm.
    #[derive(Debug, PartialEq, Eq, Hash)]
    pub enum Algo {
        /// Standard actor-critic (Algorithm 1).
        Sac => "sac",
        /// Model learning actor-critic (Algorithm 2).
        Mlac => "mlac",
        /// Reference model actor-critic (Algorithm 3).
        Rmac => "rmac",
        /// Value-gradient based policy (Algorithm 7), critic-only.
        Vgbp => "vgbp",
        /// SARSA(λ) with ε-greedy discrete actions (§6.2), critic-only.
        Sarsa => "sarsa",
    }
}

impl Algo {
    /// The approximators this algorithm can use.
    pub fn approximators(self) -> &'static [ApproxKind] {
        use ApproxKind::*;
        match self {
            Algo::Sac => &[Llr, Rbf, Tiles],
            Algo::Mlac | Algo::Rmac => &[Llr, Rbf],
            Algo::Vgbp => &[Lstd, Rbf, Llr],
            Algo::Sarsa => &[Rbf],
        }
    }

    /// Whether the algorithm has an actor (or reference model) component.
    pub fn has_actor(self) -> bool {
        matches!(self, Algo::Sac | Algo::Mlac | Algo::Rmac)
    }

    /// Whether the algorithm needs the reward's gradient `∂ρ/∂u` (VGBP's action
    /// selection, Eq. 4.15): a reward given as numbers only (an external driver's) cannot
    /// serve it.
    pub fn needs_reward_gradient(self) -> bool {
        self == Algo::Vgbp
    }

    /// Whether the algorithm learns a process model.
    pub fn has_model(self) -> bool {
        matches!(self, Algo::Mlac | Algo::Rmac | Algo::Vgbp)
    }

    /// Checks that the algorithm can use `approx`; the error (key `approx`) names the
    /// approximators it can use.
    pub fn check_approx(self, approx: ApproxKind) -> Result<(), ConfigError> {
        let allowed = self.approximators();
        if allowed.contains(&approx) {
            return Ok(());
        }
        let names: Vec<&str> = allowed.iter().map(|a| a.as_str()).collect();
        Err(ConfigError::new(
            "approx",
            format!(
                "{self} works with {}, not {approx}{}",
                names.join(", "),
                if approx == ApproxKind::Tiles {
                    " (tile coding has no gradient, §3.5)"
                } else {
                    ""
                }
            ),
        ))
    }
}

plant::choice! {
    /// The function approximator used by every component.
    #[derive(Debug, PartialEq, Eq, Hash)]
    pub enum ApproxKind {
        /// Local linear regression (§3.5.2).
        Llr => "llr",
        /// Normalised radial basis functions (§3.5.1).
        Rbf => "rbf",
        /// Tile coding (§3.5.3), SAC only.
        Tiles => "tiles",
        /// LSTD(λ) on normalised RBFs (Eq. 6.16–6.19), a VGBP critic; the process model is
        /// LLR.
        Lstd => "lstd",
    }
}

impl ApproxKind {}

plant::choice! {
    /// The horizon of the cost function ([`crate::horizon`]).
    #[derive(Debug, Default, PartialEq, Eq, Hash)]
    pub enum HorizonKind {
        /// Discounted rewards without end (Chapters 3, 5, 6).
        #[default]
        Infinite => "infinite",
        /// A trial is the horizon: its samples' rewards plus the terminal reward `τ_N`, actor
        /// and critic time-varying (Chapter 4; SAC, MLAC and RMAC, Algorithms 4–6).
        Finite => "finite",
    }
}

impl HorizonKind {
    /// The runtime horizon of `task`: a finite horizon is one trial, `N` samples.
    pub fn of(self, task: &Task) -> Horizon {
        match self {
            HorizonKind::Infinite => Horizon::Infinite,
            HorizonKind::Finite => Horizon::Finite {
                steps: task.steps_per_trial(),
            },
        }
    }
}

/// The error for a finite horizon with an algorithm that has none (VGBP, SARSA).
pub(crate) fn finite_horizon_unsupported(algo: Algo) -> ConfigError {
    ConfigError::new(
        "horizon",
        format!(
            "\"finite\" (Chapter 4) is for sac, mlac and rmac; {algo} needs horizon = \"infinite\""
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::config::Choice;

    #[test]
    fn an_unusable_approximator_is_named_with_the_usable_ones() {
        Algo::Sac.check_approx(ApproxKind::Tiles).unwrap();
        let e = Algo::Mlac.check_approx(ApproxKind::Tiles).unwrap_err();
        assert_eq!(e.key, "approx");
        assert_eq!(
            e.message,
            "mlac works with llr, rbf, not tiles (tile coding has no gradient, §3.5)"
        );
        assert_eq!(HorizonKind::parse("finite"), Ok(HorizonKind::Finite));
    }
}
