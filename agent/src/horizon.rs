//! The horizon of the task: infinite and discounted (Chapters 3, 5, 6), or finite —
//! `N` steps and then a terminal reward `τ_N(x_N)` (Chapter 4, Eq. 4.1).
//!
//! A finite horizon makes the optimal actor and critic time-varying. As in §4.3.1 (the
//! parameterisation of Eq. 4.6, `V(x, k) = θᵀφ(x, k)`, `π(x, k) = ϑᵀψ(x, k)`), time is
//! one more input of the actor, the critic and RMAC's reference model: they read
//! [`Input`]s `(x, k)`. Everything else is the algorithms of Chapter 3 unchanged
//! (Algorithms 4–6), apart from the temporal difference of the last step, whose target
//! is the known terminal value `V_N(x_N) = τ_N(x_N)` (Eq. 4.3) instead of the critic's
//! estimate:
//!
//! ```text
//! δ_k     = r_{k+1} + θᵀ[φ(x_{k+1}, k+1) − φ(x_k, k)]     k < N − 1
//! δ_{N−1} = r_N + τ_N(x_N) − θᵀφ(x_{N−1}, N−1)            (Algorithm 4 lines 11–15)
//! ```
//!
//! Algorithms 4–6 have no discount: the finite-horizon presets set `γ = 1`.
//!
//! The process model stays time-invariant (footnote 2 of §4.2: the terminal reward is
//! the sole cause of a time-varying policy): [`crate::model::ProcessModel`] predicts the
//! state part of `(x, k)` and advances time by one step, the known dynamics of time.
//! The terminal reward is `τ_N(x) = −eᵀ Q_N e`: §4.4 takes the state part of the reward,
//! `Q_N = Q`, as every built-in task does ([`plant::Reward::terminal_reward`]).

use std::ops::Deref;

use plant::Reward;

use crate::approx::MAX_IN;

/// How long a trial's cost function runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Horizon {
    /// Discounted, without end: `V(x)`, `π(x)`.
    Infinite,
    /// `steps = N` samples, then the terminal reward: `V(x, k)`, `π(x, k)` (Eq. 4.6).
    Finite {
        /// The horizon `N`: the number of samples of a trial.
        steps: usize,
    },
}

impl Horizon {
    /// Inputs the horizon adds to the actor's and critic's: 1 (time) if finite, else 0.
    pub fn extra_inputs(self) -> usize {
        match self {
            Horizon::Infinite => 0,
            Horizon::Finite { .. } => 1,
        }
    }

    /// The range of the time input, `k ∈ {0, …, N − 1}`, for the approximators' grids.
    pub fn time_range(self) -> Option<(f64, f64)> {
        match self {
            Horizon::Infinite => None,
            Horizon::Finite { steps } => Some((0.0, steps.saturating_sub(1) as f64)),
        }
    }

    /// The actor's and critic's input at sample `k` in state `x`: `x`, or `(x, k)`
    /// (Eq. 4.6).
    pub fn input(self, x: &[f64], k: usize) -> Input {
        let mut v = [0.0; MAX_IN];
        v[..x.len()].copy_from_slice(x);
        let len = match self {
            Horizon::Infinite => x.len(),
            Horizon::Finite { .. } => {
                v[x.len()] = k as f64;
                x.len() + 1
            }
        };
        Input { v, len }
    }

    /// Whether the transition from sample `k` is the trial's last (`k = N − 1`), whose
    /// temporal difference targets `τ_N(x_N)` (Algorithms 4–6).
    pub fn ends_after(self, k: usize) -> bool {
        match self {
            Horizon::Infinite => false,
            Horizon::Finite { steps } => k + 1 >= steps,
        }
    }

    /// What a trial's return adds after its last sample: `τ_N(x_N)` if finite (Eq. 4.1),
    /// nothing otherwise.
    pub fn final_reward(self, reward: &Reward, x_n: &[f64]) -> f64 {
        match self {
            Horizon::Infinite => 0.0,
            Horizon::Finite { .. } => reward.terminal_reward(x_n),
        }
    }
}

/// An input of the actor and critic: the state `x`, followed by time `k` for a finite
/// horizon ([`Horizon::input`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Input {
    v: [f64; MAX_IN],
    len: usize,
}

impl Deref for Input {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.v[..self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_is_appended_only_for_a_finite_horizon() {
        let x = [0.5, -2.0];
        assert_eq!(&*Horizon::Infinite.input(&x, 7), &x);
        let h = Horizon::Finite { steps: 100 };
        assert_eq!(&*h.input(&x, 7), &[0.5, -2.0, 7.0]);
        assert_eq!(h.time_range(), Some((0.0, 99.0)));
        assert!(!h.ends_after(98) && h.ends_after(99));
        assert!(!Horizon::Infinite.ends_after(usize::MAX - 1));
    }
}
