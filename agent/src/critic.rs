//! The critic `V(x)`: a differentiable value function together with the rule by which it
//! learns — TD(λ) with eligibility traces (Template 2.1, Eq. 2.19; [`TdLambda`]) or
//! least-squares TD(λ) (Eq. 6.16–6.19; [`crate::lstd::Lstd`]).
//!
//! The learners read the critic through [`Critic::function`] (`V` and `∂V/∂x`, which
//! MLAC's gradient, RMAC's reachable-set choice and VGBP's action need) and drive it per
//! sample:
//!
//! ```text
//! δ_k ← observe(x_k, r_{k+1}, next)      visit x_k (trace), TD error     Eq. 2.19a–b
//! …   the policy improvement reads V (before the critic changes)
//! update(δ_k)                             θ ← θ + α_c δ_k z_k             Eq. 2.19c
//! end_trial()                             LSTD: θ ← A⁻¹ b                  Eq. 6.19
//! ```
//!
//! `next` is the state `x_{k+1}`, whose value the critic estimates, or — at the end of a
//! finite horizon — the known terminal value `τ_N(x_N)` (Eq. 4.3, [`Next::Terminal`]).

use crate::approx::{Approximator, Differentiable, Traced, ValueFunction, scalar};
use crate::step_size::StepSize;

/// What follows `x_k` in the target of the temporal difference.
#[derive(Clone, Copy, Debug)]
pub enum Next<'a> {
    /// The next input `x_{k+1}` (with time, for a finite horizon): the target is
    /// `r_{k+1} + γ V(x_{k+1})`.
    State(&'a [f64]),
    /// The horizon has ended in a state worth this much, `V_N(x_N) = τ_N(x_N)` (Eq. 4.3):
    /// the target is `r_N + γ τ_N(x_N)` (Algorithms 4–6, where `γ = 1`).
    Terminal(f64),
}

/// A value function with its gradient `∇_x V`, as a critic hands it to a policy improvement
/// that needs the gradient (MLAC's, RMAC's, VGBP's); SAC's reads `dyn Approximator`.
pub type ValueWithGradient = dyn Differentiable;

/// A critic and its learning rule; `F` is what the policy improvement reads of its value
/// function: `V(x)` with its gradient (the default), or `V(x)` only (SAC's).
pub trait Critic<F: ?Sized = ValueWithGradient>: Send + crate::checkpoint::Persist {
    /// The value function `V(x)`, as the policy improvement reads it.
    fn function(&self) -> &F;
    /// Clears the eligibility traces at the start of a trial.
    fn start_trial(&mut self);
    /// Visits `x_k` (traces, Eq. 2.19b / 6.16) and returns the temporal difference
    /// `δ_k = r_{k+1} + γ V(x_{k+1}) − V(x_k)` (Eq. 2.19a), with `τ_N(x_N)` in place of
    /// `V(x_{k+1})` after a finite horizon's last sample ([`Next::Terminal`]).
    fn observe(&mut self, x: &[f64], r: f64, next: Next, gamma: f64, lambda: f64) -> f64;
    /// Updates the parameters with `δ_k` (Eq. 2.19c); called after the policy
    /// improvement has read the critic.
    fn update(&mut self, td: f64);
    /// The trial has ended (after its last [`Critic::update`]).
    fn end_trial(&mut self) {}
    /// For a memory-based critic, `(samples stored, capacity)`.
    fn fill(&self) -> Option<(usize, usize)> {
        None
    }
}

/// TD(λ) with accumulating eligibility traces, Template 2.1: any traced approximator
/// (RBF, LLR, tile coding) with learning rate `α_c` (constant, or `α_{c,k}` on a
/// [`StepSize`] schedule). `V` is its kind of value function: one
/// with a gradient (the default), or without (`dyn Traced`: tile coding, SAC's).
pub struct TdLambda<V: ?Sized = dyn ValueFunction> {
    f: Box<V>,
    step: StepSize,
}

impl TdLambda {
    /// A TD(λ) critic learning `f` with rate `α_c`.
    pub fn new(f: Box<dyn ValueFunction>, alpha: impl Into<StepSize>) -> Self {
        Self {
            f,
            step: alpha.into(),
        }
    }
}

impl TdLambda<dyn Traced> {
    /// A TD(λ) critic learning `f` with rate `α_c`, read for its values only: the critic
    /// of an improver that never asks for `∇_x V` (SAC's; tile coding has none).
    pub fn values_only(f: Box<dyn Traced>, alpha: impl Into<StepSize>) -> Self {
        Self {
            f,
            step: alpha.into(),
        }
    }
}

/// A value function read as an `F` ([`Critic::function`]).
pub trait ReadAs<F: ?Sized> {
    /// `self` as an `F`.
    fn read_as(&self) -> &F;
}

impl ReadAs<ValueWithGradient> for dyn ValueFunction {
    fn read_as(&self) -> &ValueWithGradient {
        self
    }
}

impl ReadAs<dyn Approximator> for dyn Traced {
    fn read_as(&self) -> &(dyn Approximator + 'static) {
        self
    }
}

impl<V: Traced + ReadAs<F> + ?Sized, F: ?Sized> Critic<F> for TdLambda<V> {
    fn function(&self) -> &F {
        self.f.read_as()
    }

    fn start_trial(&mut self) {
        self.f.clear_traces();
        self.step.start_trial();
    }

    fn observe(&mut self, x: &[f64], r: f64, next: Next, gamma: f64, lambda: f64) -> f64 {
        // z ← λγ z + ∇_θ V(x_k) (an LLR critic stores [x_k | V(x_k)] first, §3.5.2), then
        // δ_k with V(x_{k+1}) as the critic stands after the visit.
        let v = self.f.visit_value(x, lambda * gamma);
        let v_next = match next {
            Next::State(x_next) => scalar(self.f.as_ref(), x_next),
            Next::Terminal(tau) => tau,
        };
        r + gamma * v_next - v
    }

    fn update(&mut self, td: f64) {
        self.f.apply_td(self.step.alpha() * td);
    }

    fn fill(&self) -> Option<(usize, usize)> {
        self.f.fill()
    }
}

impl<V: Traced + ?Sized> crate::checkpoint::Persist for TdLambda<V> {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        self.f.save(s);
        self.step.save(s);
    }
    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        self.f.restore(r)?;
        self.step.restore(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::approx::rbf::{Rbf, RbfParams};

    /// TD(λ) on a single basis function `φ ≡ 1` (`V = θ`), starting at `θ = 1`.
    fn one_feature(alpha: f64) -> TdLambda {
        let rbf = Rbf::new(&RbfParams {
            centres: vec![1],
            range: vec![(0.0, 1.0)],
            periodic: vec![false],
            intersection: 0.5,
            outputs: 1,
            initial: 1.0,
            bounds: None,
        });
        TdLambda::new(Box::new(rbf), alpha)
    }

    /// `δ = r + γ V(x') − V(x)`, then `θ ← θ + α δ z` with `z = λγ z + 1` (Eq. 2.19);
    /// into a terminal state of value zero (§6.4.2) the trace still decays with `λγ`.
    #[test]
    fn td_steps_by_hand_including_a_terminal_one() {
        let (alpha, gamma, lambda) = (0.5, 0.9, 0.5);
        let mut c = one_feature(alpha);
        c.start_trial();
        // δ = −1 + 0.9·1 − 1 = −1.1; z = 1; θ = 1 − 0.55 = 0.45.
        let td = c.observe(&[0.3], -1.0, Next::State(&[0.6]), gamma, lambda);
        assert!((td + 1.1).abs() < 1e-12, "{td}");
        c.update(td);
        assert!((scalar(c.function(), &[0.1]) - 0.45).abs() < 1e-12);
        // Terminal: δ = −2 + 0 − 0.45 = −2.45; z = 0.45·1 + 1 = 1.45;
        // θ = 0.45 + 0.5·(−2.45)·1.45.
        let td = c.observe(&[0.6], -2.0, Next::Terminal(0.0), gamma, lambda);
        assert!((td + 2.45).abs() < 1e-12, "{td}");
        c.update(td);
        let want = 0.45 - 0.5 * 2.45 * 1.45;
        assert!((scalar(c.function(), &[0.1]) - want).abs() < 1e-12);
    }
}
