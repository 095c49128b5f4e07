//! Function approximators (§3.5) behind one small interface, so that each algorithm is
//! written once for every approximator.
//!
//! An approximator represents a function `y = f(x)`, `x ∈ ℝⁿ`, `y ∈ ℝᵐ`:
//!
//! * [`Approximator::value`] evaluates it;
//! * [`Differentiable::value_and_jacobian`] also gives `∂f/∂x` (RBF and LLR; not tile
//!   coding, whose binary features have no gradient, §3.5);
//! * [`Approximator::shift`] moves `f(x)` by a given step — the actor updates, Eq. 3.1
//!   (SAC) and Eq. 3.9/3.14 (MLAC);
//! * [`Approximator::fit`] moves `f(x)` towards a target — the process-model update
//!   (Algorithm 2 line 13) and the reference-model update (Eq. 3.11);
//! * [`Traced`] adds eligibility traces for a scalar critic, Template 2.1 (Eq. 2.19b–c).
//!
//! For parametric approximators ([`rbf::Rbf`], [`tiles::Tiles`]) the updates are the
//! gradient steps of the thesis; for the memory-based [`llr::Llr`] they are the sample
//! insertions and neighbour adjustments of §3.5.2.

pub mod kdtree;
pub mod llr;
pub mod rbf;
pub mod solve;
pub mod tiles;

/// Largest input dimension of any approximator.
pub const MAX_IN: usize = 8;
/// Largest output dimension of any approximator.
pub const MAX_OUT: usize = 8;

/// A function approximator `y = f(x)`.
pub trait Approximator: Send + crate::checkpoint::Persist {
    /// Input dimension `n`.
    fn input_dim(&self) -> usize;
    /// Output dimension `m`.
    fn output_dim(&self) -> usize;
    /// Writes `f(x)` into `y`.
    fn value(&self, x: &[f64], y: &mut [f64]);
    /// Moves `f(x)` by `step` (already multiplied by the learning rate).
    fn shift(&mut self, x: &[f64], step: &[f64]);
    /// Moves `f(x)` a fraction `rate` of the way towards `target`; an LLR memory also
    /// stores `[x | target]` as a new sample.
    fn fit(&mut self, x: &[f64], target: &[f64], rate: f64);
    /// For a memory-based approximator, `(samples stored, capacity)`.
    fn fill(&self) -> Option<(usize, usize)> {
        None
    }
}

/// An approximator with a gradient with respect to its input.
pub trait Differentiable: Approximator {
    /// Writes `f(x)` into `y` and `∂f/∂x` into `jac` (row-major, `m × n`).
    fn value_and_jacobian(&self, x: &[f64], y: &mut [f64], jac: &mut [f64]);

    /// As [`Self::value_and_jacobian`], with the local model chosen by the first `lead`
    /// inputs only: a memory-based approximator (LLR) takes the neighbours nearest to
    /// `x[..lead]` whatever the remaining inputs — VGBP's process model "for `x_{k+1}`"
    /// before the action is known (Algorithm 7, line 12). A parametric approximator has
    /// no neighbours to choose and evaluates at `x`.
    fn value_and_jacobian_near(&self, x: &[f64], lead: usize, y: &mut [f64], jac: &mut [f64]) {
        let _ = lead;
        self.value_and_jacobian(x, y, jac);
    }

    /// As [`Self::value_and_jacobian_near`], the same neighbours found through an index
    /// over `x[..lead]` that a memory-based approximator keeps from the first such query
    /// on, and fitted nearest first (newer first among equals): the planners' fits along a
    /// plan. The fit's sums run in another order than the scan's, so the two agree to
    /// rounding; VGBP keeps the scan, whose results are recorded bit for bit.
    fn value_and_jacobian_near_indexed(
        &self,
        x: &[f64],
        lead: usize,
        y: &mut [f64],
        jac: &mut [f64],
    ) {
        self.value_and_jacobian_near(x, lead, y, jac);
    }
}

/// A scalar approximator with eligibility traces: the critic of Template 2.1.
pub trait Traced: Approximator {
    /// Visits `x`: `z ← decay · z + ∇_θ V(x)` (Eq. 2.19b). An LLR critic also stores
    /// the sample `[x | V(x)]` with eligibility 1 (§3.5.2, "Application to SAC").
    fn visit(&mut self, x: &[f64], decay: f64);
    /// [`Traced::visit`], returning `V(x)` as it was before the visit.
    fn visit_value(&mut self, x: &[f64], decay: f64) -> f64 {
        let v = scalar(self, x);
        self.visit(x, decay);
        v
    }
    /// `θ ← θ + step · z` (Eq. 2.19c with `step = α_c δ`).
    fn apply_td(&mut self, step: f64);
    /// `z ← 0`, at the start of a trial.
    fn clear_traces(&mut self);
}

/// A scalar approximator with traces and a gradient: what a TD(λ) critic needs
/// ([`crate::critic::TdLambda`]).
pub trait ValueFunction: Traced + Differentiable {}
impl<T: Traced + Differentiable> ValueFunction for T {}

/// `θ ← θ + step · z` (Eq. 2.19c) for a scalar approximator that is linear in its
/// parameters, one parameter and one trace per feature (RBF and tile-coding critics).
pub(crate) fn linear_td_step(theta: &mut [f64], trace: &[f64], step: f64) {
    debug_assert_eq!(
        theta.len(),
        trace.len(),
        "a critic has one parameter per feature"
    );
    for (t, z) in theta.iter_mut().zip(trace) {
        *t += step * z;
    }
}

/// Evaluates a scalar approximator.
pub fn scalar<A: Approximator + ?Sized>(f: &A, x: &[f64]) -> f64 {
    let mut y = [0.0];
    f.value(x, &mut y);
    y[0]
}
