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

use plant::QuadraticReward;

use crate::Agent;
use crate::approx::{Differentiable, scalar};
use crate::critic::Critic;
use crate::explore::Exploration;

/// One experienced transition, as the policy improvement sees it.
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
    pub reward: QuadraticReward,
}

impl TaskInfo {
    /// From a plant task.
    pub fn of(task: &plant::Task) -> Self {
        Self {
            action_low: task.action_low.clone(),
            action_high: task.action_high.clone(),
            angle_mask: task.angle_mask.clone(),
            reward: task.reward.clone(),
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

    /// Action dimension.
    pub fn m(&self) -> usize {
        self.action_low.len()
    }
}

/// The algorithm-specific half of an actor-critic learner: how actions are chosen and
/// how the policy improves given the critic `V`.
pub trait Improver: Send {
    /// The policy's action `π(x)` (without exploration) into `u`; `u_prev` is the action
    /// applied in the previous sample (RMAC and VGBP linearise their model around it).
    fn act(&self, x: &[f64], u_prev: &[f64], critic: &dyn Differentiable, u: &mut [f64]);
    /// Improves the policy and learns any models from transition `t`.
    fn improve(&mut self, t: &Transition, critic: &dyn Differentiable);
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

/// An actor-critic agent: critic + improver + exploration.
pub struct ActorCritic {
    info: TaskInfo,
    learning: Learning,
    critic: Box<dyn Critic>,
    improver: Box<dyn Improver>,
    exploration: Exploration,
    x: Vec<f64>,
    u: Vec<f64>,
    u_policy: Vec<f64>,
    du: Vec<f64>,
}

impl ActorCritic {
    /// Assembles an agent.
    pub fn new(
        info: TaskInfo,
        learning: Learning,
        critic: Box<dyn Critic>,
        improver: Box<dyn Improver>,
        exploration: Exploration,
    ) -> Self {
        let (n, m) = (info.n(), info.m());
        Self {
            info,
            learning,
            critic,
            improver,
            exploration,
            x: vec![0.0; n],
            u: vec![0.0; m],
            u_policy: vec![0.0; m],
            du: vec![0.0; m],
        }
    }

    /// The critic's value `V(x)`.
    pub fn value(&self, x: &[f64]) -> f64 {
        scalar(self.critic.function(), x)
    }

    /// Line 9 (Algorithm 7: lines 12–14): `π(x)`, saturated.
    fn policy(&self, x: &[f64], u_prev: &[f64]) -> Vec<f64> {
        let mut u = vec![0.0; self.info.m()];
        self.improver.act(x, u_prev, self.critic.function(), &mut u);
        self.info.saturate(&mut u);
        u
    }

    /// Lines 6–19 for one transition; `terminal`: `x_next` ends the trial with value zero.
    /// Writes the next action into `u` if given (and the trial goes on).
    fn transition(&mut self, r: f64, x_next: &[f64], terminal: bool, u: Option<&mut [f64]>) {
        let Learning { gamma, lambda } = self.learning;
        let td = self
            .critic
            .observe(&self.x, r, (!terminal).then_some(x_next), gamma, lambda);
        let after = self.improver.acts_after_update();
        let u_next = (u.is_some() && !after).then(|| self.policy(x_next, &self.u));
        let t = Transition {
            x: &self.x,
            u: &self.u,
            u_policy: &self.u_policy,
            du: &self.du,
            r,
            x_next,
            td,
        };
        self.improver.improve(&t, self.critic.function());
        self.critic.update(td);
        let u_next =
            u_next.or_else(|| (u.is_some() && after).then(|| self.policy(x_next, &self.u)));
        self.x.copy_from_slice(x_next);
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

impl Agent for ActorCritic {
    fn start_trial(&mut self, x0: &[f64], u: &mut [f64]) {
        self.critic.start_trial();
        self.exploration.start_trial();
        self.x.copy_from_slice(x0);
        let u_policy = self.policy(x0, &vec![0.0; self.info.m()]);
        self.explore(&u_policy, u);
    }

    fn learn(&mut self, r: f64, x_next: &[f64], u: Option<&mut [f64]>) {
        self.transition(r, x_next, false, u);
    }

    fn learn_terminal(&mut self, r: f64, x_next: &[f64]) {
        self.transition(r, x_next, true, None);
    }

    fn greedy(&self, x: &[f64], u_prev: &[f64], u: &mut [f64]) {
        u.copy_from_slice(&self.policy(x, u_prev));
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
