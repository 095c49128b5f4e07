//! Reference model actor-critic, RMAC (§3.4, Algorithm 3).
//!
//! The policy is a reference model `R(x)` of desired next states coupled with the local
//! inverse of the learned process model (lines 9–10): linearising `f̂` around
//! `(x_{k+1}, u_k)`,
//! `u_{k+1} = u_k + (β_uᵀβ_u)⁻¹ β_uᵀ (R(x_{k+1}) − f̂(x_{k+1}, u_k))` (§3.4; regularised
//! by a tiny ridge so that an as yet flat model gives `u_{k+1} = u_k`), saturated.
//!
//! The reference model is improved towards the best reachable state (lines 11–12): the
//! reachable set is approximated by the model's predictions for the extreme actions
//! `U_e` (every corner of the action box), `x_r = argmax V(x')` over them, and
//! `η ← η + α_r (x_r − R(x_k)) ∇_η R(x_k)` (Eq. 3.11) — with LLR the neighbours of
//! `x_k` move towards `x_r` and `[x_k | x_r]` is stored. The process model learns from the
//! observed transition (line 14).
//!
//! `R` is represented as the desired *increment* `x̂ − x` (angles wrapped), for the same
//! reason as the process model (see [`crate::model`]).

use crate::actor_critic::{Improver, TaskInfo, Transition};
use crate::approx::solve::cholesky_solve;
use crate::approx::{Approximator, Differentiable, scalar};
use crate::model::{ProcessModel, increment};
use plant::{MAX_ACTION, MAX_STATE};

/// Ridge on `β_uᵀβ_u` in the model inversion.
const INVERSION_RIDGE: f64 = 1e-6;

/// The RMAC reference model and process model.
pub struct Rmac {
    info: TaskInfo,
    reference: Box<dyn Approximator>,
    model: ProcessModel,
    alpha: f64,
}

impl Rmac {
    /// An RMAC policy with reference model `R` (rate `α_r`) and process model `f̂`.
    pub fn new(
        info: TaskInfo,
        reference: Box<dyn Approximator>,
        model: ProcessModel,
        alpha: f64,
    ) -> Self {
        Self {
            info,
            reference,
            model,
            alpha,
        }
    }

    /// The corners of the action box, `U_e`.
    fn extremes(&self) -> impl Iterator<Item = [f64; MAX_ACTION]> + '_ {
        let m = self.info.m();
        (0..1u32 << m).map(move |bits| {
            let mut u = [0.0; MAX_ACTION];
            for (j, u) in u[..m].iter_mut().enumerate() {
                *u = if bits >> j & 1 == 1 {
                    self.info.action_high[j]
                } else {
                    self.info.action_low[j]
                };
            }
            u
        })
    }
}

impl Improver for Rmac {
    fn act(&self, x: &[f64], u_prev: &[f64], _critic: &dyn Differentiable, u: &mut [f64]) {
        let (n, m) = (self.info.n(), self.info.m());
        // x̂_{k+2} − x_{k+1} = R(x_{k+1})                                  (line 9)
        let mut want = [0.0; MAX_STATE];
        self.reference.value(x, &mut want[..n]);
        // u_{k+1} = f̂⁻¹(x_{k+1}, x̂_{k+2}), linearised around (x_{k+1}, u_k) (line 10)
        let p = self.model.predict(x, u_prev);
        let mut got = [0.0; MAX_STATE];
        increment(&self.info.angle_mask, x, &p.x_next[..n], &mut got[..n]);
        let mut a = [0.0; MAX_ACTION * MAX_ACTION];
        let mut b = [0.0; MAX_ACTION];
        for j in 0..m {
            for l in 0..m {
                a[j * m + l] = (0..n).map(|i| p.du[i * m + j] * p.du[i * m + l]).sum();
            }
            a[j * m + j] += INVERSION_RIDGE;
            b[j] = (0..n).map(|i| p.du[i * m + j] * (want[i] - got[i])).sum();
        }
        if !cholesky_solve(&mut a[..m * m], m, &mut b[..m], 1) {
            b = [0.0; MAX_ACTION];
        }
        for j in 0..m {
            u[j] = u_prev[j] + b[j];
        }
        self.info.saturate(u);
    }

    fn improve(&mut self, t: &Transition, critic: &dyn Differentiable) {
        let n = self.info.n();
        // x_r = argmax_{x' ∈ R̂_x} V(x'),  R̂_x = { f̂(x_k, u) : u ∈ U_e }   (line 11)
        let mut best = (f64::NEG_INFINITY, [0.0; MAX_STATE]);
        for u in self.extremes() {
            let p = self.model.predict(t.x, &u[..self.info.m()]);
            let v = scalar(critic, &p.x_next[..n]);
            if v > best.0 {
                best = (v, p.x_next);
            }
        }
        // η ← η + α_r (x_r − R(x_k)) ∇_η R(x_k)                           (Eq. 3.11)
        let mut target = [0.0; MAX_STATE];
        increment(&self.info.angle_mask, t.x, &best.1[..n], &mut target[..n]);
        self.reference.fit(t.x, &target[..n], self.alpha);
        self.model.learn(t.x, t.u, t.x_next); //                            (line 14)
    }
}
