//! Standard actor-critic, SAC (§3.2, Algorithm 1).
//!
//! The actor follows the exploration that turned out well:
//! `ϑ ← ϑ + α_a δ_k Δu_k ∇_ϑ π(x_k)` (Eq. 3.1, line 10). With LLR (§3.5.2,
//! "Application to SAC") the sample `[x_k | u_k]` is stored and its neighbours' actions
//! are moved by `α_a δ_k Δu_k`, saturated to the action bounds; the RBF and tile-coding
//! actors likewise stop at the bounds (see [`crate::approx::rbf`]). `Δu_k` is the
//! exploration actually applied, `sat(π(x_k) + Δu) − π(x_k)`.

use crate::actor_critic::{Improver, Transition};
use crate::approx::{Approximator, Differentiable};

/// The SAC actor.
pub struct Sac {
    actor: Box<dyn Approximator>,
    alpha: f64,
}

impl Sac {
    /// An actor `π` learning with rate `α_a`.
    pub fn new(actor: Box<dyn Approximator>, alpha: f64) -> Self {
        Self { actor, alpha }
    }
}

impl Improver for Sac {
    fn act(&self, x: &[f64], _u_prev: &[f64], _critic: &dyn Differentiable, u: &mut [f64]) {
        self.actor.value(x, u);
    }

    fn improve(&mut self, t: &Transition, _critic: &dyn Differentiable) {
        // Eq. 3.1
        let step: Vec<f64> = t.du.iter().map(|du| self.alpha * t.td * du).collect();
        self.actor.shift(t.x, &step);
    }
}
