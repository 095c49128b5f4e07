//! `[planning]`: MLAC's actions planned with its learned process model ([`crate::plan`]).

use plant::config::{ConfigError, check_int};
use serde::{Deserialize, Serialize};

/// The cross-entropy search of [`crate::plan`]: sequences of `horizon` actions, scored
/// by the learned model's rewards and the critic at their end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanningConfig {
    /// Samples `H` each sequence looks ahead before the critic's value.
    pub horizon: u32,
    /// Sequences scored per iteration (the mean among them).
    pub samples: u32,
    /// The best sequences the next iteration's mean and spread are fitted to.
    pub elites: u32,
    /// Iterations of the cross-entropy method per sample.
    pub iterations: u32,
}

impl PlanningConfig {
    /// Checks every value against its allowed range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_int("planning.horizon", self.horizon.into(), 1, 200)?;
        check_int("planning.samples", self.samples.into(), 2, 10_000)?;
        check_int(
            "planning.elites",
            self.elites.into(),
            1,
            self.samples.into(),
        )?;
        check_int("planning.iterations", self.iterations.into(), 1, 100)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn more_elites_than_samples_are_out_of_range() {
        let p = PlanningConfig {
            horizon: 10,
            samples: 16,
            elites: 4,
            iterations: 2,
        };
        p.validate().unwrap();
        let e = PlanningConfig { elites: 17, ..p }.validate().unwrap_err();
        assert_eq!(e.key, "planning.elites");
        assert!(e.to_string().contains("16"), "{e}");
    }
}
