//! One trial on the simulated plant, in the manner of a Gymnasium environment:
//! [`Episode::reset`] puts the plant at a start state, [`Episode::step`] runs one sample
//! interval and says what came of it ([`Step`]: the reward, whether the trial ended
//! because the state left the operating range (§6.4.2) or reached the goal —
//! *terminated*: nothing follows, the learners bootstrap nothing past it — or because
//! its time is up — *truncated*: the state goes on, the learners bootstrap through it).
//!
//! The trial's start is sampled once, or, in predictive timing, twice
//! ([`Episode::start`]): the agent's answer to the start state is the first interval's
//! action `u_0`, and told so (the start sampled again, *primed*) it answers `u_1`
//! ([`crate::delay::Actuator::prime`]).
//!
//! [`TimeLimit`] counts a trial's samples; it serves every runner of trials, also one
//! whose system is not simulated here (an external driver's).

use crate::delay::Actuator;
use crate::{MAX_STATE, Plant};

/// What one sample interval came to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// The sample the interval led to: `k + 1` after interval `k`.
    pub sample: usize,
    /// The interval's reward `ρ(x_k, u_k)` (Eq. 3.16), or the operating range's penalty,
    /// or the goal's reward.
    pub reward: f64,
    /// The state left the operating range or reached the goal: the trial ends here, at a
    /// terminal state.
    pub terminated: bool,
    /// The trial's last sample: its time is up.
    pub truncated: bool,
}

impl Step {
    /// Whether the trial ends with this sample.
    pub fn ended(&self) -> bool {
        self.terminated || self.truncated
    }
}

/// The samples of one trial: which interval comes next, of how many.
#[derive(Clone, Copy, Debug)]
pub struct TimeLimit {
    /// Sample intervals per trial.
    steps: usize,
    /// Intervals run so far this trial.
    run: usize,
}

impl TimeLimit {
    /// A trial of `steps` sample intervals.
    pub fn new(steps: usize) -> Self {
        Self { steps, run: 0 }
    }

    /// A trial starts.
    pub fn reset(&mut self) {
        self.run = 0;
    }

    /// The next interval has been run, with `reward`; `terminated`: the state left the
    /// operating range or reached the goal.
    pub fn step(&mut self, reward: f64, terminated: bool) -> Step {
        debug_assert!(self.run < self.steps, "the trial has ended");
        self.run += 1;
        Step {
            sample: self.run,
            reward,
            terminated,
            truncated: self.run == self.steps,
        }
    }

    /// The samples of the trial not run (all of them run unless it was terminated).
    pub fn skipped(&self) -> usize {
        self.steps - self.run
    }
}

/// The simulated plant with its actuation, one trial at a time
/// ([module documentation](self)).
pub struct Episode {
    plant: Plant,
    /// When actions take effect (timing, delays).
    actuator: Actuator,
    limit: TimeLimit,
}

impl Episode {
    /// Trials of `plant`'s task, actions taking effect as `actuator` says.
    pub fn new(plant: Plant, actuator: Actuator) -> Self {
        let limit = TimeLimit::new(plant.task().steps_per_trial());
        Self {
            plant,
            actuator,
            limit,
        }
    }

    /// A trial starts: the plant at `x0` (angles wrapped), no action applied yet; in
    /// predictive timing the safe action held until [`Actuator::prime`].
    pub fn reset(&mut self, x0: &[f64]) {
        self.plant.reset(x0);
        self.actuator.reset();
        self.limit.reset();
    }

    /// [`Episode::reset`], then the trial's start: `answer(episode, primed, u)` writes the
    /// agent's answer to the start sample into `u` — once (`primed = false`), and in
    /// predictive timing, with that answer primed as the first interval's action, once
    /// more (`primed = true`). `u` is then the action for the first interval.
    pub fn start<E>(
        &mut self,
        x0: &[f64],
        u: &mut [f64],
        mut answer: impl FnMut(&Self, bool, &mut [f64]) -> Result<(), E>,
    ) -> Result<(), E> {
        self.reset(x0);
        answer(self, false, u)?;
        if self.actuator.is_pipelined() {
            self.actuator.prime(u);
            answer(self, true, u)?;
        }
        Ok(())
    }

    /// One sample interval after the agent answered `u` ([`Actuator::interval`]).
    pub fn step(&mut self, u: &[f64]) -> Step {
        let r = self.actuator.interval(&mut self.plant, u);
        self.limit.step(r, self.plant.terminated())
    }

    /// One sample interval integrated by `integrate` (in real time: piecewise, as actions
    /// arrive); its reward is `ρ(x_k, u)` with the action in effect at its end, or the
    /// terminal transition's reward. Allocates nothing.
    pub fn step_with(&mut self, integrate: impl FnOnce(&mut Plant)) -> Step {
        let n = self.plant.task().state_dim();
        let mut x_k = [0.0; MAX_STATE];
        x_k[..n].copy_from_slice(self.plant.state());
        integrate(&mut self.plant);
        let p = &self.plant;
        let r = p.reward_of_transition(p.task().reward.reward(&x_k[..n], p.applied_action()));
        self.limit.step(r, p.terminated())
    }

    /// The plant.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The plant, to integrate or to ask its safety layer.
    pub fn plant_mut(&mut self) -> &mut Plant {
        &mut self.plant
    }

    /// When actions take effect.
    pub fn actuator(&self) -> &Actuator {
        &self.actuator
    }

    /// The samples of the trial not run (it ended early).
    pub fn skipped(&self) -> usize {
        self.limit.skipped()
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::delay::Delays;
    use crate::{SystemName, Task};

    fn episode(system: SystemName, pipelined: bool) -> Episode {
        let task = Arc::new(Task::new(system));
        let m = task.action_dim();
        Episode::new(
            Plant::new(task),
            Actuator::new(m, pipelined, Delays::fixed(0.0)),
        )
    }

    /// A trial runs its samples and is truncated at the last; the start is answered
    /// twice in predictive timing, the first answer primed.
    #[test]
    fn a_trial_is_truncated_at_its_last_sample_and_primed_in_predictive_timing() {
        for pipelined in [false, true] {
            let mut e = episode(SystemName::Pendulum, pipelined);
            let mut calls = Vec::new();
            let mut u = [0.0];
            let ok: Result<(), ()> = e.start(&[3.0, 0.0], &mut u, |e, primed, u| {
                calls.push((primed, e.actuator().next_action().map(<[f64]>::to_vec)));
                u[0] = 1.0;
                Ok(())
            });
            ok.unwrap();
            let want = if pipelined {
                vec![(false, Some(vec![0.0])), (true, Some(vec![1.0]))]
            } else {
                vec![(false, None)]
            };
            assert_eq!(calls, want);
            let steps = e.plant().task().steps_per_trial();
            let samples: Vec<Step> = (0..steps).map(|_| e.step(&u)).collect();
            assert!(samples[..steps - 1].iter().all(|s| !s.ended()));
            assert!(samples[steps - 1].truncated && !samples[steps - 1].terminated);
            assert_eq!(samples[steps - 1].sample, steps);
            assert_eq!(e.skipped(), 0);
        }
    }

    /// Leaving the operating range terminates the trial with the penalty; the samples
    /// not run are counted.
    #[test]
    fn leaving_the_operating_range_terminates_the_trial() {
        let mut e = episode(SystemName::Arm64, false);
        e.reset(&[1.19, 0.0, 0.0, 0.0]);
        let steps = e.plant().task().steps_per_trial();
        let push = [0.1, 0.0];
        let s = std::iter::repeat_with(|| e.step(&push))
            .find(Step::ended)
            .unwrap();
        assert!(s.terminated && s.reward < -1e4, "{s:?}");
        assert_eq!(e.skipped(), steps - s.sample);
        assert!(e.skipped() > 0);
    }

    /// Reaching the goal terminates the trial with the goal's reward, in place of ρ;
    /// elsewhere the reward is ρ and the trial runs to its time limit (truncated).
    #[test]
    fn reaching_the_goal_terminates_the_trial_with_its_reward() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../examples/tasks/pendulum-reach.toml");
        let task = Arc::new(Task::from_file(&path).unwrap());
        let mut e = Episode::new(
            Plant::new(task.clone()),
            Actuator::new(1, false, Delays::fixed(0.0)),
        );
        e.reset(&[0.05, 0.0]);
        let s = e.step(&[0.0]);
        assert!(s.terminated && !s.truncated && s.reward == 10.0, "{s:?}");
        assert_eq!(e.skipped(), task.steps_per_trial() - 1);
        e.reset(&[std::f64::consts::PI, 0.0]);
        let x0 = e.plant().state().to_vec();
        let first = e.step(&[0.0]);
        assert_eq!(first.reward, task.reward.reward(&x0, &[0.0]));
        let last = std::iter::repeat_with(|| e.step(&[0.0]))
            .find(Step::ended)
            .unwrap();
        assert!(last.truncated && !last.terminated, "{last:?}");
    }
}
