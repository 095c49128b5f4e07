//! A tiny finite-horizon task for hand-computed steps of SAC-FH, MLAC-FH and RMAC-FH
//! (Algorithms 4–6), driven through the shared step ([`ActorCritic`]).
//!
//! One state `x ∈ [0, 1]` (not an angle), one action, horizon `N = 2` (`k ∈ {0, 1}`),
//! reward `ρ = −x² − u²`, so `τ_N(x) = −x²`. The RBFs have 1 or 2 centres along `x` (at
//! 0 and 1) and 2 along time (at `k = 0` and `k = 1`), intersection ½: neighbouring
//! Gaussians are `h⁴ = 1/16` of their peak at each other's centre, so at a centre the
//! normalised features of a 2-centre axis are `16/17` and `1/17` ([`AT_0`], [`AT_1`]),
//! and `∂φ/∂x` at `x = 0` is `(128 ln 2 / 289) · [−1, 1]` ([`slope_at_0`]). With a
//! single centre along `x` the features do not depend on `x`.
//!
//! The process model is a known linear one, `x' = x + b u` ([`Linear`]), so that its
//! predictions and `∂f̂/∂u = b` are exact from the first step.

use plant::Reward;

use crate::actor_critic::{ActorCritic, Improver, Learning, TaskInfo};
use crate::approx::rbf::{Rbf, RbfParams};
use crate::approx::{Approximator, Differentiable};
use crate::critic::TdLambda;
use crate::explore::Exploration;
use crate::horizon::Horizon;
use crate::model::ProcessModel;

/// Normalised features of a 2-centre axis at its first centre.
pub const AT_0: [f64; 2] = [16.0 / 17.0, 1.0 / 17.0];
/// Normalised features of a 2-centre axis at its second centre.
pub const AT_1: [f64; 2] = [1.0 / 17.0, 16.0 / 17.0];

/// `ψ(k)` of the 2-centre time axis.
pub fn psi(k: usize) -> [f64; 2] {
    [AT_0, AT_1][k]
}

/// `a · b` of two feature vectors.
pub fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// `∂φᵢ/∂x` of the 2-centre state axis at `x = 0`: `−φᵢ (B⁻¹(x − cᵢ) − Σⱼ φⱼ B⁻¹(x − cⱼ))`
/// with `B⁻¹ = 8 ln 2`.
pub fn slope_at_0() -> [f64; 2] {
    let s = 128.0 * std::f64::consts::LN_2 / 289.0;
    [-s, s]
}

/// The tiny task with actions in `[−bound, bound]`.
pub fn info(bound: f64) -> TaskInfo {
    TaskInfo {
        action_low: vec![-bound],
        action_high: vec![bound],
        angle_mask: vec![false],
        reward: Reward {
            q: vec![1.0],
            p: vec![1.0],
            reference: vec![0.0],
            terminal: vec![1.0],
            angle_mask: vec![false],
            terms: Vec::new(),
        },
        horizon: Horizon::Finite { steps: 2 },
    }
}

/// An RBF over `(x, k)` with `centres` along `x` and 2 along time, all parameters 0.
pub fn rbf(centres: usize, bounds: Option<f64>) -> Rbf {
    Rbf::new(&RbfParams {
        centres: vec![centres, 2],
        range: vec![(0.0, 1.0), (0.0, 1.0)],
        periodic: vec![false, false],
        intersection: 0.5,
        outputs: 1,
        initial: 0.0,
        bounds: bounds.map(|b| (vec![-b], vec![b])),
    })
}

/// A critic over `(x, k)` with 2 centres along each; `theta[2 i + j]` weighs state centre
/// `i` and time centre `j`.
pub fn critic(theta: [f64; 4]) -> Rbf {
    let mut v = rbf(2, None);
    v.parameters_mut().copy_from_slice(&theta);
    v
}

/// The known process model `x' = x + b u`: inputs `[x, u]`, output the increment `b u`;
/// it does not learn.
pub struct Linear(pub f64);

/// A known model learns nothing: nothing to save.
impl crate::checkpoint::Persist for Linear {
    fn save(&self, _: &mut crate::checkpoint::Snapshot) {}
    fn restore(
        &mut self,
        _: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        Ok(())
    }
}

impl Approximator for Linear {
    fn input_dim(&self) -> usize {
        2
    }
    fn output_dim(&self) -> usize {
        1
    }
    fn value(&self, xu: &[f64], y: &mut [f64]) {
        y[0] = self.0 * xu[1];
    }
    fn shift(&mut self, _: &[f64], _: &[f64]) {}
    fn fit(&mut self, _: &[f64], _: &[f64], _: f64) {}
}

impl Differentiable for Linear {
    fn value_and_jacobian(&self, xu: &[f64], y: &mut [f64], jac: &mut [f64]) {
        self.value(xu, y);
        jac.copy_from_slice(&[0.0, self.0]);
    }
}

/// The process model `x' = x + b u`.
pub fn model(b: f64) -> ProcessModel {
    ProcessModel::new(Box::new(Linear(b)), vec![false], 0.0)
}

/// The shared step with `improver`, a TD(λ) critic `v` (rate `alpha_c`), `γ = 1`,
/// exploration `σ`.
pub fn agent(
    info: TaskInfo,
    v: Rbf,
    alpha_c: f64,
    lambda: f64,
    improver: Box<dyn Improver>,
    sigma: f64,
) -> ActorCritic {
    ActorCritic::new(
        info,
        Learning { gamma: 1.0, lambda },
        Box::new(TdLambda::new(Box::new(v), alpha_c)),
        improver,
        Exploration::new(sigma, 1, 7),
    )
}

/// `π(x, k)` of `agent` (no exploration, previous action 0).
pub fn greedy(agent: &ActorCritic, x: f64, k: usize) -> f64 {
    use crate::Agent;
    let mut u = [0.0];
    agent.greedy(k, &[x], &[0.0], &mut u);
    u[0]
}

/// Asserts `a ≈ b` to 1e-12.
#[track_caller]
pub fn close(a: f64, b: f64) {
    assert!((a - b).abs() < 1e-12, "{a} ≠ {b}");
}

/// A constant function of one input, `f = c` (a critic `V` or an actor `π`).
pub fn constant(c: f64) -> Rbf {
    let mut f = Rbf::new(&RbfParams {
        centres: vec![1],
        range: vec![(-1.0, 1.0)],
        periodic: vec![false],
        intersection: 0.5,
        outputs: 1,
        initial: 0.0,
        bounds: None,
    });
    f.parameters_mut()[0] = c;
    f
}

/// Asserts that `improver` acts from `x = 0.8` as the discounted LQR of the tiny task
/// (`ρ = −x² − u²`, `x' = x + b u`), `u = −k x` within `tol`: the scalar Riccati equation
/// `γ b² s² + (1 − γ − γ b²) s − 1 = 0` solved in closed form, `k = γ b s / (1 + γ b² s)`.
pub fn acts_as_lqr(improver: &dyn Improver, b: f64, gamma: f64, tol: f64, label: &str) {
    let (qa, qb) = (gamma * b * b, 1.0 - gamma - gamma * b * b);
    let s = (-qb + (qb * qb + 4.0 * qa).sqrt()) / (2.0 * qa);
    let k = gamma * b * s / (1.0 + gamma * b * b * s);
    let mut u = [0.0];
    improver.act(&[0.8], &[0.0], &constant(0.0), &mut u);
    assert!(
        (u[0] + k * 0.8).abs() < tol,
        "{label}: u = {}, −k x = {}",
        u[0],
        -k * 0.8
    );
}
