//! `[planning]`: MLAC's actions planned with its learned process model ([`crate::plan`],
//! [`crate::ilqr`]).

use plant::config::{ConfigError, check_int};
use serde::{Deserialize, Serialize};

/// Sequences scored per iteration of the cross-entropy method when a file does not say.
const DEFAULT_SAMPLES: u32 = 64;
/// Elite sequences of the cross-entropy method when a file does not say.
const DEFAULT_ELITES: u32 = 8;

/// The search over `horizon` actions: the cross-entropy method of [`crate::plan`]
/// (sequences scored by the learned model's rewards and the critic at their end), or the
/// iterative LQR of [`crate::ilqr`] (the model's local fits along the plan, the LQR of its
/// fit at the reference at its end).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanningConfig {
    /// How the sequence is searched.
    #[serde(default, skip_serializing_if = "PlanningMethod::is_cem")]
    pub method: PlanningMethod,
    /// Samples `H` each sequence looks ahead before its terminal value.
    pub horizon: u32,
    /// Sequences scored per iteration (the mean among them); the cross-entropy method's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<u32>,
    /// The best sequences the next iteration's mean and spread are fitted to; the
    /// cross-entropy method's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elites: Option<u32>,
    /// Iterations of the search per sample.
    pub iterations: u32,
    /// The iterative LQR's: whether the regulator's rollout — the LQR of the model's fit at
    /// the reference, in closed loop through the model — competes with the last plan and
    /// the actor's rollout as the sequence a sample's search starts from.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub start_from_regulator: bool,
}

/// How [`PlanningConfig`] searches its action sequence.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlanningMethod {
    /// The cross-entropy method ([`crate::plan`]).
    #[default]
    Cem,
    /// The iterative LQR, warm-started by the last sample's plan ([`crate::ilqr`]).
    Ilqr,
}

impl PlanningMethod {
    fn is_cem(&self) -> bool {
        *self == PlanningMethod::Cem
    }
}

impl PlanningConfig {
    /// Sequences per iteration of the cross-entropy method (64 if not given).
    pub fn samples(&self) -> u32 {
        self.samples.unwrap_or(DEFAULT_SAMPLES)
    }

    /// Elite sequences of the cross-entropy method (8, or `samples` if fewer, if not
    /// given).
    pub fn elites(&self) -> u32 {
        self.elites
            .unwrap_or_else(|| DEFAULT_ELITES.min(self.samples()))
    }

    /// Checks every value against its allowed range, and that the cross-entropy method's
    /// keys are not given to the iterative LQR.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_int("planning.horizon", self.horizon.into(), 1, 200)?;
        check_int("planning.iterations", self.iterations.into(), 1, 100)?;
        match self.method {
            PlanningMethod::Cem => {
                if self.start_from_regulator {
                    return Err(ConfigError::new(
                        "planning.start_from_regulator",
                        "start_from_regulator is the iterative LQR's: add method = \"ilqr\" or remove it",
                    ));
                }
                check_int("planning.samples", self.samples().into(), 2, 10_000)?;
                check_int(
                    "planning.elites",
                    self.elites().into(),
                    1,
                    self.samples().into(),
                )
            }
            PlanningMethod::Ilqr => {
                for (key, given) in [("samples", self.samples), ("elites", self.elites)] {
                    if given.is_some() {
                        return Err(ConfigError::new(
                            &format!("planning.{key}"),
                            format!(
                                "{key} is the cross-entropy method's; method = \"ilqr\" has none: remove it"
                            ),
                        ));
                    }
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cem(samples: u32, elites: u32) -> PlanningConfig {
        PlanningConfig {
            method: PlanningMethod::Cem,
            horizon: 10,
            samples: Some(samples),
            elites: Some(elites),
            iterations: 2,
            start_from_regulator: false,
        }
    }

    #[test]
    fn more_elites_than_samples_are_out_of_range() {
        cem(16, 4).validate().unwrap();
        let e = cem(16, 17).validate().unwrap_err();
        assert_eq!(e.key, "planning.elites");
        assert!(e.to_string().contains("16"), "{e}");
    }

    /// The iterative LQR has no samples or elites: a file that gives them is refused,
    /// naming the key.
    #[test]
    fn the_ilqr_refuses_the_cross_entropy_keys() {
        let ilqr = PlanningConfig {
            method: PlanningMethod::Ilqr,
            samples: None,
            elites: None,
            ..cem(16, 4)
        };
        ilqr.validate().unwrap();
        let e = PlanningConfig {
            samples: Some(16),
            ..ilqr.clone()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.key, "planning.samples", "{e}");
        assert!(e.message.contains("remove it"), "{e}");
    }

    /// Only the iterative LQR starts from the regulator's rollout: the cross-entropy method
    /// refuses the key, naming it.
    #[test]
    fn only_the_ilqr_starts_from_the_regulator() {
        let e = PlanningConfig {
            start_from_regulator: true,
            ..cem(16, 4)
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.key, "planning.start_from_regulator", "{e}");
        PlanningConfig {
            method: PlanningMethod::Ilqr,
            samples: None,
            elites: None,
            start_from_regulator: true,
            ..cem(16, 4)
        }
        .validate()
        .unwrap();
    }

    /// Without samples and elites the cross-entropy method takes 64 and 8.
    #[test]
    fn the_cross_entropy_keys_have_defaults() {
        let p = PlanningConfig {
            samples: None,
            elites: None,
            ..cem(16, 4)
        };
        p.validate().unwrap();
        assert_eq!((p.samples(), p.elites()), (64, 8));
    }
}
