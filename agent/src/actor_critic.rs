//! The actor-critic loop shared by SAC, MLAC and RMAC: Template 2.1 (Eq. 2.19) with the
//! step order of Algorithms 1–3.
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
//! critic the order is immaterial because the visit changes only the traces.
//! What differs between the algorithms is the [`Improver`]: [`crate::sac`],
//! [`crate::mlac`], [`crate::rmac`].

use plant::QuadraticReward;

use crate::Agent;
use crate::approx::{Critic, scalar};
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
/// how the policy improves given the critic.
pub trait Improver: Send {
    /// The policy's action `π(x)` (without exploration) into `u`; `u_prev` is the action
    /// applied in the previous sample (RMAC linearises its model around it).
    fn act(&self, x: &[f64], u_prev: &[f64], u: &mut [f64]);
    /// Improves the policy and learns any models from transition `t`.
    fn improve(&mut self, t: &Transition, critic: &dyn Critic);
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
    /// Critic learning rate `α_c`.
    pub alpha_critic: f64,
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
        scalar(self.critic.as_ref(), x)
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
        self.critic.clear_traces();
        self.exploration.start_trial();
        self.x.copy_from_slice(x0);
        let m = self.info.m();
        let mut u_policy = vec![0.0; m];
        self.improver.act(x0, &vec![0.0; m], &mut u_policy);
        self.info.saturate(&mut u_policy);
        self.explore(&u_policy, u);
    }

    fn learn(&mut self, r: f64, x_next: &[f64], u: Option<&mut [f64]>) {
        let Learning {
            gamma,
            lambda,
            alpha_critic,
        } = self.learning;
        let v = self.critic.visit_value(&self.x, lambda * gamma);
        let v_next = scalar(self.critic.as_ref(), x_next);
        let td = r + gamma * v_next - v;
        let m = self.info.m();
        let mut u_next = vec![0.0; m];
        if u.is_some() {
            self.improver.act(x_next, &self.u, &mut u_next);
            self.info.saturate(&mut u_next);
        }
        let t = Transition {
            x: &self.x,
            u: &self.u,
            u_policy: &self.u_policy,
            du: &self.du,
            r,
            x_next,
            td,
        };
        self.improver.improve(&t, self.critic.as_ref());
        self.critic.apply_td(alpha_critic * td);
        self.x.copy_from_slice(x_next);
        if let Some(u) = u {
            self.explore(&u_next, u);
        }
    }

    fn greedy(&self, x: &[f64], u_prev: &[f64], u: &mut [f64]) {
        self.improver.act(x, u_prev, u);
        self.info.saturate(u);
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
