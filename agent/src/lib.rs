//! Learning agents of Grondman's thesis: function approximators (§3.5), the
//! actor-critic algorithms SAC, MLAC and RMAC (Chapter 3, Algorithms 1–3; with a
//! finite horizon, Chapter 4, Algorithms 4–6) and the critic-only VGBP (Chapter 6,
//! Algorithm 7) and SARSA (§6.2).
//!
//! * [`approx`] — RBF ([`approx::rbf`]), LLR ([`approx::llr`]) and tile coding
//!   ([`approx::tiles`]) behind the [`approx::Approximator`] traits.
//! * [`actor_critic`] — Template 2.1, the loop every algorithm shares; [`sac`],
//!   [`mlac`], [`rmac`], [`vgbp`] — what each algorithm does differently; [`critic`] —
//!   the critic and its learning rule, TD(λ) or [`lstd`]; [`model`] — the learned
//!   process model; [`step_size`] — a learning rate's schedule over the trials
//!   (constant, or decaying as Eq. 2.21–2.22 ask); [`explore`] — Gaussian
//!   exploration; [`sarsa`] — the discrete-action baseline; [`plan`] — MLAC's actions
//!   planned with its learned model by the cross-entropy method, [`ilqr`] — by the
//!   iterative LQR (beyond the thesis, chosen by `[planning]`), which sees the
//!   operating range as a [`barrier`];
//!   [`lqr`] — near the reference, a regulator of that model (beyond the thesis,
//!   `[lqr]`).
//! * [`horizon`] — infinite or finite horizon (Chapter 4: time as an input, terminal
//!   reward; SAC-FH, MLAC-FH, RMAC-FH are the shared step with a finite horizon).
//! * [`config`] — the agent's part of the configuration, [`preset`] — the thesis's
//!   values of it, [`learner`] — it resolved into one type per algorithm, [`build()`] —
//!   from that to a running agent; [`checkpoint`] — the
//!   agent's learned state saved at a trial's end and restored.
//!
//! An [`Agent`] is a plain step function; it knows nothing about processes or
//! transport.

pub mod actor_critic;
pub mod approx;
pub mod barrier;
mod build;
pub mod checkpoint;
pub mod config;
pub mod critic;
pub mod explore;
pub mod horizon;
pub mod ilqr;
pub mod learner;
pub mod lqr;
pub mod lstd;
pub mod mlac;
pub mod model;
pub mod plan;
pub mod preset;
pub mod rmac;
pub mod sac;
pub mod sarsa;
pub mod seed;
pub mod step_size;
#[cfg(test)]
mod testing;
pub mod vgbp;

pub use build::build;

/// A learning controller, driven one sample at a time.
///
/// Per trial: [`Agent::start_trial`] with `x_0` gives `u_0`; then for every sample
/// [`Agent::learn`] with `r_{k+1} = ρ(x_k, u_k)` and `x_{k+1}` learns from the transition
/// and — unless it is the trial's last — gives `u_{k+1}`. A transition that leaves a
/// task's operating range (§6.4.2), or reaches its goal — a *termination* — ends the
/// trial through [`Agent::learn_terminal`] instead: nothing is bootstrapped past it. The
/// time limit is no termination (a *truncation*): the trial's last transition is learned
/// by [`Agent::learn`] without a next action, bootstrapping through it as through any
/// other.
pub trait Agent: Send + checkpoint::Persist {
    /// Starts a trial in `x0` (clears eligibility traces) and writes the first action.
    fn start_trial(&mut self, x0: &[f64], u: &mut [f64]);
    /// Learns from the last transition; writes the next action if `u` is given.
    fn learn(&mut self, r: f64, x_next: &[f64], u: Option<&mut [f64]>);
    /// Learns from a transition into a terminal state — the system left its operating
    /// range and the trial is over: the value beyond it is zero, `V(x_{k+1}) = 0`.
    fn learn_terminal(&mut self, r: f64, x_next: &[f64]);
    /// The greedy action in `x` at sample `k` of a trial — no exploration, no learning.
    /// `u_prev` is the action applied in the previous sample (zero at a trial start); `k`
    /// matters to a finite-horizon agent, whose policy is time-varying (Chapter 4).
    fn greedy(&self, k: usize, x: &[f64], u_prev: &[f64], u: &mut [f64]);
    /// A greedy trial begins: whatever the policy carries from one sample to the next
    /// within a trial (a planner's last plan) is dropped. Nothing by default.
    fn start_greedy_trial(&mut self) {}
    /// `(name, stored, capacity)` of each memory-based (LLR) approximator.
    fn memories(&self) -> Vec<(&'static str, usize, usize)>;
}
