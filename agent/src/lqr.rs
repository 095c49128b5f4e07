//! Regulating with MLAC's learned process model: a linear-quadratic regulator (LQR) of the
//! model's local fit, recomputed at every sample (certainty equivalence).
//!
//! Where the state error `e = x − x_r` lies in the configured region around the reward's
//! reference, the action is
//!
//! ```text
//! u_k = −K_k z_k,   z_k = [e_k; 1]
//! ```
//!
//! with `K_k` the discounted LQR gain of the affine model the learned `f̂` gives around
//! the reference `(x_r, u = 0)`, its neighbours chosen by the state
//! ([`ProcessModel::local_fit`]),
//!
//! ```text
//! e_{k+1} ≈ (I + ∂Δ̂/∂x) e_k + ∂Δ̂/∂u u_k + c,   c = Δ̂(x_r, 0),
//! ```
//!
//! (or, with `fit_at = "state"`, around `(x_k, π(x_k))`, the offset `c` moved to `e = 0`)
//!
//! and the reward's quadratic approximation at the reference, `ρ ≈ −eᵀQe − uᵀPu`, `Q =
//! −½ ∂²ρ/∂x²` at `x_r` (the quadratic form's `Q`, plus half of each `1 − cos` weight).
//! Which is better depends on where the model's samples are: on the acrobot's balance,
//! all near upright, the fit at `x_k` — whose neighbours, and so the gain, change from
//! sample to sample — left 75 of 200 greedy evaluations (5 seeds × 400 trials) unsettled,
//! the fit at the reference none; on the Furuta pendulum's swing-up, whose samples near
//! upright are few and fast, the fit at the reference caught the pendulum less often
//! (docs/results/furuta.md).
//!
//! The discounted problem is the undiscounted one of `(√γ A, √γ B)`, whose Riccati
//! equation is iterated until the gain settles:
//!
//! ```text
//! S ← Q_z + γ AᵀSA − γ² AᵀSB (P + γ BᵀSB)⁻¹ BᵀSA,   K = γ (P + γ BᵀSB)⁻¹ BᵀSA
//! ```
//!
//! The gain of a fit that is the same, bit for bit, as the last sample's (at the
//! reference, until a sample joins or leaves its neighbours) is not computed again.
//!
//! Outside the region, or where the local model gives no finite gain (its samples do not
//! yet show how the action moves the state), the actor acts, as in MLAC. Learning is
//! MLAC's, unchanged: the regulator only chooses the actions, and it learns nothing of its
//! own — the model it regulates is the one MLAC learns online (Algorithm 2, line 13). An
//! indirect self-tuning regulator (K. J. Åström, B. Wittenmark, *Adaptive Control*, 2nd
//! ed., 1995, ch. 5), with a learner outside the region around the reference: the swing-up
//! by one controller and the catch near upright by a linear one (K. J. Åström, K. Furuta,
//! "Swinging up a pendulum by energy control", Automatica 36, 2000).

use std::sync::Mutex;

use nalgebra::{DMatrix, DVector};

use crate::actor_critic::{Improver, TaskInfo};
use crate::config::{FitAt, LqrConfig};
use crate::critic::ValueWithGradient;
use crate::mlac::{ChoosesActions, Mlac};
use plant::Reward;

/// Riccati iterations at most, per sample.
const MAX_ITERATIONS: usize = 5000;

/// The gain has settled when no entry moves by more than this, relative to its largest.
const TOLERANCE: f64 = 1e-9;

/// MLAC whose actions near the reference come from an LQR of its own process model.
pub struct Lqr {
    mlac: Mlac,
    config: LqrConfig,
    gamma: f64,
    /// `Q` of the reward's quadratic approximation at the reference (diagonal).
    q: Vec<f64>,
    solved: LastSolution,
}

impl Lqr {
    /// Regulates for `mlac` with discount `γ` in `config`'s region.
    pub fn new(mlac: Mlac, config: LqrConfig, gamma: f64) -> Self {
        let q = quadratic_weights(&mlac.info().reward);
        Self {
            mlac,
            config,
            gamma,
            q,
            solved: LastSolution::default(),
        }
    }

    fn info(&self) -> &TaskInfo {
        self.mlac.info()
    }

    /// `e = x − x_r`, angle components wrapped.
    fn error(&self, x: &[f64]) -> Vec<f64> {
        let reward = &self.info().reward;
        (0..self.info().n()).map(|i| reward.error(x, i)).collect()
    }

    /// `(A, B)` of `z_{k+1} = A z_k + B u_k`, `z = [e; 1]`, from the model's fit around
    /// the reference `(x_r, u = 0)`, or around `(x, u_0)` (`fit_at = "state"`).
    fn local_model(&self, x: &[f64], u0: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
        let (n, m) = (self.info().n(), self.info().m());
        match self.config.fit_at {
            FitAt::Reference => {
                affine_model(&self.mlac, &self.info().reward.reference, &vec![0.0; m])
            }
            FitAt::State => affine_model(&self.mlac, &x[..n], u0),
        }
    }

    /// The discounted LQR gain `K` of `(A, B)`; `None` if the Riccati iteration does not
    /// settle — the model cannot hold the state, its cost growing without bound.
    fn gain(&self, a: &DMatrix<f64>, b: &DMatrix<f64>) -> Option<DMatrix<f64>> {
        self.solved
            .riccati(a, b, &self.q, &self.info().reward.p, self.gamma)
            .map(|(k, _)| k)
    }

    /// The regulator's action from `x` (state error `e`), the model fitted around
    /// `(x, u_0)` if it is fitted at the state; `false` if the gain is not finite.
    fn regulate(&self, x: &[f64], e: &[f64], u0: &[f64], u: &mut [f64]) -> bool {
        let (a, b) = self.local_model(x, u0);
        let Some(k) = self.gain(&a, &b) else {
            return false;
        };
        regulator_action(&k, e, u);
        self.info().saturate(u);
        u.iter().all(|v| v.is_finite())
    }
}

/// `u = −K z`, `z = [e; 1]`: the regulator's action for the state error `e`, unsaturated.
pub(crate) fn regulator_action(k: &DMatrix<f64>, e: &[f64], u: &mut [f64]) {
    let n = e.len();
    for (j, v) in u.iter_mut().enumerate() {
        *v = -(0..n).map(|i| k[(j, i)] * e[i]).sum::<f64>() - k[(j, n)];
    }
}

/// `Q = −½ ∂²ρ/∂x²` at the reference, by central differences per component (the terms
/// are sums over components), never negative.
pub(crate) fn quadratic_weights(reward: &Reward) -> Vec<f64> {
    const H: f64 = 1e-3;
    let x_r = &reward.reference;
    let at = |i: usize, d: f64| {
        let mut x = x_r.clone();
        x[i] += d;
        reward.state_reward(&x)
    };
    (0..x_r.len())
        .map(|i| (-(at(i, H) - 2.0 * at(i, 0.0) + at(i, -H)) / (2.0 * H * H)).max(0.0))
        .collect()
}

/// `(A, B)` of `z_{k+1} = A z_k + B u_k`, `z = [e; 1]`, `e = x − x_r`, from `mlac`'s
/// process model fitted around `(x_0, u_0)`: the fit's offset moved to `e = 0`, `u = 0`.
pub(crate) fn affine_model(mlac: &Mlac, x0: &[f64], u0: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, m) = (mlac.info().n(), mlac.info().m());
    let reward = &mlac.info().reward;
    let fit = mlac.model().local_fit(x0, u0);
    let e0: Vec<f64> = (0..n).map(|i| reward.error(x0, i)).collect();
    let jx = DMatrix::from_row_slice(n, n, &fit.dx_dx[..n * n]);
    let ju = DMatrix::from_row_slice(n, m, &fit.dx_du[..n * m]);
    // c = Δ̂ − ∂Δ̂/∂x e_0 − ∂Δ̂/∂u u_0
    let c = DMatrix::from_column_slice(n, 1, &fit.dx[..n])
        - &jx * DMatrix::from_column_slice(n, 1, &e0)
        - &ju * DMatrix::from_column_slice(m, 1, u0);
    let mut a = DMatrix::identity(n + 1, n + 1);
    let mut top = a.view_mut((0, 0), (n, n));
    top += &jx;
    a.view_mut((0, n), (n, 1)).copy_from(&c);
    let mut b = DMatrix::zeros(n + 1, m);
    b.view_mut((0, 0), (n, m)).copy_from(&ju);
    (a, b)
}

/// The discounted LQR of `(A, B)` with the stage cost `eᵀ diag(q) e + uᵀ diag(p) u`: its
/// gain `K` and cost-to-go `S` (`V(z) ≈ −zᵀ S z`); `None` if the Riccati iteration does
/// not settle — the model cannot hold the state, its cost growing without bound.
pub(crate) fn riccati(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &[f64],
    p: &[f64],
    g: f64,
) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
    let n = q.len();
    let mut qz = DMatrix::zeros(n + 1, n + 1);
    for (i, q) in q.iter().enumerate() {
        qz[(i, i)] = *q;
    }
    let p = DMatrix::from_diagonal(&DVector::from_column_slice(p));
    let mut s = qz.clone();
    let mut last_k: Option<DMatrix<f64>> = None;
    for _ in 0..MAX_ITERATIONS {
        let bts = b.transpose() * &s;
        let k = (&p + g * &bts * b).try_inverse()? * (g * &bts * a);
        let closed = a - b * &k;
        let next = &qz + g * closed.transpose() * &s * &closed + k.transpose() * &p * &k;
        // The state block settles at the closed loop's rate; the constant's own
        // entry, which no action moves, only at γ's, and does not enter K.
        let state_block = |m: &DMatrix<f64>| m.view((0, 0), (n, n)).clone_owned();
        let (s_now, s_next) = (state_block(&s), state_block(&next));
        let bounded = next.iter().all(|v| v.is_finite() && v.abs() < 1e15);
        if !bounded || !k.iter().all(|v| v.is_finite()) {
            return None;
        }
        let settled = |d: f64, scale: f64| d <= TOLERANCE * scale.max(1.0);
        let k_settled = last_k
            .as_ref()
            .is_some_and(|prev| settled((&k - prev).amax(), k.amax()));
        s = next;
        if k_settled && settled((&s_next - &s_now).amax(), s_next.amax()) {
            return Some((k, s));
        }
        last_k = Some(k);
    }
    None
}

/// [`riccati`]'s solution for one owner's `(q, p, γ)`, remembered with its `(A, B)`: the
/// model's fit at a fixed point (the reference) is the same, bit for bit, from one sample
/// to the next until a sample joins or leaves its neighbours, and so is the solution — the
/// iteration is not repeated.
#[derive(Default)]
pub(crate) struct LastSolution(Mutex<Option<Solution>>);

type Solved = Option<(DMatrix<f64>, DMatrix<f64>)>;

struct Solution {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    solved: Solved,
}

/// Whether two matrices are the same bits.
fn same_bits(x: &DMatrix<f64>, y: &DMatrix<f64>) -> bool {
    x.shape() == y.shape()
        && x.iter()
            .zip(y.iter())
            .all(|(a, b)| a.to_bits() == b.to_bits())
}

impl LastSolution {
    /// [`riccati`] of `(A, B)`; the owner passes the same `q`, `p` and `γ` every time.
    pub(crate) fn riccati(
        &self,
        a: &DMatrix<f64>,
        b: &DMatrix<f64>,
        q: &[f64],
        p: &[f64],
        g: f64,
    ) -> Solved {
        let mut last = self.0.lock().expect("the solution's lock");
        if let Some(l) = last
            .as_ref()
            .filter(|l| same_bits(&l.a, a) && same_bits(&l.b, b))
        {
            return l.solved.clone();
        }
        let solved = riccati(a, b, q, p, g);
        *last = Some(Solution {
            a: a.clone(),
            b: b.clone(),
            solved: solved.clone(),
        });
        solved
    }
}

impl ChoosesActions for Lqr {
    fn mlac(&self) -> &Mlac {
        &self.mlac
    }

    fn mlac_mut(&mut self) -> &mut Mlac {
        &mut self.mlac
    }

    /// The regulator's action in the region, the actor's elsewhere (or where the gain is
    /// not finite); the actor is asked only where its action is needed.
    fn choose(&self, x: &[f64], u_prev: &[f64], critic: &ValueWithGradient, u: &mut [f64]) {
        let e = self.error(x);
        if self.config.contains(&e) {
            let u0 = match self.config.fit_at {
                FitAt::Reference => vec![0.0; u.len()],
                FitAt::State => {
                    self.mlac.act(x, u_prev, critic, u);
                    u.to_vec()
                }
            };
            if self.regulate(x, &e, &u0, u) {
                return;
            }
        }
        self.mlac.act(x, u_prev, critic, u);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::horizon::Horizon;
    use crate::testing::{self, constant};

    /// On the tiny task (`ρ = −x² − u²`, the model `x' = x + b u`), actor `π = 0.1`.
    fn regulator(b: f64, gamma: f64, region: Option<Vec<f64>>) -> Lqr {
        let info = TaskInfo {
            horizon: Horizon::Infinite,
            ..testing::info(5.0)
        };
        let mlac = Mlac::new(
            info,
            Box::new(constant(0.1)),
            testing::model(b),
            0.1,
            gamma,
            0.0,
        );
        Lqr::new(
            mlac,
            LqrConfig {
                region,
                ..LqrConfig::default()
            },
            gamma,
        )
    }

    /// The scalar discounted Riccati equation `s = 1 + γ s − γ² b² s² / (1 + γ b² s)`,
    /// solved in closed form, gives `k = γ b s / (1 + γ b² s)`: the regulator's action
    /// is `−k x`, whatever the actor says, with the model (linear: the same everywhere)
    /// fitted at the reference or at the state.
    #[test]
    fn the_action_is_the_discounted_lqr_gains() {
        for fit_at in [FitAt::Reference, FitAt::State] {
            let mut lqr = regulator(0.5, 0.9, None);
            lqr.config.fit_at = fit_at;
            testing::acts_as_lqr(&lqr, 0.5, 0.9, 1e-7, &format!("{fit_at:?}"));
        }
    }

    /// Outside its region the actor acts; inside it the regulator.
    #[test]
    fn outside_the_region_the_actor_acts() {
        let lqr = regulator(0.5, 0.9, Some(vec![0.5]));
        let mut u = [0.0];
        lqr.act(&[0.8], &[0.0], &constant(0.0), &mut u);
        assert_eq!(u[0], 0.1);
        lqr.act(&[0.4], &[0.0], &constant(0.0), &mut u);
        assert!(u[0] < 0.0, "u = {}", u[0]);
    }

    /// A model in which the action moves nothing while the state grows (`x' = 1.2 x`,
    /// beyond `1/√γ`) cannot be held: no gain. With the state still (`x' = x`, the
    /// tiny task's model with `b = 0`) the cost stays finite and the gain is zero.
    #[test]
    fn a_state_no_action_can_hold_has_no_gain() {
        let lqr = regulator(0.0, 0.9, None);
        let mut a = DMatrix::identity(2, 2);
        a[(0, 0)] = 1.2;
        assert!(lqr.gain(&a, &DMatrix::zeros(2, 1)).is_none());
        let mut u = [0.0];
        lqr.act(&[0.8], &[0.0], &constant(0.0), &mut u);
        assert!(
            u[0].abs() < 1e-12,
            "a still state and a deaf action: u = {}",
            u[0]
        );
    }

    /// `Q` is the quadratic form's plus half of each `1 − cos` weight.
    #[test]
    fn the_weights_are_the_rewards_curvature_at_the_reference() {
        let mut reward = testing::info(1.0).reward;
        reward.reference = vec![0.3];
        reward.terms = vec![plant::reward::Term::Cosine {
            weights: vec![0.8],
            reference: vec![0.3],
        }];
        let q = quadratic_weights(&reward);
        assert!((q[0] - 1.4).abs() < 1e-6, "Q = {}", q[0]);
    }
}
