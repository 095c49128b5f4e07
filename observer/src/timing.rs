//! Timing: what the agent acts on, when its action takes effect, and what it learns from
//! (`observer.mode`; thesis §6.4.1; docs/latency.md).
//!
//! A [`Front`] turns each sample the plant reports — the measurement `y_k`, the plant's
//! reward, the action applied over the last interval and, in predictive timing, the
//! action the plant applies from `t_k` on — into one call of the agent ([`ToAgent`]),
//! which [`act`] performs. `rig learn` (in process) and the observer and agent processes
//! of `rig run` share both, so the two drivers learn the same numbers.
//!
//! **Direct** (`mode = "direct"`): the agent acts on `x̂_k`; its answer `u_k` takes effect
//! within `[t_k, t_{k+1})` after the compute and transport delay. Its transitions are
//! `(x̂_k, u_k) → x̂_{k+1}` with the plant's reward `ρ(x_k, u_k)` (Eq. 3.16), as in the
//! thesis's simulations — or, where the plant cannot know it (its reward is NaN: an
//! external driver that measures positions only), `ρ(x̂_k, u_k)` of the estimate the agent
//! acted on, as on the physical setup (§6.4.1).
//!
//! **Predictive** (`mode = "predictive"`): a one-sample action pipeline. At `t_k` the
//! plant applies `u_k`, which the agent computed during the previous interval, for the
//! whole interval. The observer corrects its estimate with `y_k` (giving `x̂_k`) and
//! predicts `x̂_{k+1|k} = f̂(x̂_k, u_k)` with its process model; the agent acts on that
//! prediction and its answer `u_{k+1}` is applied at `t_{k+1}` — a delay below `Ts` does
//! not reach the plant. The choices at the edges:
//!
//! * **Trial start.** The plant has just been put at `x_0` and the system rests there
//!   until the trial's clock starts, so the first action can be computed from the known
//!   start state without a deadline: the plant reports `x_0` ([`Sample::start`]), the
//!   agent starts its trial there and answers `u_0`, which the plant holds for the first
//!   interval; then the plant reports `x_0` again with `u_0` as the action it will apply
//!   ([`Sample::primed`]) and the agent learns `(x_0, u_0) → x̂_{1|0}` and answers `u_1`.
//!   A trial has `N` agent transitions, as in direct timing. (With zero held over the
//!   first interval instead, every swing-up starts one sample late: about −45 of final
//!   return on the pendulum, the reward of one more sample at the bottom.)
//! * **Transitions and reward.** The agent's transition is
//!   `(x̂_{k|k−1}, u_k) → x̂_{k+1|k}`. The plant's reward `ρ(x_k, u_k)` (Eq. 3.16: the state
//!   *before* the interval and the action applied over it) is not known when `u_{k+1}` must
//!   be chosen, so the controller computes it from the known reward function, as on the
//!   physical setup: `r = ρ(x̂_k, u_k)` with `x̂_k` the corrected estimate of `x_k` — the
//!   best estimate of `x_k` available at `t_k`. The learning curves (`returns.csv`)
//!   still sum the plant's true rewards.
//! * **Trial end.** The agent's last transition, `(x̂_{N−1|N−2}, u_{N−1}) → x̂_{N|N−1}`,
//!   is learned at `t_{N−1}` without a next action ([`Call::Last`]); the plant's last
//!   sample `N` only closes the trial ([`Call::Hold`]).
//! * **Terminal transitions** (the state left the operating range at `t_j`, §6.4.2, or
//!   reached the goal): the pending transition `(x̂_{j|j−1}, u_j)` is learned as terminal
//!   with the plant's reward of it (the range's penalty, the goal's reward) and next state
//!   `x̂_{j+1|j}`, the model's continuation (the value beyond is zero whatever it is).
//! * **Greedy evaluation** runs the same pipeline without exploration or learning: the
//!   greedy action at `x̂_{k+1|k}` for sample `k + 1`.
//!
//! Predictive timing needs a process model (`observer = "predictive"`) and an infinite
//! horizon (a finite-horizon agent's time index would be one sample off the plant's).

use std::sync::Arc;

use agent::Agent;
use plant::Task;

use crate::Observer;

/// What the plant reports at sample instant `t_k`.
#[derive(Clone, Copy, Debug)]
pub struct Sample<'a> {
    /// Sample index within the trial (0: the start state).
    pub step: usize,
    /// The trial's start: `y` is the known start state `x_0`.
    pub start: bool,
    /// Predictive timing, right after the start: `y` is `x_0` again and `u_next` the first
    /// interval's action, the answer to the start sample.
    pub primed: bool,
    /// The trial's last sample (its `N`-th, or the one that left the operating range or
    /// reached the goal).
    pub end: bool,
    /// The trial terminated here: the state left the operating range or reached the goal
    /// (with `end`).
    pub terminal: bool,
    /// The measurement `y_k`.
    pub y: &'a [f64],
    /// The plant's reward of the interval before this sample (the range's penalty if it
    /// was left, the goal's reward if it was reached).
    pub reward: f64,
    /// The action applied over the interval before this sample.
    pub u_applied: &'a [f64],
    /// Predictive timing: the action the plant applies from this instant on (as sent).
    pub u_next: &'a [f64],
}

/// Which agent call a sample makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Call {
    /// [`Agent::start_trial`] (greedy: the greedy action).
    Start,
    /// [`Agent::learn`] with a next action (greedy: the greedy action).
    Learn,
    /// [`Agent::learn`] of the trial's last transition, without a next action.
    Last,
    /// [`Agent::learn_terminal`].
    Terminal,
    /// Nothing to learn or act on: the agent's trial is already closed.
    Hold,
}

/// One agent call: what the agent acts on and learns from.
#[derive(Clone, Copy, Debug)]
pub struct ToAgent<'a> {
    /// The call.
    pub call: Call,
    /// The reward of the transition being learned.
    pub reward: f64,
    /// The state the agent acts on / the transition's next state.
    pub x: &'a [f64],
    /// The action in effect over the interval `x` starts (greedy's `u_prev`).
    pub u_prev: &'a [f64],
    /// The sample at which the agent's action will be applied (greedy's `k`).
    pub step: usize,
}

/// Performs `t` on `agent` — learning, or the greedy policy without learning if `greedy`
/// — and writes the action into `u` (zero where there is none to apply).
pub fn act(agent: &mut dyn Agent, greedy: bool, t: &ToAgent, u: &mut [f64]) {
    match (greedy, t.call) {
        (true, Call::Start) => {
            agent.start_greedy_trial();
            agent.greedy(t.step, t.x, t.u_prev, u);
        }
        (true, Call::Learn) => agent.greedy(t.step, t.x, t.u_prev, u),
        (true, _) | (false, Call::Hold) => u.fill(0.0),
        (false, Call::Start) => agent.start_trial(t.x, u),
        (false, Call::Learn) => agent.learn(t.reward, t.x, Some(u)),
        (false, Call::Last) => {
            agent.learn(t.reward, t.x, None);
            u.fill(0.0);
        }
        (false, Call::Terminal) => {
            agent.learn_terminal(t.reward, t.x);
            u.fill(0.0);
        }
    }
}

/// The observer together with the timing ([module documentation](self)).
pub struct Front {
    observer: Box<dyn Observer>,
    task: Arc<Task>,
    predictive: bool,
    /// What the agent acts on.
    x: Vec<f64>,
    /// The action in effect (made safe as the plant makes it).
    u: Vec<f64>,
    /// Predictive: whether the agent's trial is closed (its last transition learned).
    closed: bool,
}

impl Front {
    /// `observer` in direct timing, or in predictive timing (`predictive`; the observer
    /// must have a process model, [`Observer::predict_next`]).
    pub fn new(task: Arc<Task>, observer: Box<dyn Observer>, predictive: bool) -> Self {
        Self {
            x: vec![0.0; task.state_dim()],
            u: vec![0.0; task.action_dim()],
            observer,
            task,
            predictive,
            closed: false,
        }
    }

    /// Whether the timing is predictive (the agent acts on `x̂_{k+1|k}`).
    pub fn is_predictive(&self) -> bool {
        self.predictive
    }

    /// The state the agent was last given to act on.
    pub fn acted_on(&self) -> &[f64] {
        &self.x
    }

    /// The agent call of sample `s`.
    pub fn sample(&mut self, s: &Sample) -> ToAgent<'_> {
        if !self.predictive {
            return self.direct(s);
        }
        // The action applied from t_k, made safe as the plant does.
        self.task.saturate(s.u_next, &mut self.u);
        let mut reward = s.reward;
        if s.start {
            // The start state is known: the agent acts on it (u_0).
            self.observer.reset(s.y);
            self.closed = false;
            self.x.copy_from_slice(s.y);
            return ToAgent {
                call: Call::Start,
                reward,
                x: &self.x,
                u_prev: &self.u,
                step: 0,
            };
        }
        let call = if s.primed {
            // (x_0, u_0) → x̂_{1|0}: self.x still holds x_0.
            reward = self.task.reward.reward(&self.x, &self.u);
            Call::Learn
        } else {
            let x_k = self.observer.update(s.y, s.u_applied);
            if self.closed || (s.end && !s.terminal) {
                self.closed = true;
                Call::Hold
            } else if s.terminal {
                self.closed = true;
                Call::Terminal
            } else {
                // ρ(x̂_k, u_k): the reward of the interval starting now, from the estimate.
                reward = self.task.reward.reward(x_k, &self.u);
                if s.step + 1 == self.task.steps_per_trial() {
                    self.closed = true;
                    Call::Last
                } else {
                    Call::Learn
                }
            }
        };
        let next = self
            .observer
            .predict_next(&self.u)
            .expect("predictive timing needs an observer with a process model");
        self.x.copy_from_slice(next);
        ToAgent {
            call,
            reward,
            x: &self.x,
            u_prev: &self.u,
            step: s.step + 1,
        }
    }

    /// Direct timing: the agent acts on `x̂_k` and learns the plant's reward — or, where
    /// the plant cannot know it (NaN: a driver that measures positions only),
    /// `ρ(x̂_k, u_k)` from the estimate it acted on, as on the physical setup (§6.4.1).
    fn direct(&mut self, s: &Sample) -> ToAgent<'_> {
        let mut reward = s.reward;
        let call = if s.start {
            self.observer.reset(s.y);
            self.x.copy_from_slice(s.y);
            self.u.fill(0.0);
            Call::Start
        } else {
            if reward.is_nan() {
                reward = self.task.reward.reward(&self.x, s.u_applied);
            }
            self.x
                .copy_from_slice(self.observer.update(s.y, s.u_applied));
            self.u.copy_from_slice(s.u_applied);
            if s.terminal {
                Call::Terminal
            } else if s.end {
                Call::Last
            } else {
                Call::Learn
            }
        };
        ToAgent {
            call,
            reward,
            x: &self.x,
            u_prev: &self.u,
            step: s.step,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predictive::{Predictive, PredictiveModel};
    use plant::SystemName;

    fn front(predictive: bool) -> (Arc<Task>, Front) {
        let task = Arc::new(Task::new(SystemName::Pendulum));
        let o = Box::new(Predictive::new(task.clone(), PredictiveModel::Known, 1.0));
        (task.clone(), Front::new(task, o, predictive))
    }

    fn sample<'a>(
        step: usize,
        end: bool,
        terminal: bool,
        y: &'a [f64],
        u: &'a [f64],
    ) -> Sample<'a> {
        Sample {
            step,
            start: step == 0,
            primed: false,
            end,
            terminal,
            y,
            reward: -7.0,
            u_applied: u,
            u_next: u,
        }
    }

    /// Predictive timing: the agent starts in x_0 (its answer is the first interval's
    /// action u_0), then learns (x_0, u_0) → x̂_{1|0}; its last transition is learned at
    /// sample N − 1, the plant's last sample only closes the trial; rewards are ρ(x̂_k, u_k).
    #[test]
    fn predictive_calls_over_a_trial() {
        let (task, mut f) = front(true);
        let n = task.steps_per_trial();
        let (x0, u0, u) = ([1.0, 0.0], [-3.0], [2.0]);
        let t = f.sample(&sample(0, false, false, &x0, &[0.0]));
        assert_eq!((t.call, t.step, t.x), (Call::Start, 0, &x0[..]));
        let primed = Sample {
            primed: true,
            start: false,
            ..sample(0, false, false, &x0, &u0)
        };
        let t = f.sample(&primed);
        assert_eq!((t.call, t.step, t.u_prev), (Call::Learn, 1, &u0[..]));
        assert_eq!(t.reward, task.reward.reward(&x0, &u0));
        // x̂_{1|0} = f(x_0, −3): 1 rad from upright, still falling away from it.
        assert!(t.x[1] > 0.0 && t.x[0] > 1.0, "{:?}", t.x);
        let mut free = Front::new(
            task.clone(),
            Box::new(Predictive::new(task.clone(), PredictiveModel::Known, 1.0)),
            true,
        );
        free.sample(&sample(0, false, false, &x0, &[0.0]));
        let pushed = t.x[1];
        let t = free.sample(&Sample {
            primed: true,
            start: false,
            ..sample(0, false, false, &x0, &[0.0])
        });
        assert!(t.x[1] > pushed, "u_0 = −3 V slows the fall");
        for k in 1..n {
            let t = f.sample(&sample(k, false, false, &x0, &u));
            let want = if k + 1 == n { Call::Last } else { Call::Learn };
            assert_eq!((t.call, t.step), (want, k + 1));
            assert_ne!(t.reward, -7.0);
        }
        let t = f.sample(&sample(n, true, false, &x0, &u));
        assert_eq!(t.call, Call::Hold);
        // A terminal sample before the end closes the agent's pending transition.
        f.sample(&sample(0, false, false, &x0, &[0.0]));
        f.sample(&Sample {
            primed: true,
            start: false,
            ..sample(0, false, false, &x0, &u0)
        });
        let t = f.sample(&sample(1, true, true, &x0, &u));
        assert_eq!((t.call, t.reward), (Call::Terminal, -7.0));
    }

    /// Direct timing: the agent acts on x̂_k and learns the plant's reward.
    #[test]
    fn direct_calls_over_a_trial() {
        let (task, mut f) = front(false);
        let n = task.steps_per_trial();
        let (x0, u) = ([1.0, 0.0], [2.0]);
        let t = f.sample(&sample(0, false, false, &x0, &[0.0]));
        assert_eq!((t.call, t.step, t.x), (Call::Start, 0, &x0[..]));
        let t = f.sample(&sample(1, false, false, &x0, &u));
        assert_eq!((t.call, t.reward, t.u_prev), (Call::Learn, -7.0, &u[..]));
        let t = f.sample(&sample(n, true, false, &x0, &u));
        assert_eq!(t.call, Call::Last);
    }

    /// Direct timing with a plant that cannot know the reward (a driver measuring angles
    /// only: NaN): the agent learns ρ(x̂_k, u_k) of the estimate it acted on at t_k; a
    /// terminal penalty, which the plant does know, is passed on.
    #[test]
    fn direct_timing_computes_an_unknown_reward_from_the_estimate() {
        let (task, mut f) = front(false);
        let (x0, u) = ([3.0, 0.0], [2.0]);
        let unknown = |step, terminal, y| Sample {
            reward: f64::NAN,
            ..sample(step, false, terminal, y, &u)
        };
        f.sample(&sample(0, false, false, &x0, &[0.0]));
        let t = f.sample(&unknown(1, false, &[2.9, f64::NAN]));
        assert_eq!(t.reward, task.reward.reward(&x0, &u));
        let x1 = t.x.to_vec();
        assert!(x1.iter().all(|v| v.is_finite()) && x1[1] < 0.0, "{x1:?}");
        let t = f.sample(&unknown(2, false, &[2.7, f64::NAN]));
        assert_eq!(t.reward, task.reward.reward(&x1, &u));
        let t = f.sample(&sample(3, true, true, &[2.5, f64::NAN], &u));
        assert_eq!((t.call, t.reward), (Call::Terminal, -7.0));
    }
}
