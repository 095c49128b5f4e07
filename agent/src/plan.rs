//! Planning with MLAC's learned process model: model-predictive control by the
//! cross-entropy method, over a short horizon, with the critic as the terminal value.
//!
//! At every sample the action applied is the first of the action sequence
//! `u_0 … u_{H−1}` that scores best under
//!
//! ```text
//! G(u_0 … u_{H−1}) = Σ_{i<H} γ^i ρ(x̃_i, u_i) + γ^H V(x̃_H),   x̃_0 = x_k,  x̃_{i+1} = f̂(x̃_i, u_i)
//! ```
//!
//! with `f̂` the process model MLAC learns online (Algorithm 2, line 13), `ρ` the known
//! reward and `V` the critic: model-predictive control with a learned model (A. Nagabandi,
//! G. Kahn, R. S. Fearing, S. Levine, "Neural Network Dynamics for Model-Based Deep
//! Reinforcement Learning with Model-Free Fine-Tuning", ICRA 2018) and a learned value
//! as its terminal cost (K. Lowrey, A. Rajeswaran, S. Kakade, E. Todorov, I. Mordatch,
//! "Plan Online, Learn Offline", ICLR 2019). The sequences are searched by the
//! cross-entropy method (R. Y. Rubinstein, D. P. Kroese, *The Cross-Entropy Method*,
//! 2004; for control with a learned model, K. Chua et al., "Deep Reinforcement Learning
//! in a Handful of Trials using Probabilistic Dynamics Models", NeurIPS 2018):
//!
//! 1. the mean sequence starts as the actor's rollout through the model,
//!    `μ_i = π(x̃_i)`, the spread as a quarter of each action's range;
//! 2. each iteration draws `samples` sequences `sat(μ + σ ∘ ε)`, `ε ~ N(0, I)` (the mean
//!    itself among them), scores each by `G`, and moves `μ` and `σ` to the mean and the
//!    standard deviation of the best `elites`;
//! 3. the action is the first of the best sequence scored in any iteration.
//!
//! Learning is MLAC's, unchanged: the critic learns by TD(λ) from the transitions the
//! planned actions (with exploration) produce, the actor climbs Eq. 3.9 and the model
//! learns every transition. The planner only chooses the actions. Its random draws are
//! keyed by the run seed and the state's bits, so a run repeats exactly and a greedy
//! evaluation takes no numbers from a learning trial's stream.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::actor_critic::TaskInfo;
use crate::approx::{Differentiable, scalar};
use crate::config::PlanningConfig;
use crate::critic::ValueWithGradient;
use crate::mlac::{ChoosesActions, Mlac};
use crate::model::ProcessModel;

/// The random stream of the planner's draws ([`crate::explore::stream::PLANNING`]).
pub const STREAM: u64 = crate::explore::stream::PLANNING;

/// MLAC whose actions are planned with its own process model and critic.
pub struct Planner {
    mlac: Mlac,
    config: PlanningConfig,
    gamma: f64,
    seed: u64,
}

/// One action sequence, `H × m` row-major, with its score `G`.
struct Scored {
    g: f64,
    seq: Vec<f64>,
}

impl Planner {
    /// Plans for `mlac` with discount `γ`, its draws keyed by `seed`.
    pub fn new(mlac: Mlac, config: PlanningConfig, gamma: f64, seed: u64) -> Self {
        Self {
            mlac,
            config,
            gamma,
            seed,
        }
    }

    fn info(&self) -> &TaskInfo {
        self.mlac.info()
    }

    fn model(&self) -> &ProcessModel {
        self.mlac.model()
    }

    /// The random stream for planning in `x`: the run seed and the state's bits.
    fn rng(&self, x: &[f64]) -> ChaCha8Rng {
        let key = x.iter().fold(self.seed, |h, v| {
            (h ^ v.to_bits())
                .rotate_left(23)
                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        });
        let mut rng = ChaCha8Rng::seed_from_u64(key);
        rng.set_stream(STREAM);
        rng
    }

    /// `μ_i = π(x̃_i)` along the actor's rollout through the model.
    fn actor_rollout(&self, x: &[f64]) -> Vec<f64> {
        let (n, m, h) = (self.info().n(), self.info().m(), self.horizon());
        let mut seq = vec![0.0; h * m];
        let mut xs = x[..n].to_vec();
        for i in 0..h {
            let u = &mut seq[i * m..(i + 1) * m];
            self.mlac.actor().value(&xs, u);
            self.info().saturate(u);
            let next = self.model().predict(&xs, u).x_next;
            xs.copy_from_slice(&next[..n]);
        }
        seq
    }

    fn horizon(&self) -> usize {
        self.config.horizon as usize
    }

    /// `G` of one sequence from `x`; `−∞` if the model's prediction is not finite.
    fn score(&self, x: &[f64], seq: &[f64], critic: &dyn Differentiable) -> f64 {
        let (n, m) = (self.info().n(), self.info().m());
        let reward = &self.info().reward;
        let (mut g, mut discount) = (0.0, 1.0);
        let mut xs = x[..n].to_vec();
        for u in seq.chunks_exact(m) {
            g += discount * reward.reward(&xs, u);
            discount *= self.gamma;
            let next = self.model().predict(&xs, u).x_next;
            xs.copy_from_slice(&next[..n]);
        }
        g += discount * scalar(critic, &xs);
        if g.is_finite() { g } else { f64::NEG_INFINITY }
    }

    /// One iteration's candidates: the mean and `samples − 1` draws around it, scored
    /// and sorted best first.
    fn candidates(
        &self,
        x: &[f64],
        mean: &[f64],
        spread: &[f64],
        rng: &mut ChaCha8Rng,
        critic: &dyn Differentiable,
    ) -> Vec<Scored> {
        let m = self.info().m();
        let mut out = Vec::with_capacity(self.config.samples() as usize);
        out.push(Scored {
            g: self.score(x, mean, critic),
            seq: mean.to_vec(),
        });
        for _ in 1..self.config.samples() {
            let mut seq = mean.to_vec();
            for (k, v) in seq.iter_mut().enumerate() {
                let z: f64 = StandardNormal.sample(rng);
                let j = k % m;
                *v = (*v + spread[k] * z)
                    .clamp(self.info().action_low[j], self.info().action_high[j]);
            }
            let g = self.score(x, &seq, critic);
            out.push(Scored { g, seq });
        }
        out.sort_by(|a, b| b.g.total_cmp(&a.g));
        out
    }

    /// The best sequence from `x` by the cross-entropy method.
    fn plan(&self, x: &[f64], critic: &dyn Differentiable) -> Scored {
        let m = self.info().m();
        let mut mean = self.actor_rollout(x);
        let mut spread: Vec<f64> = (0..mean.len())
            .map(|k| (self.info().action_high[k % m] - self.info().action_low[k % m]) / 4.0)
            .collect();
        let mut rng = self.rng(x);
        let mut best = Scored {
            g: f64::NEG_INFINITY,
            seq: mean.clone(),
        };
        for _ in 0..self.config.iterations {
            let mut c = self.candidates(x, &mean, &spread, &mut rng, critic);
            c.truncate(self.config.elites() as usize);
            refit(&c, &mut mean, &mut spread);
            let first = c.swap_remove(0);
            if first.g > best.g {
                best = first;
            }
        }
        best
    }
}

/// `μ` and `σ` of the elite sequences, per entry.
fn refit(elites: &[Scored], mean: &mut [f64], spread: &mut [f64]) {
    let e = elites.len() as f64;
    for k in 0..mean.len() {
        let mu = elites.iter().map(|s| s.seq[k]).sum::<f64>() / e;
        let var = elites.iter().map(|s| (s.seq[k] - mu).powi(2)).sum::<f64>() / e;
        mean[k] = mu;
        spread[k] = var.sqrt();
    }
}

impl ChoosesActions for Planner {
    fn mlac(&self) -> &Mlac {
        &self.mlac
    }

    fn mlac_mut(&mut self) -> &mut Mlac {
        &mut self.mlac
    }

    fn choose(&self, x: &[f64], _u_prev: &[f64], critic: &ValueWithGradient, u: &mut [f64]) {
        let m = self.info().m();
        u.copy_from_slice(&self.plan(x, critic).seq[..m]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actor_critic::Improver;
    use crate::approx::Approximator;
    use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};
    use crate::horizon::Horizon;
    use crate::testing::{self, constant};

    /// On the tiny task (`ρ = −x² − u²`, the model `x' = x + b u`), infinite horizon.
    fn planner(horizon: u32, seed: u64) -> Planner {
        let info = TaskInfo {
            horizon: Horizon::Infinite,
            ..testing::info(2.0)
        };
        let actor = Box::new(constant(0.0));
        let mlac = Mlac::new(info, actor, testing::model(0.5), 0.1, 1.0, 0.0);
        let config = PlanningConfig {
            method: crate::config::PlanningMethod::Cem,
            horizon,
            samples: Some(64),
            elites: Some(8),
            iterations: 6,
            start_from_regulator: false,
        };
        Planner::new(mlac, config, 1.0, seed)
    }

    /// Over two samples with `V = 0`, `G = −x₀² − u₀² − (x₀ + b u₀)² − u₁²` is highest
    /// at `u₀ = −b x₀ / (1 + b²)` (−0.32 from `x₀ = 0.8`, `b = ½`), where the actor says
    /// 0: the planner finds it, the same action again for the same state and seed.
    #[test]
    fn the_planned_action_maximises_the_predicted_return() {
        let p = planner(2, 7);
        let v = constant(0.0);
        let (mut u, mut again) = ([0.0], [0.0]);
        p.act(&[0.8], &[0.0], &v, &mut u);
        p.act(&[0.8], &[0.0], &v, &mut again);
        assert!((u[0] + 0.32).abs() < 0.02, "u = {}", u[0]);
        assert_eq!(u, again);
        let mut other = [0.0];
        planner(2, 8).act(&[0.8], &[0.0], &v, &mut other);
        assert!((other[0] + 0.32).abs() < 0.02, "u = {}", other[0]);
    }

    /// `V(x) = a x`, for the terminal value.
    struct Slope(f64);

    impl Persist for Slope {
        fn save(&self, _: &mut Snapshot) {}
        fn restore(&mut self, _: &mut Reader) -> Result<(), CheckpointError> {
            Ok(())
        }
    }

    impl Approximator for Slope {
        fn input_dim(&self) -> usize {
            1
        }
        fn output_dim(&self) -> usize {
            1
        }
        fn value(&self, x: &[f64], y: &mut [f64]) {
            y[0] = self.0 * x[0];
        }
        fn shift(&mut self, _: &[f64], _: &[f64]) {}
        fn fit(&mut self, _: &[f64], _: &[f64], _: f64) {}
    }

    impl Differentiable for Slope {
        fn value_and_jacobian(&self, x: &[f64], y: &mut [f64], jac: &mut [f64]) {
            self.value(x, y);
            jac[0] = self.0;
        }
    }

    /// With one sample of look-ahead, `G = −x₀² − u₀² + V(x₀ + b u₀)`: a constant critic
    /// leaves the reward's `−u²` to decide (`u₀ = 0`), and `V = a x` pulls the action up
    /// to `u₀ = a b / 2` (0.2 for `a = 0.8`, `b = ½`).
    #[test]
    fn the_critic_is_the_terminal_value() {
        let p = planner(1, 7);
        let mut u = [1.0];
        p.act(&[0.2], &[0.0], &constant(5.0), &mut u);
        assert!(u[0].abs() < 0.02, "u = {}", u[0]);
        p.act(&[0.2], &[0.0], &Slope(0.8), &mut u);
        assert!((u[0] - 0.2).abs() < 0.02, "u = {}", u[0]);
    }
}
