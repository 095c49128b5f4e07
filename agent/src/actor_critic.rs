//! The loop shared by SAC, MLAC, RMAC and VGBP: Template 2.1 (Eq. 2.19) with the step
//! order of Algorithms 1–3 and 7.
//!
//! Per sample, after measuring `x_{k+1}` and `r_{k+1}` (lines 6–19):
//!
//! ```text
//! δ_k     ← r_{k+1} + γ V(x_{k+1}) − V(x_k)            line 7      (Eq. 2.19a)
//! u_{k+1} ← π(x_{k+1})                                  line 9
//! improve the policy (and learn the models)             lines 10–13 (per algorithm)
//! z_k     ← λγ z_{k−1} + ∇_θ V(x_k)                     line 12/15  (Eq. 2.19b)
//! θ       ← θ + α_c δ_k z_k                              line 13/16  (Eq. 2.19c)
//! apply sat(u_{k+1} + Δu_{k+1}),  Δu ~ N(0, σ²)         lines 14–15
//! ```
//!
//! The critic's visit of `x_k` happens before `V(x_{k+1})` is evaluated, as §3.5.2
//! describes for LLR (the sample `[x_k | V(x_k)]` is stored first); for a parametric
//! critic the order is immaterial because the visit changes only the traces. The critic
//! and its learning rule (TD(λ) or LSTD(λ)) are a [`Critic`].
//!
//! VGBP (Algorithm 7) has no actor: its action is computed from the critic and the
//! process model, and it is chosen *after* the critic and model updates (lines 12–14
//! follow lines 6–10), where Algorithms 1–3 choose it before (line 9) —
//! [`Improver::acts_after_update`].
//!
//! What differs between the algorithms is the [`Improver`]: [`crate::sac`],
//! [`crate::mlac`], [`crate::rmac`], [`crate::vgbp`].
//!
//! **Finite horizon** (Chapter 4, Algorithms 4–6): the same step with the task's
//! [`Horizon`] (in [`TaskInfo`]). The agent counts the samples `k` of a trial; actor,
//! critic and reference model read `(x_k, k)` (Eq. 4.6) wherever the infinite-horizon
//! algorithms read `x_k`, so the improvers are those of Chapter 3; and the last sample's
//! temporal difference targets the terminal reward (Eq. 4.3):
//!
//! ```text
//! δ_k ← r_{k+1} + γ V(x_{k+1}, k+1) − V(x_k, k)         k < N − 1
//! δ_k ← r_{k+1} + γ τ_N(x_{k+1})   − V(x_k, k)          k = N − 1  (γ = 1 in §4.4)
//! ```
//!
//! Algorithms 4 and 5 write their loop with the action applied at its top (line 7), that
//! is from the actor as updated by the previous sample; the shared step keeps line 9 of
//! Algorithms 1–3 — the action chosen before the update — which is also the order of
//! Algorithm 6 (lines 10–11). The difference is one sample's update of the actor.
//! Measured (MLAC-FH, 20 runs × 600 trials, last greedy return, mean ± sample std, seeds
//! 1 and 2): −901 ± 148 and −888 ± 113 with this order, −858 ± 56 and −906 ± 114 with
//! the action chosen after the update — no systematic difference.
//!
//! **Trial endings.** A termination (the operating range left, §6.4.2; the goal reached)
//! targets the reward alone, `δ_k = r_{k+1} − V(x_k)` ([`Agent::learn_terminal`]), with
//! either horizon: the terminal transition's reward stands for everything after it, `τ_N`
//! included. The time limit is a truncation: the last transition bootstraps
//! `γ V(x_{k+1})` (`τ_N(x_N)` for a finite horizon) as any other.

use plant::Reward;

use crate::Agent;
use crate::approx::{Approximator, scalar};
use crate::critic::{Critic, Next, ValueWithGradient};
use crate::explore::Exploration;
use crate::horizon::{Horizon, Input};

/// One experienced transition, as the policy improvement sees it.
///
/// With a finite horizon, `x` and `x_next` carry time after the state: `(x_k, k)` and
/// `(x_{k+1}, k+1)` (Eq. 4.6) — the inputs of actor, critic and reference model; the
/// process model reads their state parts.
pub struct Transition<'a> {
    /// `x_k`.
    pub x: &'a [f64],
    /// `u_k` as applied (saturated, exploration included).
    pub u: &'a [f64],
    /// `π(x_k)`, the policy's action when `u_k` was chosen.
    pub u_policy: &'a [f64],
    /// The exploration actually applied, `u_k − π(x_k)` (after saturation).
    pub du: &'a [f64],
    /// `r_{k+1} = ρ(x_k, u_k)`.
    pub r: f64,
    /// `x_{k+1}`.
    pub x_next: &'a [f64],
    /// The temporal difference `δ_k`.
    pub td: f64,
}

/// What the actor-critic loop knows about the task.
#[derive(Clone, Debug)]
pub struct TaskInfo {
    /// Lower action bounds.
    pub action_low: Vec<f64>,
    /// Upper action bounds.
    pub action_high: Vec<f64>,
    /// Which state components are angles.
    pub angle_mask: Vec<bool>,
    /// The reward function, known to model-based learners (MLAC, VGBP).
    pub reward: Reward,
    /// Infinite, or finite with time as an input (Chapter 4).
    pub horizon: Horizon,
}

impl TaskInfo {
    /// From a plant task, with an infinite horizon.
    pub fn of(task: &plant::Task) -> Self {
        Self {
            action_low: task.action_low.clone(),
            action_high: task.action_high.clone(),
            angle_mask: task.angle_mask.clone(),
            reward: task.reward.clone(),
            horizon: Horizon::Infinite,
        }
    }

    /// Saturates `u` in place.
    pub fn saturate(&self, u: &mut [f64]) {
        for (j, v) in u.iter_mut().enumerate() {
            *v = v.clamp(self.action_low[j], self.action_high[j]);
        }
    }

    /// State dimension.
    pub fn n(&self) -> usize {
        self.angle_mask.len()
    }

    /// Input dimension of actor, critic and reference model: the state, and time for a
    /// finite horizon (Eq. 4.6).
    pub fn input_dim(&self) -> usize {
        self.n() + self.horizon.extra_inputs()
    }

    /// Action dimension.
    pub fn m(&self) -> usize {
        self.action_low.len()
    }
}

/// The algorithm-specific half of an actor-critic learner: how actions are chosen and
/// how the policy improves given the critic `V`.
/// `F` is what it reads of the critic's value function: `V(x)` with its gradient (the
/// default), or `V(x)` only ([`crate::critic::Critic`]).
pub trait Improver<F: ?Sized = ValueWithGradient>: Send + crate::checkpoint::Persist {
    /// The policy's action `π(x)` (without exploration) into `u`; `u_prev` is the action
    /// applied in the previous sample (RMAC and VGBP linearise their model around it).
    /// With a finite horizon `x` is `(x_k, k)`.
    fn act(&self, x: &[f64], u_prev: &[f64], critic: &F, u: &mut [f64]);
    /// A learning trial begins (a learning rate on a schedule counts it).
    fn start_trial(&mut self) {}
    /// A greedy trial begins (nothing learns; a planner drops its last plan).
    fn start_greedy_trial(&mut self) {}
    /// Improves the policy and learns any models from transition `t`.
    fn improve(&mut self, t: &Transition, critic: &F);
    /// Whether the next action is chosen after the critic and model updates of this
    /// sample (Algorithm 7) rather than before them (Algorithms 1–3, line 9).
    fn acts_after_update(&self) -> bool {
        false
    }
    /// `(name, stored, capacity)` of each memory-based approximator.
    fn memories(&self) -> Vec<(&'static str, usize, usize)> {
        Vec::new()
    }
}

/// Learning parameters of Template 2.1.
#[derive(Clone, Debug, PartialEq)]
pub struct Learning {
    /// Discount `γ`.
    pub gamma: f64,
    /// Trace decay `λ`.
    pub lambda: f64,
}

/// An actor-critic agent: critic + improver + exploration; the improver reads the
/// critic's value function as an `F` (with its gradient, or SAC's: values only).
pub struct ActorCritic<F: ?Sized = ValueWithGradient> {
    info: TaskInfo,
    learning: Learning,
    critic: Box<dyn Critic<F>>,
    improver: Box<dyn Improver<F>>,
    exploration: Exploration,
    /// `x_k`, as the actor and critic read it: `(x_k, k)` for a finite horizon.
    x: Input,
    /// `k`, the sample index within the trial.
    k: usize,
    u: Vec<f64>,
    u_policy: Vec<f64>,
    du: Vec<f64>,
}

impl<F: Approximator + ?Sized> ActorCritic<F> {
    /// Assembles an agent.
    pub fn new(
        info: TaskInfo,
        learning: Learning,
        critic: Box<dyn Critic<F>>,
        improver: Box<dyn Improver<F>>,
        exploration: Exploration,
    ) -> Self {
        let (n, m) = (info.n(), info.m());
        let x = info.horizon.input(&vec![0.0; n], 0);
        Self {
            info,
            learning,
            critic,
            improver,
            exploration,
            x,
            k: 0,
            u: vec![0.0; m],
            u_policy: vec![0.0; m],
            du: vec![0.0; m],
        }
    }

    /// The critic's value `V(x)`, or `V(x, k)` for a finite horizon (`k` is ignored for
    /// an infinite one).
    pub fn value(&self, x: &[f64], k: usize) -> f64 {
        scalar(self.critic.function(), &self.info.horizon.input(x, k))
    }

    /// Line 9 (Algorithm 7: lines 12–14): `π(x)`, saturated; `x` is an actor input.
    fn policy(&self, x: &[f64], u_prev: &[f64]) -> Vec<f64> {
        let mut u = vec![0.0; self.info.m()];
        self.improver.act(x, u_prev, self.critic.function(), &mut u);
        self.info.saturate(&mut u);
        u
    }

    /// Lines 6–19 for one transition into `x_next` (a state; the time input is added
    /// here). `terminal`: the trial terminated in `x_next` (it left the operating range,
    /// §6.4.2, or reached the goal), whose value is zero — also with a finite horizon,
    /// where neither `V` nor `τ_N` follows a termination.
    /// Writes the next action into `u` if given (and the trial goes on).
    fn transition(&mut self, r: f64, x_next: &[f64], terminal: bool, u: Option<&mut [f64]>) {
        let Learning { gamma, lambda } = self.learning;
        let horizon = self.info.horizon;
        let x_next_in = horizon.input(x_next, self.k + 1);
        let next = if terminal {
            Next::Terminal(0.0)
        } else if horizon.ends_after(self.k) {
            // After a finite horizon's last sample V(x_N, N) is τ_N(x_N)    (Eq. 4.3)
            Next::Terminal(self.info.reward.terminal_reward(x_next))
        } else {
            Next::State(&x_next_in)
        };
        let td = self.critic.observe(&self.x, r, next, gamma, lambda);
        let after = self.improver.acts_after_update();
        let u_next = (u.is_some() && !after).then(|| self.policy(&x_next_in, &self.u));
        let t = Transition {
            x: &self.x,
            u: &self.u,
            u_policy: &self.u_policy,
            du: &self.du,
            r,
            x_next: &x_next_in,
            td,
        };
        self.improver.improve(&t, self.critic.function());
        self.critic.update(td);
        let u_next =
            u_next.or_else(|| (u.is_some() && after).then(|| self.policy(&x_next_in, &self.u)));
        self.x = x_next_in;
        self.k += 1;
        match (u, u_next) {
            (Some(u), Some(u_next)) => self.explore(&u_next, u),
            _ => self.critic.end_trial(),
        }
    }

    /// Lines 14–15: `u ← sat(π(x) + Δu)`; remembers `π(x)` and the applied exploration.
    fn explore(&mut self, u_policy: &[f64], u: &mut [f64]) {
        self.u_policy.copy_from_slice(u_policy);
        self.exploration.draw(&mut self.du);
        for j in 0..u.len() {
            u[j] = u_policy[j] + self.du[j];
        }
        self.info.saturate(u);
        for j in 0..u.len() {
            self.du[j] = u[j] - u_policy[j];
        }
        self.u.copy_from_slice(u);
    }
}

impl<F: Approximator + ?Sized> Agent for ActorCritic<F> {
    fn start_trial(&mut self, x0: &[f64], u: &mut [f64]) {
        self.critic.start_trial();
        self.improver.start_trial();
        self.exploration.start_trial();
        self.k = 0;
        self.x = self.info.horizon.input(x0, 0);
        let u_policy = self.policy(&self.x, &vec![0.0; self.info.m()]);
        self.explore(&u_policy, u);
    }

    fn learn(&mut self, r: f64, x_next: &[f64], u: Option<&mut [f64]>) {
        self.transition(r, x_next, false, u);
    }

    fn learn_terminal(&mut self, r: f64, x_next: &[f64]) {
        self.transition(r, x_next, true, None);
    }

    fn greedy(&self, k: usize, x: &[f64], u_prev: &[f64], u: &mut [f64]) {
        u.copy_from_slice(&self.policy(&self.info.horizon.input(x, k), u_prev));
    }

    fn start_greedy_trial(&mut self) {
        self.improver.start_greedy_trial();
    }

    fn memories(&self) -> Vec<(&'static str, usize, usize)> {
        let mut m: Vec<_> = self
            .critic
            .fill()
            .map(|(s, c)| ("critic", s, c))
            .into_iter()
            .collect();
        m.extend(self.improver.memories());
        m
    }
}

/// The critic, the improver (actor, reference model, process model) and the exploration
/// stream; the per-sample state is set again by the next trial's start.
impl<F: ?Sized> crate::checkpoint::Persist for ActorCritic<F> {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        s.scope("critic", |s| self.critic.save(s));
        s.scope("improver", |s| self.improver.save(s));
        self.exploration.save(s);
    }
    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        r.scope("critic", |r| self.critic.restore(r))?;
        r.scope("improver", |r| self.improver.restore(r))?;
        self.exploration.restore(r)
    }
}

#[cfg(test)]
mod tests {
    use super::{ActorCritic, Learning};
    use crate::Agent;
    use crate::approx::rbf::{Rbf, RbfParams};
    use crate::approx::scalar;
    use crate::critic::{Critic, TdLambda};
    use crate::explore::Exploration;
    use crate::horizon::Horizon;
    use crate::lstd::Lstd;
    use crate::sac::Sac;
    use crate::testing::{self, close, dot, psi};

    /// The last sample of a finite horizon targets `τ_N(x_N)` (Eq. 4.3, Algorithm 4
    /// line 12), not the critic's `V(x_N, N)` — which here is about 5, where
    /// `τ_N(x_N) = −x_N² = −0.64`. No exploration, so only the critic learns; `λ = 0`.
    #[test]
    fn the_last_sample_targets_the_terminal_reward() {
        let theta = [1.0, 5.0];
        let mut critic = testing::rbf(1, None);
        critic.parameters_mut().copy_from_slice(&theta);
        let v_at_n = scalar(&critic, &[0.8, 2.0]);
        assert!(v_at_n > 4.9, "V(x_N, N) = {v_at_n}");
        let v = |theta: [f64; 2], k| dot(theta, psi(k));
        let sac = Box::new(Sac::new(Box::new(testing::rbf(1, None)), 1.0));
        let mut ac = testing::agent(testing::info(10.0), critic, 1.0, 0.0, sac, 0.0);
        let (x2, r1, r2) = (0.8, -1.0, -2.0);
        let mut u = [0.0];
        ac.start_trial(&[0.3], &mut u);
        ac.learn(r1, &[0.6], Some(&mut u));
        // δ_0 = r_1 + V(x_1, 1) − V(x_0, 0),  θ ← θ + δ_0 ψ(0)
        let d0 = r1 + v(theta, 1) - v(theta, 0);
        let theta = [theta[0] + d0 * psi(0)[0], theta[1] + d0 * psi(0)[1]];
        ac.learn(r2, &[x2], None);
        // δ_1 = r_2 + τ_N(x_2) − V(x_1, 1),  θ ← θ + δ_1 ψ(1)
        let d1 = r2 - x2 * x2 - v(theta, 1);
        let theta = [theta[0] + d1 * psi(1)[0], theta[1] + d1 * psi(1)[1]];
        for k in 0..2 {
            close(ac.value(&[0.5], k), v(theta, k));
        }
        assert_eq!(
            testing::greedy(&ac, 0.5, 1),
            0.0,
            "σ = 0: the actor is unchanged"
        );
    }

    /// A termination (the goal reached, the operating range left) targets the reward
    /// alone, `δ = r − V(x)`; the time limit (truncation) bootstraps,
    /// `δ = r + γ V(x') − V(x)` — for every actor-critic learner (they share this step),
    /// with a TD(λ) critic and with LSTD. One basis function, `V ≡ θ`.
    #[test]
    fn a_termination_bootstraps_nothing_and_a_truncation_bootstraps() {
        let (gamma, r) = (0.9, -2.0);
        let one = |initial: f64| {
            Rbf::new(&RbfParams {
                centres: vec![1],
                range: vec![(0.0, 1.0)],
                periodic: vec![false],
                intersection: 0.5,
                outputs: 1,
                initial,
                bounds: None,
            })
        };
        let mut info = testing::info(10.0);
        info.horizon = Horizon::Infinite;
        let value_after = |critic: Box<dyn Critic>, terminal: bool| {
            let sac = Box::new(Sac::new(Box::new(one(0.0)), 1.0));
            let learning = Learning { gamma, lambda: 0.0 };
            let exploration = Exploration::new(0.0, 1, 7);
            let mut ac = ActorCritic::new(info.clone(), learning, critic, sac, exploration);
            let mut u = [0.0];
            ac.start_trial(&[0.3], &mut u);
            if terminal {
                ac.learn_terminal(r, &[0.6]);
            } else {
                ac.learn(r, &[0.6], None);
            }
            ac.value(&[0.5], 0)
        };
        // TD(λ), α_c = 1 from θ = 5: θ becomes the target.
        let td = || Box::new(TdLambda::new(Box::new(one(5.0)), 1.0));
        close(value_after(td(), true), r);
        close(value_after(td(), false), r + gamma * 5.0);
        // LSTD from A_0 = a_0: θ = b / A, A = a_0 + 1 − γ φ(x') (φ(x') = 0 if terminal).
        let a0 = 0.5;
        let lstd = || Box::new(Lstd::new(one(0.0), a0, None));
        close(value_after(lstd(), true), r / (a0 + 1.0));
        close(value_after(lstd(), false), r / (a0 + 1.0 - gamma));
    }
}
