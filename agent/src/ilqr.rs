//! Planning with MLAC's learned process model by the iterative LQR (iLQR): model-predictive
//! control whose action sequence is improved by Newton-like steps along the model's local
//! fits.
//!
//! At every sample the action applied is the first of the sequence `u_0 … u_{H−1}` that
//! lowers the predicted cost
//!
//! ```text
//! J = Σ_{i<H} γ^i ℓ(x̃_i, u_i) + γ^H (z̃_Hᵀ S z̃_H + ℓ_b(x̃_H)),   ℓ = −ρ + ℓ_b,
//! x̃_0 = x_k,   x̃_{i+1} = f̂(x̃_i, u_i)
//! ```
//!
//! with `ℓ_b` the operating range's [`Barrier`] (zero for a task without one),
//! `f̂` the process model MLAC learns online (Algorithm 2, line 13), `z = [e; 1]` and
//! `S` the cost-to-go of the discounted LQR of the model's fit at the reference
//! ([`crate::lqr`]) — the stage cost's quadratic form `eᵀ diag(q) e` while that LQR has no
//! finite solution. The iterative LQR (W. Li, E. Todorov, "Iterative linear quadratic
//! regulator design for nonlinear biological movement systems", ICINCO 2004) with a
//! learned locally weighted model (D. Mitrovic, S. Klanke, S. Vijayakumar, "Adaptive
//! optimal feedback control with learned internal dynamics models", 2010), run in a
//! receding horizon from the last sample's plan (Y. Tassa, T. Erez, E. Todorov,
//! "Synthesis and stabilization of complex behaviors through online trajectory
//! optimization", IROS 2012), the LQR's cost as the terminal cost (D. Q. Mayne et al.,
//! "Constrained model predictive control: stability and optimality", Automatica 36, 2000):
//!
//! 1. the sequence starts as the best (lowest `J`) of the last sample's plan, shifted by
//!    one sample, its last action repeated, the actor's rollout through the model, and,
//!    with `start_from_regulator`, the regulator's: the LQR of `S`, `u_i = −K z̃_i`, in
//!    closed loop through the model (at a trial's first sample there is no last plan);
//! 2. backward pass, along the rollout `x̄_i, ū_i` with the model's fit there,
//!    `δx_{i+1} = A_i δx_i + B_i δu_i` (`A = I + ∂Δ̂/∂x`, `B = ∂Δ̂/∂u`), `ℓ`'s gradient
//!    and the reward's curvature at the reference plus the barrier's at `x̄_i`
//!    (`ℓ_xx = 2 diag(q) + ∂²ℓ_b/∂x²`, `ℓ_uu = 2 diag(p)`):
//!
//!    ```text
//!    Q_x  = ℓ_x + γ Aᵀ V_x'          Q_u  = ℓ_u + γ Bᵀ V_x'
//!    Q_xx = ℓ_xx + γ Aᵀ V_xx' A      Q_uu = ℓ_uu + γ Bᵀ V_xx' B + μ I      Q_ux = γ Bᵀ V_xx' A
//!    k = −Q_uu⁻¹ Q_u,   K = −Q_uu⁻¹ Q_ux   (both zero for an action at its bound that k pushes beyond)
//!    V_x  = Q_x + Kᵀ Q_uu k + Kᵀ Q_u + Q_uxᵀ k
//!    V_xx = Q_xx + Kᵀ Q_uu K + Kᵀ Q_ux + Q_uxᵀ K
//!    ```
//!
//!    `μ` growing tenfold from 10⁻⁶ until every `Q_uu` is positive definite;
//! 3. forward pass, `u_i = sat(ū_i + α k_i + K_i (x̃_i ⊖ x̄_i))` through the model, `α`
//!    halved from 1 until `J` decreases; if it does not within five halvings, the search
//!    ends.
//!
//! Learning is MLAC's, unchanged: the critic, the actor and the model learn from the
//! transitions the planned actions (with exploration) produce. The plan is carried from
//! one sample to the next within a trial, learning or greedy, and dropped when the next
//! begins: every trial starts from the actor's rollout, so a run resumed at a trial
//! repeats an uninterrupted one.
//!
//! # Speed
//!
//! A sample's work is mostly the model's local fits, one per planned sample of every
//! rollout tried (about 150 per sample with the acrobot's 20 samples and 3 iterations).
//! Their neighbours by the state are found through the model memory's index of the
//! states, or recalled from a search along the last rollout that proves them the same
//! ([`ProcessModel::local_fit`](crate::model::ProcessModel::local_fit)); the terminal
//! cost's LQR is solved again only when the model's fit at the reference has changed.
//! On the acrobot's swing-up (`examples/acrobot/mlac-ilqr.toml`) the agent's step takes
//! 0.33–0.36 ms of CPU at the median and 0.88–0.94 ms at the 99th percentile (three
//! seeds of `agent/benches/planning_step.rs`), where a scan of the memory per fit took
//! 4.3–4.8 ms and 12.4–14.1 ms: `docs/results/planning-speed.md`.

use std::sync::Mutex;

use nalgebra::{DMatrix, DVector};

use crate::actor_critic::{Improver, TaskInfo};
use crate::barrier::Barrier;
use crate::config::PlanningConfig;
use crate::critic::ValueWithGradient;
use crate::lqr::{LastSolution, affine_model, quadratic_weights, regulator_action};
use crate::mlac::{ChoosesActions, Mlac};
use plant::OperatingRange;
use plant::angle::wrap;

/// The halvings of the forward pass's step `α` before an iteration gives up.
const LINE_SEARCH: usize = 5;

/// The regularisations `μ` tried, smallest first, until every `Q_uu` is positive definite.
const REGULARISATION: [f64; 6] = [1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1];

/// MLAC whose actions are planned by the iterative LQR with its own process model.
pub struct Ilqr {
    mlac: Mlac,
    config: PlanningConfig,
    gamma: f64,
    /// `q` of the reward's quadratic approximation at the reference.
    q: Vec<f64>,
    /// The last sample's plan, `H × m` row-major (empty before the first).
    last: Mutex<Vec<f64>>,
    /// The terminal cost's LQR, solved again only when the model's fit changes.
    solved: LastSolution,
    /// The operating range's cost `ℓ_b`.
    barrier: Barrier,
}

/// A sequence's rollout through the model: the states `x̃_0 … x̃_H`, the actions, the
/// model's fit `(A_i, B_i)` at each step and the cost `J` (`+∞` if not finite).
struct Rollout {
    xs: Vec<Vec<f64>>,
    us: Vec<f64>,
    fits: Vec<(DMatrix<f64>, DMatrix<f64>)>,
    cost: f64,
}

/// The cost-to-go's quadratic expansion at one sample of the plan: `V_x` and `V_xx`.
struct Value {
    x: DVector<f64>,
    xx: DMatrix<f64>,
}

/// The feedback of a backward pass: `k_i` and `K_i` of every step.
struct Feedback {
    k: Vec<DVector<f64>>,
    gain: Vec<DMatrix<f64>>,
}

impl Ilqr {
    /// Plans for `mlac` with discount `γ`; `config.method` is the iterative LQR's.
    pub fn new(mlac: Mlac, config: PlanningConfig, gamma: f64) -> Self {
        let q = quadratic_weights(&mlac.info().reward);
        Self {
            mlac,
            config,
            gamma,
            q,
            last: Mutex::new(Vec::new()),
            solved: LastSolution::default(),
            barrier: Barrier::default(),
        }
    }

    /// Plans within the task's operating range `range`, if it has one: its [`Barrier`]
    /// joins the stage and terminal costs.
    pub fn within(mut self, range: Option<&OperatingRange>) -> Self {
        self.barrier = Barrier::of(range, &self.info().reward.reference, self.gamma);
        self
    }

    fn info(&self) -> &TaskInfo {
        self.mlac.info()
    }

    fn horizon(&self) -> usize {
        self.config.horizon as usize
    }

    /// `e = x − x_r`, angle components wrapped.
    fn error(&self, x: &[f64]) -> Vec<f64> {
        let reward = &self.info().reward;
        (0..self.info().n()).map(|i| reward.error(x, i)).collect()
    }

    /// `a ⊖ b`: the difference of two states, angle components wrapped.
    fn difference(&self, a: &[f64], b: &[f64]) -> DVector<f64> {
        let mask = &self.info().angle_mask;
        DVector::from_iterator(
            a.len(),
            (0..a.len()).map(|i| {
                if mask[i] {
                    wrap(a[i] - b[i])
                } else {
                    a[i] - b[i]
                }
            }),
        )
    }

    /// `S` of the terminal cost `zᵀ S z` and the gain `K` of the LQR of the model's fit at
    /// the reference, or the stage cost's quadratic form and no gain where that LQR has no
    /// finite solution.
    fn terminal(&self) -> (DMatrix<f64>, Option<DMatrix<f64>>) {
        let m = self.info().m();
        let (a, b) = affine_model(&self.mlac, &self.info().reward.reference, &vec![0.0; m]);
        let reward = &self.info().reward;
        match self.solved.riccati(&a, &b, &self.q, &reward.p, self.gamma) {
            Some((k, s)) => (s, Some(k)),
            None => {
                let n = self.q.len();
                let mut s = DMatrix::zeros(n + 1, n + 1);
                for (i, q) in self.q.iter().enumerate() {
                    s[(i, i)] = *q;
                }
                (s, None)
            }
        }
    }

    /// `x̃_{i+1} = f̂(x̃_i, u_i)` and the model's fit `(A, B)` there.
    fn step(&self, x: &[f64], u: &[f64]) -> (Vec<f64>, (DMatrix<f64>, DMatrix<f64>)) {
        let (n, m) = (self.info().n(), self.info().m());
        let fit = self.mlac.model().local_fit(x, u);
        let mask = &self.info().angle_mask;
        let next = (0..n)
            .map(|i| {
                let v = x[i] + fit.dx[i];
                if mask[i] { wrap(v) } else { v }
            })
            .collect();
        let a = DMatrix::identity(n, n) + DMatrix::from_row_slice(n, n, &fit.dx_dx[..n * n]);
        let b = DMatrix::from_row_slice(n, m, &fit.dx_du[..n * m]);
        (next, (a, b))
    }

    /// The rollout from `x` of the actions `policy(i, x̃_i)` chooses, saturated.
    fn rollout(
        &self,
        x: &[f64],
        s: &DMatrix<f64>,
        mut policy: impl FnMut(usize, &[f64], &mut [f64]),
    ) -> Rollout {
        let (n, m, h) = (self.info().n(), self.info().m(), self.horizon());
        let mut r = Rollout {
            xs: vec![x[..n].to_vec()],
            us: vec![0.0; h * m],
            fits: Vec::with_capacity(h),
            cost: 0.0,
        };
        let mut discount = 1.0;
        for i in 0..h {
            let u = &mut r.us[i * m..(i + 1) * m];
            policy(i, &r.xs[i], u);
            self.info().saturate(u);
            r.cost +=
                discount * (self.barrier.cost(&r.xs[i]) - self.info().reward.reward(&r.xs[i], u));
            discount *= self.gamma;
            let (next, fit) = self.step(&r.xs[i], u);
            r.xs.push(next);
            r.fits.push(fit);
        }
        let mut z = self.error(&r.xs[h]);
        z.push(1.0);
        let z = DVector::from_vec(z);
        r.cost += discount * ((z.transpose() * s * &z)[(0, 0)] + self.barrier.cost(&r.xs[h]));
        if !r.cost.is_finite() {
            r.cost = f64::INFINITY;
        }
        r
    }

    /// Step 1: the best of the actor's rollout, the last plan, shifted, and — with
    /// `start_from_regulator` and a finite gain `K` — the regulator's rollout,
    /// `u_i = −K z̃_i`; a tie goes to the last plan, and never to the regulator's.
    fn initial(&self, x: &[f64], s: &DMatrix<f64>, gain: Option<&DMatrix<f64>>) -> Rollout {
        let (m, h) = (self.info().m(), self.horizon());
        let mut best = self.rollout(x, s, |_, xi, u| self.mlac.actor().value(xi, u));
        let last = self.last.lock().expect("the plan's lock").clone();
        if last.len() == h * m {
            let shifted = self.rollout(x, s, |i, _, u| {
                let j = (i + 1).min(h - 1);
                u.copy_from_slice(&last[j * m..(j + 1) * m]);
            });
            if shifted.cost <= best.cost {
                best = shifted;
            }
        }
        if let Some(k) = gain.filter(|_| self.config.start_from_regulator) {
            let regulated = self.rollout(x, s, |_, xi, u| regulator_action(k, &self.error(xi), u));
            if regulated.cost < best.cost {
                best = regulated;
            }
        }
        best
    }

    /// Step 2 with regularisation `μ`; `None` if some `Q_uu` is not positive definite.
    fn backward(&self, r: &Rollout, s: &DMatrix<f64>, mu: f64) -> Option<Feedback> {
        let (n, m, h) = (self.info().n(), self.info().m(), self.horizon());
        let diagonal = |v: &[f64], add: f64| {
            DMatrix::from_diagonal(&DVector::from_iterator(
                v.len(),
                v.iter().map(|w| 2.0 * w + add),
            ))
        };
        let (lxx, luu) = (diagonal(&self.q, 0.0), diagonal(&self.info().reward.p, mu));
        // V at the plan's end: the terminal cost z̃_Hᵀ S z̃_H
        let mut z = self.error(&r.xs[h]);
        z.push(1.0);
        let sz = s * DVector::from_vec(z);
        let mut v = Value {
            x: 2.0 * sz.rows(0, n).clone_owned(),
            xx: 2.0 * s.view((0, 0), (n, n)).clone_owned(),
        };
        let (mut bx, mut bxx) = (vec![0.0; n], vec![0.0; n]);
        self.barrier.add_derivatives(&r.xs[h], &mut bx, &mut bxx);
        v.x += DVector::from_vec(bx);
        v.xx += DMatrix::from_diagonal(&DVector::from_vec(bxx));
        let mut fb = Feedback {
            k: vec![DVector::zeros(m); h],
            gain: vec![DMatrix::zeros(m, n); h],
        };
        for i in (0..h).rev() {
            (fb.k[i], fb.gain[i], v) = self.step_back(r, i, &v, &lxx, &luu)?;
        }
        Some(fb)
    }

    /// One step of the backward pass at sample `i`: `k_i`, `K_i` and `V` there, from `V`
    /// at sample `i + 1`.
    fn step_back(
        &self,
        r: &Rollout,
        i: usize,
        next: &Value,
        lxx: &DMatrix<f64>,
        luu: &DMatrix<f64>,
    ) -> Option<(DVector<f64>, DMatrix<f64>, Value)> {
        let (n, m, g) = (self.info().n(), self.info().m(), self.gamma);
        let reward = &self.info().reward;
        let (a, b) = &r.fits[i];
        let (x, u) = (&r.xs[i], &r.us[i * m..(i + 1) * m]);
        let (mut lx, mut lu) = (vec![0.0; n], vec![0.0; m]);
        reward.grad_x(x, &mut lx);
        reward.grad_u(u, &mut lu);
        let (mut bx, mut bxx) = (vec![0.0; n], vec![0.0; n]);
        self.barrier.add_derivatives(x, &mut bx, &mut bxx);
        // ℓ = −ρ + ℓ_b: its gradients are −∂ρ/∂x + ∂ℓ_b/∂x, −∂ρ/∂u
        let qx = DVector::from_vec(bx) - DVector::from_vec(lx) + g * a.transpose() * &next.x;
        let qu = -DVector::from_vec(lu) + g * b.transpose() * &next.x;
        let qxx = lxx
            + DMatrix::from_diagonal(&DVector::from_vec(bxx))
            + g * a.transpose() * &next.xx * a;
        let quu = luu + g * b.transpose() * &next.xx * b;
        let qux = g * b.transpose() * &next.xx * a;
        let chol = quu.clone().cholesky()?;
        let mut k = -chol.solve(&qu);
        let mut gain = -chol.solve(&qux);
        self.hold_at_bounds(u, &mut k, &mut gain);
        let vx = &qx + gain.transpose() * &quu * &k + gain.transpose() * &qu + qux.transpose() * &k;
        let vxx = &qxx
            + gain.transpose() * &quu * &gain
            + gain.transpose() * &qux
            + qux.transpose() * &gain;
        let value = Value {
            x: vx,
            xx: 0.5 * (&vxx + vxx.transpose()),
        };
        Some((k, gain, value))
    }

    /// `k_j` and row `j` of `K` zero for an action at its bound that `k` pushes beyond.
    fn hold_at_bounds(&self, u: &[f64], k: &mut DVector<f64>, gain: &mut DMatrix<f64>) {
        for j in 0..u.len() {
            let (lo, hi) = (self.info().action_low[j], self.info().action_high[j]);
            if (u[j] >= hi && k[j] > 0.0) || (u[j] <= lo && k[j] < 0.0) {
                k[j] = 0.0;
                gain.row_mut(j).fill(0.0);
            }
        }
    }

    /// Step 3: the first step `α` whose rollout lowers `J`, if any.
    fn forward(&self, x: &[f64], r: &Rollout, fb: &Feedback, s: &DMatrix<f64>) -> Option<Rollout> {
        let m = self.info().m();
        let mut alpha = 1.0;
        for _ in 0..=LINE_SEARCH {
            let next = self.rollout(x, s, |i, xi, u| {
                let du = &fb.gain[i] * self.difference(xi, &r.xs[i]);
                for j in 0..m {
                    u[j] = r.us[i * m + j] + alpha * fb.k[i][j] + du[j];
                }
            });
            if next.cost < r.cost {
                return Some(next);
            }
            alpha *= 0.5;
        }
        None
    }

    /// The plan from `x`: the initial sequence improved by the configured iterations.
    fn plan(&self, x: &[f64]) -> Rollout {
        let (s, gain) = self.terminal();
        let mut r = self.initial(x, &s, gain.as_ref());
        for _ in 0..self.config.iterations {
            let Some(fb) = REGULARISATION
                .iter()
                .find_map(|&mu| self.backward(&r, &s, mu))
            else {
                break;
            };
            match self.forward(x, &r, &fb, &s) {
                Some(next) => r = next,
                None => break,
            }
        }
        r
    }
}

impl ChoosesActions for Ilqr {
    fn mlac(&self) -> &Mlac {
        &self.mlac
    }

    fn mlac_mut(&mut self) -> &mut Mlac {
        &mut self.mlac
    }

    /// The first action of the plan; the actor's where the model predicts no finite cost.
    fn choose(&self, x: &[f64], u_prev: &[f64], critic: &ValueWithGradient, u: &mut [f64]) {
        let r = self.plan(x);
        if !r.cost.is_finite() {
            self.last.lock().expect("the plan's lock").clear();
            self.mlac.act(x, u_prev, critic, u);
            return;
        }
        u.copy_from_slice(&r.us[..u.len()]);
        *self.last.lock().expect("the plan's lock") = r.us;
    }

    /// Each trial's first plan starts from the actor's rollout.
    fn start_any_trial(&mut self) {
        self.last.get_mut().expect("the plan's lock").clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actor_critic::Transition;
    use crate::approx::llr::{Eviction, Llr, LlrParams, Search};
    use crate::config::PlanningMethod;
    use crate::horizon::Horizon;
    use crate::model::ProcessModel;
    use crate::testing::{self, constant};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// On the tiny task (`ρ = −x² − u²`, the model `x' = x + b u`), actor `π = 0.1`.
    fn planner(b: f64, gamma: f64, horizon: u32) -> Ilqr {
        planning_with(testing::model(b), gamma, horizon)
    }

    /// On the tiny task with `model`, actor `π = 0.1`.
    fn planning_with(model: ProcessModel, gamma: f64, horizon: u32) -> Ilqr {
        let info = TaskInfo {
            horizon: Horizon::Infinite,
            ..testing::info(5.0)
        };
        let mlac = Mlac::new(info, Box::new(constant(0.1)), model, 0.1, gamma, 0.0);
        let config = PlanningConfig {
            method: PlanningMethod::Ilqr,
            horizon,
            samples: None,
            elites: None,
            iterations: 3,
            start_from_regulator: false,
        };
        Ilqr::new(mlac, config, gamma)
    }

    /// With a linear model the terminal cost is the exact cost-to-go, so the plan's first
    /// action is the infinite-horizon LQR's, `−k x`, over one sample or ten.
    #[test]
    fn on_a_linear_model_the_plan_is_the_lqr() {
        for horizon in [1, 10] {
            let p = planner(0.5, 0.9, horizon);
            testing::acts_as_lqr(&p, 0.5, 0.9, 1e-6, &format!("H = {horizon}"));
        }
    }

    /// With `start_from_regulator` the search starts from the regulator's rollout where the
    /// actor's (`π = 0.1`) costs more: on a linear model that rollout's cost is the
    /// terminal cost at the start, `z₀ᵀ S z₀`, and its first action the LQR's, `−K z₀`.
    #[test]
    fn the_regulator_s_rollout_is_a_start() {
        let mut p = planner(0.5, 0.9, 10);
        let (s, gain) = p.terminal();
        let actor = p.initial(&[0.8], &s, gain.as_ref());
        p.config.start_from_regulator = true;
        let regulated = p.initial(&[0.8], &s, gain.as_ref());
        let k = gain.expect("the linear model's LQR");
        let z = DVector::from_vec(vec![0.8, 1.0]);
        let cost_to_go = (z.transpose() * &s * &z)[(0, 0)];
        assert!(
            regulated.cost < actor.cost - 0.01,
            "{} {}",
            regulated.cost,
            actor.cost
        );
        assert!((regulated.cost - cost_to_go).abs() < 1e-9 * cost_to_go);
        assert!((regulated.us[0] + k[(0, 0)] * 0.8 + k[(0, 1)]).abs() < 1e-12);
        assert_eq!(actor.us[0], 0.1);
    }

    /// `x' = x + 0.3 sin 2x + 0.4 u`, the tiny task's state kept within ±2.
    fn nonlinear(x: f64, u: f64) -> f64 {
        (x + 0.3 * (2.0 * x).sin() + 0.4 * u).clamp(-2.0, 2.0)
    }

    /// An LLR model of [`nonlinear`] from 300 random transitions, its neighbours found by
    /// `search`.
    fn learned(search: Search) -> ProcessModel {
        let llr = Llr::new(&LlrParams {
            memory: 300,
            neighbours: 6,
            weights: vec![1.0, 0.2],
            periodic: vec![false, false],
            outputs: 1,
            bounds: None,
            eviction: Eviction::Redundant(0.01),
            search,
            clip_to_neighbours: false,
        });
        let mut model = ProcessModel::new(Box::new(llr), vec![false], 0.0);
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for _ in 0..400 {
            let (x, u) = (rng.random_range(-2.0..2.0), rng.random_range(-5.0..5.0));
            model.learn(&[x], &[u], &[nonlinear(x, u)]);
        }
        model
    }

    /// With an LLR model, a plan through the model's index of the states (neighbours
    /// recalled along the plan, or searched) is the plan through a scan that ranks them
    /// the same way, bit for bit, sample after sample as the model learns.
    #[test]
    fn plans_through_the_index_are_the_scans() {
        let run = |search| {
            let mut p = planning_with(learned(search), 0.95, 10);
            let (mut x, mut actions) = (1.8, Vec::new());
            for _ in 0..40 {
                let mut u = [0.0];
                p.act(&[x], &[0.0], &constant(0.0), &mut u);
                actions.push(u[0].to_bits());
                let x_next = nonlinear(x, u[0]);
                let t = Transition {
                    x: &[x],
                    u: &u,
                    u_policy: &u,
                    du: &[0.0],
                    r: -x * x - u[0] * u[0],
                    x_next: &[x_next],
                    td: 0.0,
                };
                p.improve(&t, &constant(0.0));
                x = x_next;
            }
            (actions, p.mlac().model().fill())
        };
        let (indexed, scanned) = (run(Search::KdTree), run(Search::Scan));
        assert_eq!(indexed, scanned);
        assert!(indexed.0.iter().any(|&u| f64::from_bits(u).abs() > 0.5));
    }

    /// Near the operating range's edge the plan steers back harder than without the
    /// range (the barrier is part of its cost); well inside, where the plan stays within
    /// the barrier's inner bound, it is the same plan, bit for bit.
    #[test]
    fn the_operating_range_pushes_the_plan_back_from_its_edge() {
        let range = OperatingRange {
            limits: vec![(-1.0, 1.0)],
            penalty: -1e4,
        };
        let first = |p: Ilqr, x: f64| {
            let mut u = [0.0];
            p.act(&[x], &[0.0], &constant(0.0), &mut u);
            u[0]
        };
        // A weak actuator (x' = x + 0.1 u): the plan stays beyond the inner bound, 0.75,
        // for a few samples.
        let free = first(planner(0.1, 0.9, 10), 0.95);
        let kept = first(planner(0.1, 0.9, 10).within(Some(&range)), 0.95);
        assert!(kept < free - 0.1, "with the range {kept}, without {free}");
        let free = first(planner(0.1, 0.9, 10), 0.2);
        let kept = first(planner(0.1, 0.9, 10).within(Some(&range)), 0.2);
        assert_eq!(kept.to_bits(), free.to_bits());
    }

    /// The plan is carried to the next sample and dropped when a trial, learning or
    /// greedy, begins.
    #[test]
    fn the_carried_plan_is_dropped_at_each_trial() {
        let mut p = planner(0.5, 0.9, 4);
        let mut u = [0.0];
        p.act(&[0.8], &[0.0], &constant(0.0), &mut u);
        assert_eq!(p.last.lock().unwrap().len(), 4);
        p.start_greedy_trial();
        assert!(p.last.lock().unwrap().is_empty());
        p.act(&[0.8], &[0.0], &constant(0.0), &mut u);
        p.start_trial();
        assert!(p.last.lock().unwrap().is_empty());
    }
}
