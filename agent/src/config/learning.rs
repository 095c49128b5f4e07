//! `[learning]`: the parameters of Template 2.1 the components share, and the
//! exploration.

use plant::config::{ConfigError, check_float, check_int};
use serde::{Deserialize, Serialize};

use super::HorizonKind;

/// Learning parameters shared by the components.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LearningConfig {
    /// Discount `γ`, in (0, 1); a finite horizon also allows 1 (no discount, as in
    /// Algorithms 4–6).
    pub gamma: f64,
    /// Eligibility-trace decay `λ` of the critic.
    pub lambda: f64,
    /// Exploration standard deviation `σ`.
    pub sigma: f64,
    /// Explore on every this-many-th step (1: every step, §3.6; 3: §6.4.1).
    pub explore_every: u32,
    /// MLAC: `∇_u f̂` is taken as zero within this distance of an action bound (§3.5.1).
    pub saturation_margin: f64,
    /// The actor's outputs are saturated to the action bounds and its updates stop there
    /// (§3.5.1, the thesis's second remedy for input saturation; default). `false`
    /// ignores the saturation in the actor — the plant still saturates what it applies —
    /// for §3.7's claim that ignoring it does not produce a well-performing policy.
    #[serde(default = "yes")]
    pub bounded_actor: bool,
}

fn yes() -> bool {
    true
}

impl LearningConfig {
    /// Checks every value against its allowed range; `γ = 1` only with a finite horizon.
    pub fn validate(&self, horizon: HorizonKind) -> Result<(), ConfigError> {
        if horizon == HorizonKind::Infinite {
            check_float("learning.gamma", self.gamma, 0.0, 1.0, true)?;
        } else if !(self.gamma > 0.0 && self.gamma <= 1.0) {
            return Err(ConfigError::new(
                "learning.gamma",
                format!(
                    "{} is out of range: must be a number in (0, 1] (1: no discount, Algorithms 4–6)",
                    self.gamma
                ),
            ));
        }
        check_float("learning.lambda", self.lambda, 0.0, 1.0, false)?;
        check_float("learning.sigma", self.sigma, 0.0, 1e3, false)?;
        check_int(
            "learning.explore_every",
            self.explore_every.into(),
            1,
            1_000_000,
        )?;
        check_float(
            "learning.saturation_margin",
            self.saturation_margin,
            0.0,
            1e3,
            false,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_finite_horizon_may_leave_rewards_undiscounted() {
        let l = LearningConfig {
            gamma: 1.0,
            lambda: 0.65,
            sigma: 1.0,
            explore_every: 1,
            saturation_margin: 0.0,
            bounded_actor: true,
        };
        l.validate(HorizonKind::Finite).unwrap();
        let e = l.validate(HorizonKind::Infinite).unwrap_err();
        assert_eq!(e.key, "learning.gamma");
        assert!(e.message.contains("(0, 1)"), "{e}");
        let e = LearningConfig { gamma: 1.01, ..l }
            .validate(HorizonKind::Finite)
            .unwrap_err();
        assert!(e.message.contains("(0, 1]"), "{e}");
    }
}
