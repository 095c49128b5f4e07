//! `[observer]`: what the plant's sensor measures, the state observer, and the timing of
//! the agent's actions relative to the samples; with the validation of its values.

use plant::config::{ConfigError, check_float, check_int};
use serde::{Deserialize, Serialize};

plant::choice! {
    /// What the plant's sensor measures ([`plant::sensor`]).
    #[derive(Debug, Default, PartialEq, Eq, Hash)]
    pub enum SensorKind {
        /// The full state (the thesis's simulations).
        #[default]
        Full => "full",
        /// Encoder angles only (quantised, optionally noisy); velocities are estimated.
        Angle => "angle",
    }
}

impl SensorKind {}

plant::choice! {
    /// The state observer (this crate).
    #[derive(Debug, Default, PartialEq, Eq, Hash)]
    pub enum ObserverKind {
        /// `x̂ = y` (full-state sensor only).
        #[default]
        PassThrough => "pass-through",
        /// Backward-difference velocities, low-pass filtered.
        FiniteDifference => "finite-difference",
        /// Model prediction `x̂_{k+1|k} = f̂(x̂_k, u_k)` corrected by the measured angle.
        Predictive => "predictive",
    }
}

impl ObserverKind {}

plant::choice! {
    /// The predictive observer's process model.
    #[derive(Debug, Default, PartialEq, Eq, Hash)]
    pub enum ObserverModel {
        /// LLR learned online from the observer's own estimates (§3.5.2).
        #[default]
        Learned => "learned",
        /// The plant's dynamics integrated with RK4 (the simulator's own model).
        Known => "known",
    }
}

impl ObserverModel {}

plant::choice! {
    /// When the agent acts, relative to the sample it acts on (thesis §6.4.1;
    /// [`crate::timing`]).
    #[derive(Debug, Default, PartialEq, Eq, Hash)]
    pub enum ObserverMode {
        /// The agent acts on `x̂_k`; its action takes effect within the interval
        /// `[t_k, t_{k+1})`, as soon as it is computed and transported (`run.delay_ms` /
        /// `run.delay_from` after `t_k`; 0: at `t_k`, the thesis's simulations).
        #[default]
        Direct => "direct",
        /// The agent acts on the one-step prediction `x̂_{k+1|k} = f̂(x̂_k, u_k)`; its action
        /// is applied at `t_{k+1}`, for the whole next interval (a one-sample action
        /// pipeline, §6.4.1's physical setup): a delay below `Ts` does not reach the plant.
        /// Needs `observer = "predictive"` (the model) and an infinite horizon.
        Predictive => "predictive",
    }
}

impl ObserverMode {}

/// Sensor and state observer (`[observer]`); the defaults — full state, pass-through —
/// are the thesis's simulations, and a configuration with them is written without this
/// section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverConfig {
    /// What the plant measures.
    pub sensor: SensorKind,
    /// Encoder counts per revolution (angle sensor).
    pub counts_per_rev: u32,
    /// Standard deviation of Gaussian angle noise before quantisation \[rad\].
    pub noise_std: f64,
    /// The observer.
    pub observer: ObserverKind,
    /// The predictive observer's process model.
    pub model: ObserverModel,
    /// Finite difference: low-pass coefficient `a` in [0, 1) (0: raw difference).
    pub filter: f64,
    /// Predictive: velocity gain `l` on the angle innovation, in [0, 2).
    pub gain: f64,
    /// Timing: the agent acts on `x̂_k` (direct) or on `x̂_{k+1|k}` with its action applied
    /// at the next sample instant (predictive).
    #[serde(default)]
    pub mode: ObserverMode,
}

impl Default for ObserverConfig {
    fn default() -> Self {
        Self {
            sensor: SensorKind::Full,
            counts_per_rev: 4096,
            noise_std: 0.0,
            observer: ObserverKind::PassThrough,
            model: ObserverModel::Learned,
            filter: 0.0,
            gain: 1.0,
            mode: ObserverMode::Direct,
        }
    }
}

impl ObserverConfig {
    /// Whether this is the default (full state, pass-through, default parameters).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Whether the observer integrates the plant's own dynamics (the predictive observer
    /// with the known model), which a task without a simulation does not have.
    pub fn uses_known_model(&self) -> bool {
        self.observer == ObserverKind::Predictive && self.model == ObserverModel::Known
    }

    /// Checks every value against its allowed range, that predictive timing has the
    /// predictive observer's model, and that an angle sensor has an observer that
    /// estimates the velocities. (Predictive timing also needs an infinite horizon: the
    /// experiment checks that, it knows the agent's.)
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_int(
            "observer.counts_per_rev",
            self.counts_per_rev.into(),
            4,
            1 << 30,
        )?;
        check_float("observer.noise_std", self.noise_std, 0.0, 1.0, false)?;
        check_half_open("observer.filter", self.filter, 1.0)?;
        check_half_open("observer.gain", self.gain, 2.0)?;
        if self.mode == ObserverMode::Predictive && self.observer != ObserverKind::Predictive {
            return Err(ConfigError::new(
                "observer.mode",
                format!(
                    "\"predictive\" needs observer = \"predictive\" (its process model predicts x̂_{{k+1|k}}), not \"{}\"",
                    self.observer
                ),
            ));
        }
        if self.sensor == SensorKind::Angle && self.observer == ObserverKind::PassThrough {
            return Err(ConfigError::new(
                "observer.observer",
                "\"pass-through\" needs sensor = \"full\"; an angle sensor needs \"finite-difference\" or \"predictive\"",
            ));
        }
        Ok(())
    }
}

/// Checks `0 ≤ v < hi`.
fn check_half_open(key: &str, v: f64, hi: f64) -> Result<(), ConfigError> {
    if v.is_finite() && (0.0..hi).contains(&v) {
        Ok(())
    } else {
        Err(ConfigError::new(
            key,
            format!("{v} is out of range: must be a number in [0, {hi})"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_key_and_range() {
        ObserverConfig::default().validate().unwrap();
        let bad = |o: ObserverConfig| o.validate().unwrap_err().to_string();
        let e = bad(ObserverConfig {
            gain: 2.5,
            ..Default::default()
        });
        assert_eq!(
            e,
            "`observer.gain`: 2.5 is out of range: must be a number in [0, 2)"
        );
        let e = bad(ObserverConfig {
            filter: 1.0,
            ..Default::default()
        });
        assert_eq!(
            e,
            "`observer.filter`: 1 is out of range: must be a number in [0, 1)"
        );
        let e = bad(ObserverConfig {
            sensor: SensorKind::Angle,
            mode: ObserverMode::Predictive,
            ..Default::default()
        });
        assert!(e.starts_with("`observer.mode`"), "{e}");
        let e = bad(ObserverConfig {
            sensor: SensorKind::Angle,
            ..Default::default()
        });
        assert!(e.starts_with("`observer.observer`"), "{e}");
    }
}
