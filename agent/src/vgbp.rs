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
//! with `β_u = ∂f̂/∂u` the input matrix of the local affine process model (Eq. 6.12).
//! A reward with an action term beyond `uᵀPu` (an absolute action cost) keeps
//! Eq. 6.10 and solves it for `u` from the terms' gradients
//! ([`plant::Reward::best_action`]); the reward stays separable and strictly concave in
//! `u`, so the solution is unique. `β_u` is
//! fitted to the model samples nearest to the state: "obtain X and Y from M^P for
//! x_{k+1}" (line 12) comes before the action is known, so an LLR model's neighbours
//! are chosen by the state alone ([`ProcessModel::predict_near_state`]). They were
//! chosen nearest to `(x, u = 0)` before, and where the policy had given `u = 0` (all
//! of the first trial, `∂V/∂x` being zero then) the neighbours all had `u = 0`: no
//! slope along `u`, `β_u = 0`, so Eq. 6.21 gave `u = 0` again — in greedy evaluations
//! the pendulum stayed at the bottom (return −4935) until those samples left the model's
//! memory, 25 trials later (VGBP-LSTD, 20 runs, seed 1: one run, trials 5–25). The
//! old fit at `(x, u = 0)` remains an option (`fit_at_zero_action`) for the VGBP-RBF
//! preset, measured better with it. Exploration and saturation (Eq. 6.11, lines 15–16)
//! are the shared loop's. The model learns every
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
//!
//! **Search** (an option, `grid = levels ≥ 2`; 0 is off): the action maximises the
//! right-hand side of Eq. 6.6 itself, `ρ(x, u) + γ V(f̂(x, u))`, with the process model
//! affine in `u` as Eq. 6.9 has it — `f̂(x, u) = f̂(x, 0) + β_u u`, the fit at the state
//! of line 12 — but without the first-order Taylor step of `V` (Eq. 6.8). Eq. 6.21 is the
//! closed-form maximiser only while `∂V/∂x` is the same at `x` and at `f̂(x, u)`; on the
//! pendulum one step at full voltage changes `φ̇` by 2.6 rad/s, the spacing of the 20 × 20
//! critic grid, so the gradient at `x` says little about `V` where the action leads. Per
//! action component, `levels` evenly spaced values between the bounds and the action of
//! Eq. 6.21 (after any look-ahead) are compared, and the best is refined by a golden
//! section search within one level's spacing; several components are searched one at a
//! time, in two sweeps. The search makes no new model query (one fit per step, as
//! Eq. 6.21); it costs `levels + 2·20` critic evaluations per component and step.

use crate::actor_critic::{Improver, TaskInfo, Transition};
use crate::approx::{Differentiable, scalar};
use crate::critic::ValueWithGradient;
use crate::model::{Prediction, ProcessModel};
use plant::angle::wrap;
use plant::{MAX_ACTION, MAX_STATE};

/// Golden-section steps of the action search: the bracket of two grid steps shrinks by
/// `0.618²⁰ ≈ 7·10⁻⁵` (0.4 mV on the pendulum's 61 levels).
const GOLDEN_STEPS: u32 = 20;

/// The VGBP policy: process model plus the closed-form action of Eq. 6.21.
pub struct Vgbp {
    info: TaskInfo,
    model: ProcessModel,
    gamma: f64,
    lookahead: u32,
    /// Action levels per component of the search of Eq. 6.6 (0: none).
    grid: u32,
    /// Eq. 6.21's model fit at `(x, u = 0)` instead of at the state (see the module docs).
    at_zero_action: bool,
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
            grid: 0,
            at_zero_action: false,
        }
    }

    /// With `levels ≥ 2`: the action maximises the right-hand side of Eq. 6.6 itself
    /// (see the module docs, "Search"), over `levels` evenly spaced values of each action
    /// component between its bounds, refined by a golden-section search; the action of
    /// Eq. 6.21 (and the look-ahead) is one more candidate. 0: no search.
    pub fn with_action_grid(mut self, levels: u32) -> Self {
        self.grid = levels;
        self
    }

    /// With `true`, Eq. 6.21's `β_u` comes from the model samples nearest to
    /// `(x, u = 0)`, as before Algorithm 7 line 12 was followed (kept for the VGBP-RBF
    /// preset, see [`crate::preset`]); `false` (the default): nearest to `x`.
    pub fn with_fit_at_zero_action(mut self, at_zero_action: bool) -> Self {
        self.at_zero_action = at_zero_action;
        self
    }

    /// `ρ(x, u) + γ V(f̂₀ + β_u u)`: the right-hand side of Eq. 6.6 with the model affine
    /// in `u` (Eq. 6.9) — `f̂₀` and `β_u` of the fit at the state, `p0` — and `V` itself.
    fn affine_rhs(
        &self,
        x: &[f64],
        p0: &Prediction,
        u: &[f64],
        critic: &dyn Differentiable,
    ) -> f64 {
        let (n, m) = (self.info.n(), self.info.m());
        let mut xn = [0.0; MAX_STATE];
        for i in 0..n {
            let v = p0.x_next[i] + (0..m).map(|j| p0.du[i * m + j] * u[j]).sum::<f64>();
            xn[i] = if self.info.angle_mask[i] { wrap(v) } else { v };
        }
        self.info.reward.reward(x, u) + self.gamma * scalar(critic, &xn[..n])
    }

    /// Coordinate-wise maximisation of [`Self::affine_rhs`] from the candidate `u`: per
    /// component a grid of `self.grid` levels, then golden-section refinement within one
    /// grid step of the best level; two sweeps when there are several components.
    fn search(&self, x: &[f64], critic: &dyn Differentiable, u: &mut [f64]) {
        let m = self.info.m();
        let p0 = self.model.predict_near_state(x, &[0.0; MAX_ACTION][..m]);
        let mut v = [0.0; MAX_ACTION];
        v[..m].copy_from_slice(u);
        let mut best_q = self.affine_rhs(x, &p0, &v[..m], critic);
        let levels = self.grid.max(2);
        for _ in 0..if m == 1 { 1 } else { 2 } {
            for j in 0..m {
                let (lo, hi) = (self.info.action_low[j], self.info.action_high[j]);
                let h = (hi - lo) / f64::from(levels - 1);
                let q_at = |a: f64| {
                    let mut w = v;
                    w[j] = a;
                    self.affine_rhs(x, &p0, &w[..m], critic)
                };
                let mut best_a = v[j];
                for l in 0..levels {
                    let a = lo + h * f64::from(l);
                    let q = q_at(a);
                    if q > best_q {
                        (best_q, best_a) = (q, a);
                    }
                }
                // Golden section on [best − h, best + h] ∩ [lo, hi].
                let (mut a, mut b) = ((best_a - h).max(lo), (best_a + h).min(hi));
                let r = 0.5 * (5f64.sqrt() - 1.0);
                let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
                let (mut qc, mut qd) = (q_at(c), q_at(d));
                for _ in 0..GOLDEN_STEPS {
                    if qc > qd {
                        (b, d, qd) = (d, c, qc);
                        c = b - r * (b - a);
                        qc = q_at(c);
                    } else {
                        (a, c, qc) = (c, d, qd);
                        d = a + r * (b - a);
                        qd = q_at(d);
                    }
                }
                let (a, q) = if qc > qd { (c, qc) } else { (d, qd) };
                if q > best_q {
                    (best_q, best_a) = (q, a);
                }
                v[j] = best_a;
            }
        }
        u.copy_from_slice(&v[..m]);
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
            if self.at_zero_action {
                self.model.predict(x, u_lin)
            } else {
                self.model.predict_near_state(x, u_lin)
            }
        };
        let at = if at_prediction { &p.x_next[..n] } else { x };
        let (mut v, mut dv) = ([0.0], [0.0; MAX_STATE]);
        critic.value_and_jacobian(at, &mut v, &mut dv[..n]);
        // −∂ρ/∂u_j = γ (∂V/∂x β_u)_j, solved for u_j (Eq. 6.10; 6.21 for a quadratic ρ)
        let (reward, low, high) = (
            &self.info.reward,
            &self.info.action_low,
            &self.info.action_high,
        );
        for j in 0..m {
            let g: f64 = (0..n).map(|i| dv[i] * p.du[i * m + j]).sum();
            u[j] = reward.best_action(j, self.gamma * g, low[j], high[j]);
        }

        self.info.saturate(u);
    }
}

impl Improver for Vgbp {
    fn act(&self, x: &[f64], _u_prev: &[f64], critic: &ValueWithGradient, u: &mut [f64]) {
        let m = self.info.m();
        // Lines 12–14: β^P from the model's neighbours of x_{k+1}; Eq. 6.21.
        self.greedy_step(x, &[0.0; MAX_ACTION][..m], false, critic, u);
        if self.lookahead > 0 {
            self.look_ahead(x, critic, u);
        }
        if self.grid > 0 {
            self.search(x, critic, u);
        }
    }

    fn improve(&mut self, t: &Transition, _critic: &ValueWithGradient) {
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

impl Vgbp {
    /// The look-ahead from Eq. 6.21's action `u` (see the module docs).
    fn look_ahead(&self, x: &[f64], critic: &dyn Differentiable, u: &mut [f64]) {
        let m = self.info.m();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::approx::Approximator;
    use crate::horizon::Horizon;
    use crate::testing;

    /// `V(x) = −s x²`.
    struct Quadratic(f64);

    impl Persist for Quadratic {
        fn save(&self, _: &mut Snapshot) {}
        fn restore(&mut self, _: &mut Reader) -> Result<(), CheckpointError> {
            Ok(())
        }
    }

    impl Approximator for Quadratic {
        fn input_dim(&self) -> usize {
            1
        }
        fn output_dim(&self) -> usize {
            1
        }
        fn value(&self, x: &[f64], y: &mut [f64]) {
            y[0] = -self.0 * x[0] * x[0];
        }
        fn shift(&mut self, _: &[f64], _: &[f64]) {}
        fn fit(&mut self, _: &[f64], _: &[f64], _: f64) {}
    }

    impl Differentiable for Quadratic {
        fn value_and_jacobian(&self, x: &[f64], y: &mut [f64], jac: &mut [f64]) {
            self.value(x, y);
            jac[0] = -2.0 * self.0 * x[0];
        }
    }

    /// The tiny task of [`crate::testing::info`] with `P = 2` and an infinite horizon.
    fn info(bound: f64) -> TaskInfo {
        let mut info = crate::testing::info(bound);
        info.reward.p = vec![2.0];
        info.horizon = Horizon::Infinite;
        info
    }

    /// `x' = x + b u`, `ρ = −x² − p u²`, `V = −s x²`: Eq. 6.21 takes `∂V/∂x` at `x`,
    /// `u = ½ γ b (−2 s x) / p = −γ s b x / p`; the maximiser of Eq. 6.6,
    /// `−p u² − γ s (x + b u)²`, is `u* = −γ s b x / (p + γ s b²)`. The search finds
    /// `u*`, and stops at the bound when `u*` lies beyond it.
    #[test]
    fn the_search_maximises_eq_6_6() {
        let (b, s, p, g, x) = (0.5, 3.0, 2.0, 0.9, 0.8);
        let critic = Quadratic(s);
        let mut u = [0.0];
        Vgbp::new(info(10.0), testing::model(b), g, 0).act(&[x], &[0.0], &critic, &mut u);
        assert!(
            (u[0] - (-g * s * b * x / p)).abs() < 1e-12,
            "Eq. 6.21: {}",
            u[0]
        );
        let want = -g * s * b * x / (p + g * s * b * b);
        let vgbp = Vgbp::new(info(10.0), testing::model(b), g, 0).with_action_grid(61);
        vgbp.act(&[x], &[0.0], &critic, &mut u);
        assert!(
            (u[0] - want).abs() < 1e-4,
            "search: {} against {want}",
            u[0]
        );
        let vgbp = Vgbp::new(info(0.2), testing::model(b), g, 0).with_action_grid(61);
        vgbp.act(&[x], &[0.0], &critic, &mut u);
        assert_eq!(u[0], -0.2);
    }
}
