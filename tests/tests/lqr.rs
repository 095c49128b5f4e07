//! VGBP on a linear system with a quadratic reward reproduces the linear-quadratic
//! regulator (Doya, 2000; repeated in §6.1): with an exact quadratic critic
//! `V(x) = −xᵀSx` (`S` from our own discounted Riccati iteration) and a process model
//! learned by LLR from observed transitions, VGBP's action equals the discrete-time LQR
//! action `−Kx`.
//!
//! Two readings of the action selection are checked on the double integrator
//! (`Ts = 0.05 s`, `Q = diag(1, 0.1)`, `P = 0.1`, `γ = 0.97`):
//! * with the look-ahead (`∂V/∂x` at the predicted next state, Eq. 6.10 without the
//!   Taylor step of Eq. 6.8) the fixed point is the LQR gain — asserted to 1 %;
//! * the thesis's Eq. 6.21 (`∂V/∂x` at the current state) gives `γ P⁻¹ BᵀS`, which
//!   tends to the LQR gain as `Ts → 0` and differs from it by about `γBᵀSB/P` (11 % here)
//!   — asserted to match `γ P⁻¹ BᵀS` to 1 %, which shows the learned model is right.

use std::sync::Arc;

use agent::actor_critic::{Improver, TaskInfo};
use agent::approx::llr::{Eviction, Llr, LlrParams, Search};
use agent::approx::{Approximator, Differentiable};
use agent::model::ProcessModel;
use agent::vgbp::Vgbp;
use plant::{Plant, SystemName, Task};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const GAMMA: f64 = 0.97;

type M2 = [[f64; 2]; 2];

fn mul(a: &M2, b: &M2) -> M2 {
    let mut c = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            c[i][j] = (0..2).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn transpose(a: &M2) -> M2 {
    [[a[0][0], a[1][0]], [a[0][1], a[1][1]]]
}

/// Discounted discrete-time Riccati iteration for reward `−xᵀQx − uᵀPu` (maximised):
/// `S = Q + γAᵀSA − γ² AᵀSB (P + γBᵀSB)⁻¹ BᵀSA`, `K = γ (P + γBᵀSB)⁻¹ BᵀSA`.
fn riccati(a: &M2, b: [f64; 2], q: [f64; 2], p: f64) -> (M2, [f64; 2]) {
    let q_mat = [[q[0], 0.0], [0.0, q[1]]];
    let mut s = q_mat;
    let mut k = [0.0; 2];
    for _ in 0..100_000 {
        let sb = [
            s[0][0] * b[0] + s[0][1] * b[1],
            s[1][0] * b[0] + s[1][1] * b[1],
        ];
        let bsb = b[0] * sb[0] + b[1] * sb[1];
        // BᵀSA as a row vector.
        let bsa = [
            sb[0] * a[0][0] + sb[1] * a[1][0],
            sb[0] * a[0][1] + sb[1] * a[1][1],
        ];
        let denom = p + GAMMA * bsb;
        k = [GAMMA * bsa[0] / denom, GAMMA * bsa[1] / denom];
        let asa = mul(&transpose(a), &mul(&s, a));
        let mut next = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                next[i][j] =
                    q_mat[i][j] + GAMMA * asa[i][j] - GAMMA * GAMMA * bsa[i] * bsa[j] / denom;
            }
        }
        let change = (0..4)
            .map(|e| (next[e / 2][e % 2] - s[e / 2][e % 2]).abs())
            .fold(0.0, f64::max);
        s = next;
        if change < 1e-13 {
            break;
        }
    }
    (s, k)
}

/// The exact critic `V(x) = −xᵀSx`.
struct Quadratic(M2);

/// The exact critic learns nothing: nothing to save.
impl agent::checkpoint::Persist for Quadratic {
    fn save(&self, _: &mut agent::checkpoint::Snapshot) {}
    fn restore(
        &mut self,
        _: &mut agent::checkpoint::Reader,
    ) -> Result<(), agent::checkpoint::CheckpointError> {
        Ok(())
    }
}

impl Approximator for Quadratic {
    fn input_dim(&self) -> usize {
        2
    }
    fn output_dim(&self) -> usize {
        1
    }
    fn value(&self, x: &[f64], y: &mut [f64]) {
        let s = &self.0;
        y[0] = -(0..2)
            .map(|i| (0..2).map(|j| x[i] * s[i][j] * x[j]).sum::<f64>())
            .sum::<f64>();
    }
    fn shift(&mut self, _: &[f64], _: &[f64]) {
        unreachable!("the exact critic does not learn")
    }
    fn fit(&mut self, _: &[f64], _: &[f64], _: f64) {
        unreachable!("the exact critic does not learn")
    }
}

impl Differentiable for Quadratic {
    fn value_and_jacobian(&self, x: &[f64], y: &mut [f64], jac: &mut [f64]) {
        self.value(x, y);
        let s = &self.0;
        for i in 0..2 {
            jac[i] = -(0..2).map(|j| (s[i][j] + s[j][i]) * x[j]).sum::<f64>();
        }
    }
}

/// A process model learned by LLR from 2000 random transitions of the real plant.
fn learned_model(task: &Arc<Task>) -> ProcessModel {
    let llr = Llr::new(&LlrParams {
        memory: 2000,
        neighbours: 30,
        weights: vec![1.0, 1.0, 0.2],
        periodic: vec![false; 3],
        outputs: 2,
        bounds: None,
        eviction: Eviction::Oldest,
        search: Search::KdTree,
        clip_to_neighbours: false,
    });
    let mut model = ProcessModel::new(Box::new(llr), task.angle_mask.clone(), 0.0);
    let mut plant = Plant::new(task.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..2000 {
        let x = [rng.random_range(-1.5..1.5), rng.random_range(-1.5..1.5)];
        let u = [rng.random_range(-5.0..5.0)];
        plant.reset(&x);
        plant.step(&u);
        model.learn(&x, &u, plant.state());
    }
    model
}

#[test]
fn vgbp_with_an_exact_quadratic_critic_is_the_lqr() {
    let task = Arc::new(Task::new(SystemName::DoubleIntegrator));
    let ts = task.ts;
    let a = [[1.0, ts], [0.0, 1.0]];
    let b = [ts * ts / 2.0, ts];
    let (q, p) = ([task.reward.q[0], task.reward.q[1]], task.reward.p[0]);
    let (s, k) = riccati(&a, b, q, p);
    let critic = Quadratic(s);
    let info = TaskInfo::of(&task);
    let lookahead = Vgbp::new(info.clone(), learned_model(&task), GAMMA, 20);
    let first_order = Vgbp::new(info.clone(), learned_model(&task), GAMMA, 0);
    // The search of Eq. 6.6 (model affine in u, V itself) maximises the same quadratic.
    let searched = Vgbp::new(info, learned_model(&task), GAMMA, 0).with_action_grid(61);
    // Eq. 6.21 with the exact B: u = γ P⁻¹ Bᵀ(−Sx)… as a gain, γ P⁻¹ BᵀS.
    let k_thesis = [
        GAMMA / p * (b[0] * s[0][0] + b[1] * s[1][0]),
        GAMMA / p * (b[0] * s[0][1] + b[1] * s[1][1]),
    ];
    let spread = (k_thesis[0] - k[0]).abs() / k[0].abs();
    assert!(spread > 0.05, "the two readings must differ here: {spread}");
    let mut u = [0.0];
    for x in [
        [0.5, 0.0],
        [0.0, 0.5],
        [-0.4, 0.3],
        [0.3, -0.6],
        [-0.2, -0.2],
    ] {
        let lqr = -(k[0] * x[0] + k[1] * x[1]);
        lookahead.act(&x, &[0.0], &critic, &mut u);
        assert!(
            (u[0] - lqr).abs() <= 0.01 * lqr.abs(),
            "x = {x:?}: VGBP {} vs LQR {lqr} (K = {k:?})",
            u[0]
        );
        searched.act(&x, &[0.0], &critic, &mut u);
        assert!(
            (u[0] - lqr).abs() <= 0.01 * lqr.abs(),
            "x = {x:?}: VGBP with search {} vs LQR {lqr}",
            u[0]
        );
        let thesis = -(k_thesis[0] * x[0] + k_thesis[1] * x[1]);
        first_order.act(&x, &[0.0], &critic, &mut u);
        assert!(
            (u[0] - thesis).abs() <= 0.01 * thesis.abs(),
            "x = {x:?}: Eq. 6.21 {} vs γP⁻¹BᵀSx {thesis}",
            u[0]
        );
    }
}
