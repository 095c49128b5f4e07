//! State observers: from what the plant's sensor measures to the state estimate `x̂_k`
//! the agent acts on.
//!
//! * [`PassThrough`] — the sensor measures the full state (the thesis's simulations).
//! * [`FiniteDifference`] — the sensor measures only the angles (the physical pendulum
//!   of §6.4.1 has an encoder on the motor shaft); velocities are estimated by a
//!   backward difference over one sample, wrapped, smoothed by a first-order low-pass.
//! * [`Predictive`] — angle-only measurement with a model-predicted state: the process
//!   model (learned online by LLR from the observer's own estimates, or the plant's known
//!   dynamics) predicts `x̂_{k+1|k}`, and the measured angle corrects it.
//! * [`timing`] — what the agent acts on and learns from, in direct or predictive timing
//!   (shared by `rig learn` and the observer process of `rig run`).
//! * [`config`] — `[observer]`: sensor, observer and timing, with their validation;
//!   [`build`] — the observer a [`config::ObserverConfig`] asks for.
//!
//! Observers are plain step functions; they know nothing about processes or transport.

pub mod config;
pub mod predictive;
pub mod timing;

pub use predictive::{Predictive, PredictiveModel};

use std::sync::Arc;

use agent::config::Component;
use config::{ObserverConfig, ObserverKind, ObserverModel};
use plant::Task;
use plant::angle::wrap;

/// A state estimator, updated once per sample.
pub trait Observer: Send {
    /// Restarts at a trial start, where the state is known to be `x0`.
    fn reset(&mut self, x0: &[f64]);
    /// Updates with the measurement `y_k` (and the action applied over the last
    /// interval) and returns `x̂_k`.
    fn update(&mut self, y: &[f64], u_applied: &[f64]) -> &[f64];
    /// The one-step prediction `x̂_{k+1|k} = f̂(x̂_k, u_k)` from the current estimate and
    /// the action `u_k` applied over the coming interval, if this observer has a process
    /// model (predictive timing, [`timing`]); it does not change the estimate.
    fn predict_next(&mut self, _u: &[f64]) -> Option<&[f64]> {
        None
    }
}

/// Full-state measurement: `x̂_k = y_k`.
pub struct PassThrough {
    x: Vec<f64>,
}

impl PassThrough {
    /// For states of dimension `n`.
    pub fn new(n: usize) -> Self {
        Self { x: vec![0.0; n] }
    }
}

impl Observer for PassThrough {
    fn reset(&mut self, x0: &[f64]) {
        self.x.copy_from_slice(x0);
    }
    fn update(&mut self, y: &[f64], _u: &[f64]) -> &[f64] {
        self.x.copy_from_slice(y);
        &self.x
    }
}

/// Angle-only measurement with finite-difference velocities.
///
/// The state is `[angles…, velocities…]` or interleaved; `position_of[i]` names, for each
/// velocity component `i`, the angle it is the derivative of. The velocity estimate is
/// `v̂_k = a · v̂_{k−1} + (1 − a) · wrap(φ_k − φ_{k−1}) / Ts` with `a` the filter
/// coefficient (0: raw difference).
pub struct FiniteDifference {
    ts: f64,
    filter: f64,
    /// `(velocity index, angle index)` pairs.
    pairs: Vec<(usize, usize)>,
    x: Vec<f64>,
}

impl FiniteDifference {
    /// For sampling time `ts`, velocity/angle index pairs and filter coefficient in [0, 1).
    pub fn new(n: usize, ts: f64, pairs: Vec<(usize, usize)>, filter: f64) -> Self {
        assert!((0.0..1.0).contains(&filter) && ts > 0.0);
        Self {
            ts,
            filter,
            pairs,
            x: vec![0.0; n],
        }
    }
}

impl Observer for FiniteDifference {
    fn reset(&mut self, x0: &[f64]) {
        self.x.copy_from_slice(x0);
    }
    fn update(&mut self, y: &[f64], _u: &[f64]) -> &[f64] {
        for &(v, a) in &self.pairs {
            let raw = wrap(y[a] - self.x[a]) / self.ts;
            self.x[v] = self.filter * self.x[v] + (1.0 - self.filter) * raw;
        }
        for &(_, a) in &self.pairs {
            self.x[a] = y[a];
        }
        &self.x
    }
}

/// `(velocity index, position index)` pairs of a state `[positions…, velocities…]` of
/// dimension `n` (every system of the `plant` crate is ordered so).
pub fn velocity_pairs(n: usize) -> Vec<(usize, usize)> {
    (0..n / 2).map(|i| (n / 2 + i, i)).collect()
}

/// The observer `cfg` asks for on `task`. A learned predictive model is an LLR memory with
/// the input scaling of the agent's LLR process model `agent_model` when there is one
/// (Table 6.2: angles 1, velocities 0.1, actions 1), else that default.
pub fn build(
    task: Arc<Task>,
    cfg: &ObserverConfig,
    agent_model: Option<&Component>,
) -> Box<dyn Observer> {
    let n = task.state_dim();
    match cfg.observer {
        ObserverKind::PassThrough => Box::new(PassThrough::new(n)),
        ObserverKind::FiniteDifference => Box::new(FiniteDifference::new(
            n,
            task.ts,
            velocity_pairs(n),
            cfg.filter,
        )),
        ObserverKind::Predictive => {
            let model = match cfg.model {
                ObserverModel::Known => PredictiveModel::Known,
                ObserverModel::Learned => {
                    let weights = match agent_model {
                        Some(Component::Llr(l)) => l.weights.clone(),
                        _ => predictive::default_weights(&task),
                    };
                    PredictiveModel::learned(&task, weights)
                }
            };
            Box::new(Predictive::new(task, model, cfg.gain))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_through_returns_the_measurement() {
        let mut o = PassThrough::new(2);
        o.reset(&[1.0, 2.0]);
        assert_eq!(o.update(&[3.0, 4.0], &[0.0]), &[3.0, 4.0]);
    }

    #[test]
    fn finite_difference_recovers_a_constant_velocity_across_the_wrap() {
        let ts = 0.03;
        let mut o = FiniteDifference::new(2, ts, vec![(1, 0)], 0.0);
        let w = 5.0;
        let mut phi = 3.0;
        o.reset(&[phi, w]);
        for _ in 0..20 {
            phi = wrap(phi + w * ts);
            // The measurement's velocity entry is ignored (not measured).
            let x = o.update(&[phi, f64::NAN], &[0.0]).to_vec();
            assert!((x[1] - w).abs() < 1e-9, "{x:?}");
            assert_eq!(x[0], phi);
        }
    }
}
