//! Value-gradient based policy, VGBP (Doya, 2000; §6.3, Algorithm 7): a critic-only
//! learner that takes its action from the right-hand side of the Bellman equation,
//! using the known reward function and a learned process model (Eq. 6.6).
//!
//! With `V` linearised around `x` and `f̂` linear in `u` (Eq. 6.7–6.9), the maximiser of
//! `ρ(x, u) + γ V(f̂(x, u))` solves `−∂ρ/∂u = γ ∂V/∂x ∂f̂/∂u` (Eq. 6.10); for the
//! quadratic reward `ρ = −eᵀQe − uᵀPu` (Eq. 6.20) in closed form
//!
//! ```text
//! u = ½ γ P⁻¹ β_uᵀ ∂V(x)/∂xᵀ                              Eq. 6.21 (lines 12–14)
//! ```
//!
//! with `β_u = ∂f̂/∂u` the input matrix of the local affine process model (Eq. 6.12),
//! fitted to the model samples nearest to the state: "obtain X and Y from M^P for
//! x_{k+1}" (line 12) comes before the action is known, so an LLR model's neighbours
//! are chosen by the state alone ([`ProcessModel::predict_near_state`]). They were
//! chosen nearest to `(x, u = 0)` before, and where the policy had given `u = 0` (all
//! of the first trial, `∂V/∂x` being zero then) the neighbours all had `u = 0`: no
//! slope along `u`, `β_u = 0`, so Eq. 6.21 gave `u = 0` again — in greedy evaluations
//! the pendulum stayed at the bottom (return −4935) until those samples left the model's
//! memory, 25 trials later (VGBP-LSTD, 20 runs: one run for trials 5–25, and the same
//! trap behind many of the spikes of the plain Eq. 6.21). Exploration and
//! saturation (Eq. 6.11, lines 15–16) are the shared loop's. The model learns every
//! transition (line 10); the critic is any [`crate::critic::Critic`] — LSTD(λ) on RBFs,
//! RBF with TD(λ), or LLR.
//!
//! **Look-ahead** (an option; 0 is the thesis's Eq. 6.21): with `lookahead = n > 0` the
//! gradient is re-evaluated `n` times at the predicted next state,
//! `u ← ½ γ P⁻¹ β_uᵀ ∂V(f̂(x, u))/∂xᵀ` (the model re-linearised at the new `u`) — Eq. 6.10
//! without the Taylor step of Eq. 6.8 — and of the iterates the one with the highest
//! right-hand side of Eq. 6.6, `ρ(x, u) + γ V(f̂(x, u))`, is taken (near a bound the plain
//! iteration can flip between the two extreme actions). For a linear system and a
//! quadratic critic the fixed point is exactly the discrete-time LQR action, where
//! Eq. 6.21 is off by a term of order `γ BᵀSB / P` (11 % for the double integrator at
//! `Ts = 0.05`; `tests/tests/lqr.rs`).

use crate::actor_critic::{Improver, TaskInfo, Transition};
use crate::approx::{Differentiable, scalar};
use crate::model::ProcessModel;
use plant::{MAX_ACTION, MAX_STATE};

/// The VGBP policy: process model plus the closed-form action of Eq. 6.21.
pub struct Vgbp {
    info: TaskInfo,
    model: ProcessModel,
    gamma: f64,
    lookahead: u32,
}

impl Vgbp {
    /// VGBP with process model `f̂`, discount `γ` and `lookahead` re-evaluations of the
    /// value gradient at the predicted next state (0: Eq. 6.21 as in the thesis).
    ///
    /// # Panics
    /// If the reward's action weights `P` are not all positive: Eq. 6.21 needs `P⁻¹`
    /// (the reward must be concave in `u`, §6.3).
    pub fn new(info: TaskInfo, model: ProcessModel, gamma: f64, lookahead: u32) -> Self {
        assert!(
            info.reward.p.iter().all(|&p| p > 0.0),
            "VGBP needs a reward strictly concave in u (P > 0)"
        );
        Self {
            info,
            model,
            gamma,
            lookahead,
        }
    }

    /// `ρ(x, u) + γ V(f̂(x, u))`, the right-hand side of Eq. 6.6.
    fn bellman_rhs(&self, x: &[f64], u: &[f64], critic: &dyn Differentiable) -> f64 {
        let n = self.info.n();
        let p = self.model.predict(x, u);
        self.info.reward.reward(x, u) + self.gamma * scalar(critic, &p.x_next[..n])
    }

    /// `u = ½ γ P⁻¹ β_uᵀ ∇V(at)`, with `β_u = ∂f̂/∂u` linearised at `(x, u_lin)`.
    fn greedy_step(
        &self,
        x: &[f64],
        u_lin: &[f64],
        at_prediction: bool,
        critic: &dyn Differentiable,
        u: &mut [f64],
    ) {
        let (n, m) = (self.info.n(), self.info.m());
        let p = if at_prediction {
            self.model.predict(x, u_lin)
        } else {
            self.model.predict_near_state(x, u_lin)
        };
        let at = if at_prediction { &p.x_next[..n] } else { x };
        let (mut v, mut dv) = ([0.0], [0.0; MAX_STATE]);
        critic.value_and_jacobian(at, &mut v, &mut dv[..n]);
        for j in 0..m {
            let g: f64 = (0..n).map(|i| dv[i] * p.du[i * m + j]).sum();
            u[j] = 0.5 * self.gamma * g / self.info.reward.p[j];
        }

        self.info.saturate(u);
    }
}

impl Improver for Vgbp {
    fn act(&self, x: &[f64], _u_prev: &[f64], critic: &dyn Differentiable, u: &mut [f64]) {
        let m = self.info.m();
        // Lines 12–14: β^P from the model's neighbours of (x_{k+1}, 0); Eq. 6.21.
        self.greedy_step(x, &[0.0; MAX_ACTION][..m], false, critic, u);
        if self.lookahead == 0 {
            return;
        }
        // Look-ahead: iterate Eq. 6.10 at the predicted next state and keep the iterate
        // with the highest right-hand side of Eq. 6.6.
        let mut best = [0.0; MAX_ACTION];
        best[..m].copy_from_slice(u);
        let mut best_q = self.bellman_rhs(x, &best[..m], critic);
        let mut u_lin = [0.0; MAX_ACTION];
        for _ in 0..self.lookahead {
            u_lin[..m].copy_from_slice(u);
            self.greedy_step(x, &u_lin[..m], true, critic, u);
            let q = self.bellman_rhs(x, u, critic);
            if q > best_q {
                best_q = q;
                best[..m].copy_from_slice(u);
            }
        }
        u.copy_from_slice(&best[..m]);
    }

    fn improve(&mut self, t: &Transition, _critic: &dyn Differentiable) {
        self.model.learn(t.x, t.u, t.x_next); //                          (line 10)
    }

    fn acts_after_update(&self) -> bool {
        true
    }

    fn memories(&self) -> Vec<(&'static str, usize, usize)> {
        self.model
            .fill()
            .map(|(s, c)| ("model", s, c))
            .into_iter()
            .collect()
    }
}
use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};

impl Persist for Vgbp {
    fn save(&self, s: &mut Snapshot) {
        self.model.save(s);
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        self.model.restore(r)
    }
}
