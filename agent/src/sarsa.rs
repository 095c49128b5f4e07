//! SARSA(λ) (§6.2, Eq. 6.1–6.5), the critic-only baseline of Chapter 6: a Q-function
//! over a discrete action set, learned on-policy with eligibility traces, actions chosen
//! ε-greedily.
//!
//! `Q(x, a) = θ_aᵀ φ(x)`: one set of normalised RBFs `φ` (§3.5.1) shared by every action
//! `a ∈ U_SARSA`, one parameter vector per action (§6.4.1: 20 × 20 RBFs, `{−3, 0, 3}`,
//! `p = 3 · 400`). Per sample:
//!
//! ```text
//! u_{k+1}  ← ε-greedy in Q(x_{k+1}, ·),  ε = max(ε_min, decay^(trial−1))   Eq. 6.22
//! δ_{k+1}  ← r_{k+1} + γ Q(x_{k+1}, u_{k+1}) − Q(x_k, u_k)                  Eq. 6.1
//! z_k      ← λγ z_{k−1} + ∂Q(x_k, u_k)/∂θ                                    Eq. 6.4
//! θ        ← θ + α δ_{k+1} z_k                                               Eq. 6.5
//! ```
//!
//! At a trial's last sample the bootstrap action is drawn the same way but not applied.
//! With more than one action dimension the set is the Cartesian product of the listed
//! values over the dimensions. The ε-greedy draws come from their own stream of the run
//! seed; ties in `argmax Q` go to the first action in the list.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::Agent;
use crate::approx::Approximator;
use crate::approx::rbf::Rbf;
use crate::step_size::StepSize;

/// Stream id of SARSA's ε-greedy draws.
pub const STREAM: u64 = crate::explore::stream::SARSA;

/// ε-greedy schedule of Eq. 6.22.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Epsilon {
    /// Per-trial decay factor (0.96).
    pub decay: f64,
    /// Floor (0.1).
    pub min: f64,
}

impl Epsilon {
    /// `ε = max(min, decay^(trial−1))` for the 1-based `trial`.
    pub fn at(&self, trial: u32) -> f64 {
        self.min.max(
            self.decay
                .powi(trial.saturating_sub(1).min(i32::MAX as u32) as i32),
        )
    }
}

/// A SARSA(λ) agent.
pub struct Sarsa {
    q: Rbf,
    actions: Vec<Vec<f64>>,
    step: StepSize,
    gamma: f64,
    lambda: f64,
    epsilon: Epsilon,
    rng: ChaCha8Rng,
    trial: u32,
    trace: Vec<f64>,
    phi: Vec<f64>,
    q_values: Vec<f64>,
    x: Vec<f64>,
    a: usize,
}

impl Sarsa {
    /// SARSA over `actions` (each a full action vector) with `q` an RBF approximator
    /// with one output per action, learning with rate `α` (constant or on a schedule).
    ///
    /// # Panics
    /// If `q`'s outputs do not match the action count (validated by the configuration).
    pub fn new(
        q: Rbf,
        actions: Vec<Vec<f64>>,
        alpha: impl Into<StepSize>,
        gamma: f64,
        lambda: f64,
        epsilon: Epsilon,
        run_seed: u64,
    ) -> Self {
        assert_eq!(q.output_dim(), actions.len(), "one Q output per action");
        let mut rng = ChaCha8Rng::seed_from_u64(run_seed);
        rng.set_stream(STREAM);
        let p = q.len();
        let n = q.input_dim();
        Self {
            trace: vec![0.0; p * actions.len()],
            q_values: vec![0.0; actions.len()],
            phi: vec![0.0; p],
            x: vec![0.0; n],
            a: 0,
            q,
            actions,
            step: alpha.into(),
            gamma,
            lambda,
            epsilon,
            rng,
            trial: 0,
        }
    }

    /// The action set `U_SARSA` as the Cartesian product of `values` over `m`
    /// dimensions.
    pub fn action_set(values: &[f64], m: usize) -> Vec<Vec<f64>> {
        (0..m).fold(vec![Vec::new()], |acc, _| {
            acc.iter()
                .flat_map(|a| {
                    values.iter().map(move |&v| {
                        let mut a = a.clone();
                        a.push(v);
                        a
                    })
                })
                .collect()
        })
    }

    fn greedy_index(&self, x: &[f64]) -> usize {
        let mut q = vec![0.0; self.actions.len()];
        self.q.value(x, &mut q);
        argmax(&q)
    }

    /// ε-greedy choice in `x` (Eq. 6.22).
    fn choose(&mut self, x: &[f64]) -> usize {
        let eps = self.epsilon.at(self.trial);
        if self.rng.random::<f64>() < eps {
            self.rng.random_range(0..self.actions.len())
        } else {
            self.greedy_index(x)
        }
    }

    /// `Q(x, ·)` into `self.q_values`.
    fn q_of(&mut self, x: &[f64]) {
        self.q.value(x, &mut self.q_values);
    }
}

fn argmax(q: &[f64]) -> usize {
    let mut best = 0;
    for (i, &v) in q.iter().enumerate() {
        if v > q[best] {
            best = i;
        }
    }
    best
}

impl Agent for Sarsa {
    fn start_trial(&mut self, x0: &[f64], u: &mut [f64]) {
        self.trial = self.trial.saturating_add(1);
        self.step.start_trial();
        self.trace.fill(0.0);
        self.x.copy_from_slice(x0);
        self.a = self.choose(x0);
        u.copy_from_slice(&self.actions[self.a]);
    }

    fn learn(&mut self, r: f64, x_next: &[f64], u: Option<&mut [f64]>) {
        let a_next = self.choose(x_next);
        self.q_of(x_next);
        let q_next = self.q_values[a_next];
        self.update(r, q_next, x_next, a_next);
        if let Some(u) = u {
            u.copy_from_slice(&self.actions[a_next]);
        }
    }

    fn learn_terminal(&mut self, r: f64, x_next: &[f64]) {
        // A terminal state has value zero: Q(x_{k+1}, ·) = 0.
        self.update(r, 0.0, x_next, self.a);
    }

    fn greedy(&self, _k: usize, x: &[f64], _u_prev: &[f64], u: &mut [f64]) {
        u.copy_from_slice(&self.actions[self.greedy_index(x)]);
    }

    fn memories(&self) -> Vec<(&'static str, usize, usize)> {
        Vec::new()
    }
}

impl Sarsa {
    /// Eq. 6.1–6.5 for the transition `(x_k, u_k, r_{k+1}, x_{k+1})` with
    /// `Q(x_{k+1}, u_{k+1}) = q_next`; then `u_{k+1}` is the action index `a_next`.
    fn update(&mut self, r: f64, q_next: f64, x_next: &[f64], a_next: usize) {
        let k = self.actions.len();
        let x = std::mem::take(&mut self.x);
        self.q_of(&x);
        let q_now = self.q_values[self.a];
        // δ = r + γ Q(x_{k+1}, u_{k+1}) − Q(x_k, u_k)                       (Eq. 6.1)
        let td = r + self.gamma * q_next - q_now;
        // z ← λγ z + ∂Q(x_k, u_k)/∂θ: φ(x_k) in the block of u_k             (Eq. 6.4)
        self.q.basis(&x, &mut self.phi);
        let decay = self.lambda * self.gamma;
        for (i, phi) in self.phi.iter().enumerate() {
            let z = &mut self.trace[i * k..(i + 1) * k];
            for z in z.iter_mut() {
                *z *= decay;
            }
            z[self.a] += phi;
        }
        // θ ← θ + α δ z                                                      (Eq. 6.5)
        let step = self.step.alpha() * td;
        for (t, z) in self.q.parameters_mut().iter_mut().zip(&self.trace) {
            *t += step * z;
        }
        self.x = x;
        self.x.copy_from_slice(x_next);
        self.a = a_next;
    }
}

impl crate::checkpoint::Persist for Sarsa {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        s.scope("sarsa", |s| {
            s.scope("q", |s| {
                self.q.save(s);
                self.step.save(s);
            });
            s.rng("rng", &self.rng);
            s.u64s("trial", &[u64::from(self.trial), self.a as u64]);
            s.f64s("trace", &self.trace);
            s.f64s("x", &self.x);
        });
    }
    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        r.scope("sarsa", |r| {
            r.scope("q", |r| {
                self.q.restore(r)?;
                self.step.restore(r)
            })?;
            self.rng = r.rng("rng")?;
            let t = r.u64s("trial")?;
            if t.len() != 2 || t[1] as usize >= self.actions.len() {
                return Err(crate::checkpoint::CheckpointError::Unfit {
                    section: "sarsa.trial",
                    why: "does not fit the action set".into(),
                });
            }
            (self.trial, self.a) = (t[0] as u32, t[1] as usize);
            r.f64s_into("trace", &mut self.trace)?;
            r.f64s_into("x", &mut self.x)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::approx::rbf::RbfParams;

    fn one_feature(actions: usize) -> Rbf {
        Rbf::new(&RbfParams {
            centres: vec![1],
            range: vec![(0.0, 1.0)],
            periodic: vec![false],
            intersection: 0.5,
            outputs: actions,
            initial: 0.0,
            bounds: None,
        })
    }

    #[test]
    fn epsilon_schedule_of_eq_6_22() {
        let e = Epsilon {
            decay: 0.96,
            min: 0.1,
        };
        assert_eq!(e.at(1), 1.0);
        assert!((e.at(2) - 0.96).abs() < 1e-15);
        assert!((e.at(30) - 0.96f64.powi(29)).abs() < 1e-15);
        assert_eq!(e.at(100), 0.1);
    }

    #[test]
    fn action_set_is_a_product() {
        assert_eq!(
            Sarsa::action_set(&[-1.0, 1.0], 2),
            vec![
                vec![-1.0, -1.0],
                vec![-1.0, 1.0],
                vec![1.0, -1.0],
                vec![1.0, 1.0]
            ]
        );
    }

    /// Two hand-computed steps with a single basis function (`φ ≡ 1`) and greedy
    /// choices (ε = 0): the traces and TD errors of Eq. 6.1–6.5.
    #[test]
    fn two_steps_by_hand() {
        let (alpha, gamma, lambda) = (0.5, 0.9, 0.5);
        let greedy = Epsilon {
            decay: 0.0,
            min: 0.0,
        };
        let mut s = Sarsa::new(
            one_feature(2),
            vec![vec![-1.0], vec![1.0]],
            alpha,
            gamma,
            lambda,
            greedy,
            7,
        );
        // Trial 1 has ε = max(0, 0⁰) = 1: start a second trial to be greedy.
        let mut u = [0.0];
        s.start_trial(&[0.5], &mut u);
        s.start_trial(&[0.5], &mut u);
        assert_eq!(u, [-1.0], "all Q = 0: the first action wins the tie");
        // Step 1: u_{k+1} is chosen before the update (tie again: action 0);
        // δ = −2 + 0.9·0 − 0 = −2; z = [1, 0]; θ = [−1, 0].
        s.learn(-2.0, &[0.5], Some(&mut u));
        assert_eq!(s.q.parameters(), &[-1.0, 0.0]);
        assert_eq!(u, [-1.0]);
        // Step 2: Q(x, ·) = [−1, 0], so u_{k+1} = action 1;
        // δ = −3 + 0.9·0 − (−1) = −2; z = 0.45·[1, 0] + [1, 0]; θ = [−1 − 1.45, 0].
        s.learn(-3.0, &[0.5], Some(&mut u));
        let t = s.q.parameters();
        assert!((t[0] + 2.45).abs() < 1e-12 && t[1] == 0.0, "{t:?}");
        assert_eq!(u, [1.0]);
        // Step 3 ends in a terminal state: Q(x_{k+1}, ·) = 0 although Q(x, 0) = −2.45;
        // δ = −4 + 0 − Q(x, 1) = −4; z = 0.45·[1.45, 0] + [0, 1]; θ += 0.5·δ·z.
        s.learn_terminal(-4.0, &[0.5]);
        let t = s.q.parameters();
        let want = [-2.45 - 2.0 * 0.45 * 1.45, -2.0];
        assert!((t[0] - want[0]).abs() < 1e-12 && (t[1] - want[1]).abs() < 1e-12);
    }
}
