//! Simulated plants of Grondman's thesis (Appendix A) and the pieces every plant shares.
//!
//! * [`Dynamics`] — a continuous-time system `ẋ = f(x, u)`; implemented by
//!   [`pendulum::Pendulum`] (Appendix A.1), [`two_link::TwoLink`] (Appendix A.2) and
//!   [`double_integrator::DoubleIntegrator`] (a linear check system).
//! * [`rk4`] — fixed-step fourth-order Runge–Kutta with a zero-order-hold input.
//! * [`reward::Reward`] — Eq. 3.16 / 5.1 / 5.2 / 6.20, and the terms a task file adds
//!   (periodic, goal bonus, absolute action cost), with ∂ρ/∂x and ∂ρ/∂u.
//! * [`region::Region`] — a box or a ball in the state space: goals.
//! * [`operating_range::OperatingRange`] — the limits whose leaving ends a trial.
//! * [`start::StartDistribution`] — start states drawn from the run seed.
//! * [`sensor::Sensor`] — what is measured: the full state or encoder angles.
//! * [`task::Task`] — everything an experiment needs to know about a system: dynamics,
//!   sampling time, action bounds, reward, start states, trial length, how trials end.
//! * [`delay`] — sample-to-actuation delays (fixed or recorded) and when an action takes
//!   effect (direct or one-sample pipeline).
//! * [`Plant`] — the step function: saturate the action, integrate one sample period,
//!   wrap the angles.
//! * [`episode::Episode`] — one trial on the plant: reset to a start state, step one
//!   sample interval at a time until terminated or truncated.
//! * [`schedule::Schedule`] — the trials of a run: learning trials, greedy evaluations,
//!   start states, simulated learning time.
//! * [`safety`] — the plant side's safety pieces (saturation, operating range, the
//!   stale-action [`safety::Watchdog`]), for the simulated plant and Rust drivers.
//! * [`config`] — what every configuration section shares ([`config::ConfigError`],
//!   [`config::Choice`]) and the plant's own, `[run]` ([`config::RunConfig`]).
//!
//! Conventions: SI units; angles wrapped to [-π, π); actions saturated at the plant
//! whatever the caller sends; non-finite actions replaced by the safe action (zero).

pub mod angle;
pub mod config;
pub mod delay;
pub mod double_integrator;
pub mod episode;
pub mod operating_range;
pub mod pendulum;
pub mod region;
pub mod reward;
pub mod rk4;
pub mod safety;
pub mod schedule;
pub mod sensor;
pub mod start;
pub mod task;
pub mod two_link;

pub use reward::Reward;
pub use task::{Goal, OperatingRange, Simulation, SystemName, Task, TaskFile};

/// Largest state dimension of any system in this crate (the two-link arm has 4; a
/// finite-horizon learner appends time, which lives in the agent, not here).
pub const MAX_STATE: usize = 8;
/// Largest action dimension of any system in this crate.
pub const MAX_ACTION: usize = 4;

/// A continuous-time system `ẋ = f(x, u)`.
pub trait Dynamics: Send + Sync {
    /// Number of state components `n`.
    fn state_dim(&self) -> usize;
    /// Number of action components `m`.
    fn action_dim(&self) -> usize;
    /// Writes `f(x, u)` into `dx` (all slices have the lengths above).
    fn derivative(&self, x: &[f64], u: &[f64], dx: &mut [f64]);
}

/// The simulated plant: one sample period of a [`Task`]'s system per [`Plant::step`].
///
/// Every action passes the plant's [`safety::SafetyLayer`]: saturated to the task's bounds
/// (Eq. 6.11's `sat`), or, with a non-finite component, replaced by zero, the safe action;
/// both counted. A task with an [`OperatingRange`] ends its trial when the state leaves
/// the range (§6.4.2), a task with a [`Goal`] when the state reaches it:
/// [`Plant::terminated`].
pub struct Plant {
    task: std::sync::Arc<Task>,
    x: Vec<f64>,
    applied: Vec<f64>,
    safety: safety::SafetyLayer,
    /// The reward of the terminal transition — the operating range's penalty, the goal's
    /// reward — once the trial has ended there.
    terminated: Option<f64>,
}

impl Plant {
    /// A plant for `task`, at the task's first start state.
    ///
    /// # Panics
    /// If the task has no simulation ([`Task::simulation`]).
    pub fn new(task: std::sync::Arc<Task>) -> Self {
        task.simulation();
        let x = task.initial_states[0].clone();
        let applied = vec![0.0; task.action_dim()];
        Self {
            safety: safety::SafetyLayer::new(&task),
            task,
            x,
            applied,
            terminated: None,
        }
    }

    /// The task this plant simulates.
    pub fn task(&self) -> &Task {
        &self.task
    }

    /// Puts the plant at state `x0` (angles wrapped), with no action applied yet.
    pub fn reset(&mut self, x0: &[f64]) {
        self.x.copy_from_slice(x0);
        self.task.wrap_state(&mut self.x);
        self.applied.fill(0.0);
        self.terminated = None;
        self.safety.start_trial();
    }

    /// Whether the state has left the task's operating range or reached its goal: the
    /// trial is over (terminated), and the last step's reward was the range's penalty or
    /// the goal's reward.
    pub fn terminated(&self) -> bool {
        self.terminated.is_some()
    }

    /// Wraps the angles and checks the operating range and the goal after an integration.
    fn settle(&mut self) {
        self.task.wrap_state(&mut self.x);
        if self.terminated.is_none() {
            self.terminated = self.safety.check(&self.x);
        }
    }

    /// The current state `x_k`.
    pub fn state(&self) -> &[f64] {
        &self.x
    }

    /// The action applied by the last [`Plant::step`] (after saturation).
    pub fn applied_action(&self) -> &[f64] {
        &self.applied
    }

    /// The plant's safety layer (its counts; its watchdog, in real time).
    pub fn safety(&mut self) -> &mut safety::SafetyLayer {
        &mut self.safety
    }

    /// Applies `u` (saturated) for one sample period `Ts` and returns the reward
    /// `ρ(x_k, u_k)` of the transition: the state before it and the action actually applied
    /// (Eq. 3.16) — or the operating range's penalty if the transition leaves the range,
    /// the goal's reward if it reaches the goal.
    pub fn step(&mut self, u: &[f64]) -> f64 {
        self.safety.admit(u, &mut self.applied);
        let r = self.task.reward.reward(&self.x, &self.applied);
        let sim = self.task.simulation();
        let h = self.task.ts / sim.substeps as f64;
        for _ in 0..sim.substeps {
            rk4::step(sim.dynamics.as_ref(), &mut self.x, &self.applied, h);
        }
        self.settle();
        self.reward_of_transition(r)
    }

    /// One sample period with a sample-to-actuation delay of `delay` seconds
    /// (`0 ≤ delay < Ts`): the action in effect (the previous one; zero after a reset)
    /// stays for `delay`, then `u` for the rest of the period. The reward is that of
    /// [`Plant::step`], `ρ(x_k, u_k)` with the action in effect at the period's end. With
    /// `delay = 0` this is [`Plant::step`], bit for bit.
    pub fn step_delayed(&mut self, u: &[f64], delay: f64) -> f64 {
        if delay <= 0.0 {
            return self.step(u);
        }
        let x_k = self.x.clone();
        let u_prev = self.applied.clone();
        self.advance(&u_prev, delay);
        self.advance(u, self.task.ts - delay);
        self.reward_of_transition(self.task.reward.reward(&x_k, &self.applied))
    }

    /// `r`, or the terminal transition's reward once the trial has ended (the range's
    /// penalty, the goal's reward).
    pub fn reward_of_transition(&self, r: f64) -> f64 {
        self.terminated.unwrap_or(r)
    }

    /// Applies `u` (saturated) for `duration` seconds — part of a sample period, when an
    /// action arrives late in real time — with RK4 steps no longer than those of
    /// [`Plant::step`].
    pub fn advance(&mut self, u: &[f64], duration: f64) {
        self.safety.admit(u, &mut self.applied);
        if duration <= 0.0 {
            return;
        }
        let sim = self.task.simulation();
        let h_max = self.task.ts / sim.substeps as f64;
        let n = (duration / h_max).ceil().max(1.0) as usize;
        let h = duration / n as f64;
        for _ in 0..n {
            rk4::step(sim.dynamics.as_ref(), &mut self.x, &self.applied, h);
        }
        self.settle();
    }
}
