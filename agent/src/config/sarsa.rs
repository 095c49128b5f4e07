//! `[sarsa]`: SARSA's discrete actions and exploration.

use plant::Task;
use plant::config::{ConfigError, check_float, check_int};
use serde::{Deserialize, Serialize};

/// SARSA's discrete actions and exploration (§6.4.1, Eq. 6.22).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SarsaConfig {
    /// The action values (per action dimension; the set is their product).
    pub actions: Vec<f64>,
    /// ε decays by this factor per trial.
    pub epsilon_decay: f64,
    /// ε never falls below this.
    pub epsilon_min: f64,
}

impl SarsaConfig {
    /// Checks every value against its allowed range: at most 4096 discrete actions in
    /// all, each within `task`'s action bounds.
    pub fn validate(&self, task: &Task) -> Result<(), ConfigError> {
        let m = task.action_dim();
        let count = self.actions.len() as u64;
        check_int("sarsa.actions", count, 1, 64)?;
        if count.pow(m as u32) > 4096 {
            return Err(ConfigError::new(
                "sarsa.actions",
                format!("{count}^{m} discrete actions: at most 4096"),
            ));
        }
        let lo = task
            .action_low
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let hi = task
            .action_high
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        for (i, &a) in self.actions.iter().enumerate() {
            check_float(&format!("sarsa.actions[{i}]"), a, lo, hi, false)?;
        }
        check_float("sarsa.epsilon_decay", self.epsilon_decay, 0.0, 1.0, false)?;
        check_float("sarsa.epsilon_min", self.epsilon_min, 0.0, 1.0, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::SystemName;

    #[test]
    fn actions_must_be_within_the_bounds() {
        let task = Task::new(SystemName::Pendulum);
        let s = SarsaConfig {
            actions: vec![-3.0, 0.0, 3.0],
            epsilon_decay: 0.96,
            epsilon_min: 0.1,
        };
        s.validate(&task).unwrap();
        let e = SarsaConfig {
            actions: vec![-3.0, 9.0],
            ..s
        }
        .validate(&task)
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "`sarsa.actions[1]`: 9 is out of range: must be a finite number in [-3, 3]"
        );
    }
}
