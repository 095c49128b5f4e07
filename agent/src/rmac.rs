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
//!
//! **RMAC-FH** (Algorithm 6, §4.3.4) is this improver with a finite horizon: the
//! reference model reads `(x, k)` and still outputs a state (without time), and the
//! reachable states `(f̂(x_k, u), k+1)` are compared by the critic at time `k + 1`.

use crate::actor_critic::{Improver, TaskInfo, Transition};
use crate::approx::solve::cholesky_solve;
use crate::approx::{Approximator, scalar};
use crate::critic::ValueWithGradient;
use crate::model::{ProcessModel, increment};
use crate::step_size::StepSize;
use plant::{MAX_ACTION, MAX_STATE};

/// Ridge on `β_uᵀβ_u` in the model inversion.
const INVERSION_RIDGE: f64 = 1e-6;

/// The RMAC reference model and process model.
pub struct Rmac {
    info: TaskInfo,
    reference: Box<dyn Approximator>,
    model: ProcessModel,
    step: StepSize,
}

impl Rmac {
    /// An RMAC policy with reference model `R` (rate `α_r`, constant or on a schedule)
    /// and process model `f̂`.
    pub fn new(
        info: TaskInfo,
        reference: Box<dyn Approximator>,
        model: ProcessModel,
        alpha: impl Into<StepSize>,
    ) -> Self {
        Self {
            info,
            reference,
            model,
            step: alpha.into(),
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
    fn act(&self, x: &[f64], u_prev: &[f64], _critic: &ValueWithGradient, u: &mut [f64]) {
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

    fn start_trial(&mut self) {
        self.step.start_trial();
    }

    fn improve(&mut self, t: &Transition, critic: &ValueWithGradient) {
        let (n, d) = (self.info.n(), self.info.input_dim());
        // x_r = argmax_{x' ∈ R̂_x} V(x'),  R̂_x = { f̂(x_k, u) : u ∈ U_e }   (line 11)
        let mut best = (f64::NEG_INFINITY, [0.0; MAX_STATE]);
        for u in self.extremes() {
            let p = self.model.predict(t.x, &u[..self.info.m()]);
            let v = scalar(critic, &p.x_next[..d]);
            if v > best.0 {
                best = (v, p.x_next);
            }
        }
        // η ← η + α_r (x_r − R(x_k)) ∇_η R(x_k)                           (Eq. 3.11)
        let mut target = [0.0; MAX_STATE];
        increment(&self.info.angle_mask, t.x, &best.1[..n], &mut target[..n]);
        self.reference.fit(t.x, &target[..n], self.step.alpha());
        self.model.learn(t.x, t.u, t.x_next); //                            (line 14)
    }
}

use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};

impl Persist for Rmac {
    fn save(&self, s: &mut Snapshot) {
        s.scope("reference", |s| {
            self.reference.save(s);
            self.step.save(s);
        });
        self.model.save(s);
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.scope("reference", |r| {
            self.reference.restore(r)?;
            self.step.restore(r)
        })?;
        self.model.restore(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Agent;
    use crate::testing::{self, AT_0, AT_1, close, dot, psi};

    /// RMAC-FH (Algorithm 6), the reference-model update of one sample by hand
    /// (lines 23–24), on the tiny task of [`crate::testing`] with the model `x' = x + b u`
    /// and actions in `[−1, 1]`: the reachable states are compared at time `k + 1`.
    #[test]
    fn rmac_fh_step_by_hand() {
        let (alpha_r, b, x0) = (0.5, 0.5, 0.5);
        // V prefers x = 0 at k = 0 and x = 1 at k = 1.
        let theta = [0.0, -10.0, -10.0, 0.0];
        let v = |phi: [f64; 2], k| {
            phi[0] * dot([theta[0], theta[1]], psi(k)) + phi[1] * dot([theta[2], theta[3]], psi(k))
        };
        assert!(v(AT_1, 1) > v(AT_0, 1) && v(AT_0, 0) > v(AT_1, 0));
        let info = testing::info(1.0);
        let reference = Box::new(testing::rbf(1, None));
        let rmac = Rmac::new(info.clone(), reference, testing::model(b), alpha_r);
        let mut ac = testing::agent(info, testing::critic(theta), 0.0, 0.0, Box::new(rmac), 1.0);
        let mut u = [0.0];
        ac.start_trial(&[x0], &mut u);
        ac.learn(-1.0, &[0.7], Some(&mut u));
        // Reachable from (x_0, 0): (x_0 ∓ b, 1) = (0, 1), (1, 1); the best is x_r = 1
        // (line 23). R is the desired increment: η ← η + α_r (x_r − x_0 − R(x_0, 0)) ψ(0)
        // with R(x_0, 0) = 0 (line 24).
        let eta = alpha_r * (1.0 - x0);
        for k in 0..2 {
            // u = f̂⁻¹(x, x + R(x, k)) around u_prev = 0: b R / (b² + ridge)      (line 11)
            let r = eta * dot(psi(0), psi(k));
            close(
                testing::greedy(&ac, x0, k),
                b * r / (b * b + INVERSION_RIDGE),
            );
        }
    }
}
