//! Standard actor-critic, SAC (§3.2, Algorithm 1).
//!
//! The actor follows the exploration that turned out well:
//! `ϑ ← ϑ + α_a δ_k Δu_k ∇_ϑ π(x_k)` (Eq. 3.1, line 10). With LLR (§3.5.2,
//! "Application to SAC") the sample `[x_k | u_k]` is stored and its neighbours' actions
//! are moved by `α_a δ_k Δu_k`, saturated to the action bounds; the RBF and tile-coding
//! actors likewise stop at the bounds (see [`crate::approx::rbf`]). `Δu_k` is the
//! exploration actually applied, `sat(π(x_k) + Δu) − π(x_k)`.

use crate::actor_critic::{Improver, Transition};
use crate::approx::Approximator;
use crate::step_size::StepSize;

/// The SAC actor.
pub struct Sac {
    actor: Box<dyn Approximator>,
    step: StepSize,
}

impl Sac {
    /// An actor `π` learning with rate `α_a` (constant, or on a schedule).
    pub fn new(actor: Box<dyn Approximator>, alpha: impl Into<StepSize>) -> Self {
        Self {
            actor,
            step: alpha.into(),
        }
    }
}

/// SAC reads nothing of the critic but the temporal difference: any critic will do.
impl<F: ?Sized> Improver<F> for Sac {
    fn act(&self, x: &[f64], _u_prev: &[f64], _critic: &F, u: &mut [f64]) {
        self.actor.value(x, u);
    }

    fn start_trial(&mut self) {
        self.step.start_trial();
    }

    fn improve(&mut self, t: &Transition, _critic: &F) {
        // Eq. 3.1
        let alpha = self.step.alpha();
        let step: Vec<f64> = t.du.iter().map(|du| alpha * t.td * du).collect();
        self.actor.shift(t.x, &step);
    }
}

use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};

impl Persist for Sac {
    fn save(&self, s: &mut Snapshot) {
        s.scope("actor", |s| {
            self.actor.save(s);
            self.step.save(s);
        });
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.scope("actor", |r| {
            self.actor.restore(r)?;
            self.step.restore(r)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Agent;
    use crate::testing::{self, close, dot, psi};

    /// SAC-FH (Algorithm 4), one trial of `N = 2` samples by hand, on the tiny task of
    /// [`crate::testing`] (actor and critic features `ψ(k)`, independent of `x`).
    #[test]
    fn sac_fh_trial_by_hand() {
        let (alpha_a, alpha_c, lambda) = (0.5, 0.25, 0.5);
        let actor = Box::new(testing::rbf(1, Some(10.0)));
        let sac = Box::new(Sac::new(actor, alpha_a));
        let critic = testing::rbf(1, None);
        let mut ac = testing::agent(testing::info(10.0), critic, alpha_c, lambda, sac, 1.0);
        let (x0, x1, x2, r1, r2) = (0.3, 0.6, 0.8, -1.0, -2.0);
        let mut u = [0.0];
        ac.start_trial(&[x0], &mut u);
        let du0 = u[0]; // π(x_0, 0) = 0: u_0 is all exploration (line 7)
        ac.learn(r1, &[x1], Some(&mut u));
        // k = 0, critic 0: δ_0 = r_1 + θᵀ[φ(x_1, 1) − φ(x_0, 0)] = r_1        (line 14)
        // ϑ = α_a δ_0 Δu_0 ψ(0) (line 16), z = φ(0), θ = α_c δ_0 φ(0)  (lines 17–18)
        let d0 = r1;
        // u_1 = π(x_1, 1) + Δu_1 was chosen before this update (the shared step's order,
        // Algorithm 1 line 9), from the actor still at 0.
        let du1 = u[0];
        assert!(u[0].abs() < 10.0 && du0.abs() < 10.0, "no saturation");
        ac.learn(r2, &[x2], None);
        // k = N − 1: δ_1 = r_2 + τ_N(x_2) − θᵀφ(x_1, 1), τ_N(x) = −x²         (line 12)
        let d1 = r2 - x2 * x2 - alpha_c * d0 * dot(psi(0), psi(1));
        // ϑ += α_a δ_1 Δu_1 ψ(1);  z = λ φ(0) + φ(1), θ += α_c δ_1 z
        for k in 0..2 {
            let (p0, p1) = (dot(psi(0), psi(k)), dot(psi(1), psi(k)));
            let pi = alpha_a * (d0 * du0 * p0 + d1 * du1 * p1);
            close(testing::greedy(&ac, 0.42, k), pi);
            let v = alpha_c * (d0 * p0 + d1 * (lambda * p0 + p1));
            close(ac.value(&[0.42], k), v);
        }
    }
}
