//! `[lqr]`: MLAC's actions, near the reference, from a linear-quadratic regulator of its
//! learned process model ([`crate::lqr`]).

use plant::Task;
use plant::config::{ConfigError, check_len};
use serde::{Deserialize, Serialize};

/// Where the regulator of [`crate::lqr`] acts instead of the actor.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LqrConfig {
    /// Half-widths, one per state component, of the box around the reward's reference
    /// in which the regulator acts (angle errors wrapped; `inf`: unbounded). Absent: it
    /// acts everywhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<Vec<f64>>,
    /// Where the process model is linearised.
    #[serde(default, skip_serializing_if = "FitAt::is_reference")]
    pub fit_at: FitAt,
}

/// Where [`crate::lqr`] linearises the learned process model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitAt {
    /// Around the reward's reference `(x_r, u = 0)`, the same point at every sample.
    #[default]
    Reference,
    /// Around the current state and the actor's action there.
    State,
}

impl FitAt {
    fn is_reference(&self) -> bool {
        *self == FitAt::Reference
    }
}

impl LqrConfig {
    /// Checks the region against `task`'s states, and that the reward has an action cost
    /// (the regulator needs `P > 0`).
    pub fn validate(&self, task: &Task) -> Result<(), ConfigError> {
        if let Some(r) = &self.region {
            check_len("lqr.region", r.len(), task.state_dim(), "state component")?;
            if let Some(v) = r.iter().find(|v| v.is_nan() || **v <= 0.0) {
                return Err(ConfigError::new(
                    "lqr.region",
                    format!("{v} is out of range: each half-width must be > 0 (inf: unbounded)"),
                ));
            }
        }
        if task.reward.p.iter().any(|&p| p <= 0.0) {
            return Err(ConfigError::new(
                "lqr",
                format!(
                    "the regulator needs a cost on every action (action_weights > 0); {} has P = {:?}",
                    task.name, task.reward.p
                ),
            ));
        }
        Ok(())
    }

    /// Whether the state error `e = x − x_r` lies in the region.
    pub fn contains(&self, e: &[f64]) -> bool {
        self.region
            .as_ref()
            .is_none_or(|r| e.iter().zip(r).all(|(e, h)| e.abs() <= *h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_region_has_one_positive_half_width_per_state() {
        let task = plant::task::builtin::task(plant::SystemName::Pendulum);
        LqrConfig::default().validate(&task).unwrap();
        let ok = LqrConfig {
            region: Some(vec![0.3, f64::INFINITY]),
            ..LqrConfig::default()
        };
        ok.validate(&task).unwrap();
        assert!(ok.contains(&[-0.2, 40.0]) && !ok.contains(&[0.31, 0.0]));
        let short = LqrConfig {
            region: Some(vec![0.3]),
            ..LqrConfig::default()
        };
        assert_eq!(short.validate(&task).unwrap_err().key, "lqr.region");
        let zero = LqrConfig {
            region: Some(vec![0.3, 0.0]),
            ..LqrConfig::default()
        };
        let e = zero.validate(&task).unwrap_err();
        assert!(e.message.contains("> 0"), "{e}");
    }
}
