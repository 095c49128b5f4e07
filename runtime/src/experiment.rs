//! The in-process runner: one learning experiment (a "run": `trials` consecutive trials,
//! §3.6) with plant, observer and agent called directly, one sample at a time. Which
//! trial comes next is the run's schedule ([`plant::schedule`]); a trial is an episode
//! on the plant ([`plant::episode`]), as in the plant process.
//!
//! Per trial: the plant is reset to the task's start state; the agent acts on the
//! observer's estimate; the reward of each sample is `ρ(x_k, u_k)` of the true state and
//! the applied action (Eq. 3.16), and the trial's return is their sum. Every
//! `eval_every` trials one extra *greedy* trial is run from the same start state: no
//! exploration, no learning, and it does not count as learning time. A task with several
//! start states (§6.4.2) is evaluated from each of them, and the greedy return is their
//! mean. A trial that leaves the task's operating range (§6.4.2) or reaches its goal ends
//! there: the agent learns the transition as terminal, and the simulated time counts only
//! the samples run.
//!
//! What the observer sees is the plant's *sensor* output (`[observer] sensor`: the full
//! state, or encoder angles — [`plant::sensor`]); the true state stays with the plant and
//! serves only rewards and evaluation (ground truth), never the observer or the agent. The
//! agent acts on the observer's estimate. At a trial start the state is known (the plant
//! has just been put there), so the observer and the agent start from it.
//!
//! When the agent's action takes effect and what it acts on is the timing
//! (`observer.mode`, [`observer::timing`]): direct — on `x̂_k`, applied after the
//! sample-to-actuation delay (`run.delay_ms`, or drawn from `run.delay_from`) within the
//! interval — or predictive — on `x̂_{k+1|k}`, applied at the next sample instant
//! ([`plant::delay::Actuator`]).
//!
//! With a finite horizon (Chapter 4) a trial's return also counts the terminal reward of
//! the state it ends in, `τ_N(x_N) + Σ_k ρ(x_k, u_k)` (Eq. 4.1).

use std::convert::Infallible;
use std::sync::Arc;

use agent::Agent;
use agent::checkpoint::{Checkpoint, Origin, Snapshot};
use agent::horizon::Horizon;
use observer::timing::{Front, Sample as AtSample, act};
use plant::episode::{Episode, Step};
use plant::schedule::{Schedule, Trial};
use plant::sensor::Sensor;
use plant::{Plant, Task};

use crate::build::{actuator, front, sensor};
use crate::config::ExperimentConfig;
use crate::response::ResponseSample;
use crate::resumable::{ResumeError, resumable_delays};

/// The outcome of one learning trial.
#[derive(Clone, Debug, PartialEq)]
pub struct TrialRecord {
    /// Run index (0-based).
    pub run: u32,
    /// Trial number (1-based).
    pub trial: u32,
    /// Simulated learning time at the end of this trial \[s\].
    pub sim_time_s: f64,
    /// Sum of rewards of the trial, as learned (with exploration).
    pub ret: f64,
    /// Return of the greedy evaluation trial after this one, if one was run.
    pub greedy: Option<f64>,
}

/// One experiment's moving parts.
pub struct Experiment {
    task: Arc<Task>,
    /// The plant and when actions take effect (timing, delays), one trial at a time.
    episode: Episode,
    sensor: Sensor,
    /// The sensor's last measurement `y_k`.
    y: Vec<f64>,
    /// The observer in its timing.
    front: Front,
    agent: Box<dyn Agent>,
    horizon: Horizon,
    /// Which experiment and run this is (for checkpoints).
    origin: Origin,
    run: u32,
    /// Which trial comes next.
    schedule: Schedule,
    /// How far what the agent acted on was from the truth (learning trials).
    acted_on_error: ActedOnError,
}

/// Root-mean-square error, per state component, of the states the agent acted on against
/// the true states they stand for: `x̂_k − x_k` in direct timing, the prediction
/// `x̂_{k+1|k} − x_{k+1}` in predictive timing (angle errors wrapped).
#[derive(Clone, Debug, Default)]
pub struct ActedOnError {
    sum_sq: Vec<f64>,
    samples: u64,
}

impl ActedOnError {
    fn add(&mut self, task: &Task, acted_on: &[f64], truth: &[f64]) {
        self.sum_sq.resize(truth.len(), 0.0);
        for (i, (&a, &t)) in acted_on.iter().zip(truth).enumerate() {
            let e = if task.angle_mask[i] {
                plant::angle::wrap(a - t)
            } else {
                a - t
            };
            self.sum_sq[i] += e * e;
        }
        self.samples += 1;
    }

    /// The RMSE of each state component (empty before the first sample).
    pub fn rmse(&self) -> Vec<f64> {
        let n = self.samples.max(1) as f64;
        self.sum_sq.iter().map(|s| (s / n).sqrt()).collect()
    }
}

impl Experiment {
    /// Run `run` of the experiment `cfg` describes (all random streams derived from
    /// `cfg.run.seed` and `run`), its agent built from the configuration's learner.
    pub fn new(cfg: &ExperimentConfig, run: u32) -> Self {
        let task = cfg.task();
        let run_seed = agent::seed::run_seed(cfg.run().seed, run);
        let agent = agent::build(&task, cfg.learner(), run_seed);
        let o = cfg.observer();
        let sensor = sensor(&task, o, run_seed);
        Self {
            episode: Episode::new(Plant::new(task.clone()), actuator(&task, cfg, run_seed)),
            sensor,
            y: vec![0.0; task.state_dim()],
            front: front(&task, cfg),
            horizon: cfg.agent().horizon.of(&task),
            origin: cfg.origin(run),
            schedule: Schedule::new(
                task.clone(),
                cfg.run().trials,
                cfg.run().eval_every,
                run_seed,
            ),
            task,
            agent,
            run,
            acted_on_error: ActedOnError::default(),
        }
    }

    /// The agent's learned state after the last completed trial.
    pub fn checkpoint(&self) -> Checkpoint {
        let mut state = Snapshot::default();
        self.agent.save(&mut state);
        Checkpoint {
            origin: self.origin.clone(),
            trial: self.schedule.done(),
            sim_time_s: self.schedule.sim_time_s(),
            state,
        }
    }

    /// Run `run` of experiment `cfg`, continued after the trial checkpoint `c` was taken
    /// at. The checkpoint holds the agent's state only: the observer must be stateless
    /// across trials (the default sensor and observer).
    pub fn resume(cfg: &ExperimentConfig, run: u32, c: &Checkpoint) -> Result<Self, ResumeError> {
        if !cfg.observer().is_default() {
            return Err(ResumeError::Observer);
        }
        resumable_delays(cfg)?;
        let mut e = Self::new(cfg, run);
        c.restore(&cfg.origin(run), e.agent.as_mut())?;
        e.schedule.resume(c.trial, c.sim_time_s);
        Ok(e)
    }

    /// How far the states the agent acted on in the learning trials so far were from the
    /// truth.
    pub fn acted_on_error(&self) -> &ActedOnError {
        &self.acted_on_error
    }

    /// The agent (for inspection after learning).
    pub fn agent(&self) -> &dyn Agent {
        self.agent.as_ref()
    }

    /// Runs the next learning trial (and its greedy evaluation, if due); `None` when all
    /// trials are done.
    pub fn next_trial(&mut self) -> Option<TrialRecord> {
        let trial = self.schedule.next_trial()?;
        let ret = self.learning_trial(&trial.x0);
        let greedy = self
            .schedule
            .end_trial(self.episode.skipped())
            .map(|evaluation| self.evaluate(&evaluation));
        Some(TrialRecord {
            run: self.run,
            trial: trial.number,
            sim_time_s: self.schedule.sim_time_s(),
            ret,
            greedy,
        })
    }

    /// One learning trial from `x0`; returns its return (with the terminal reward of a
    /// finite horizon).
    fn learning_trial(&mut self, x0: &[f64]) -> f64 {
        let mut u = vec![0.0; self.task.action_dim()];
        // The agent starts from the plant's state as measured (angles wrapped), exactly as
        // it does over the wire.
        self.start(x0, false, &mut u);
        let mut ret = 0.0;
        let predictive = self.front.is_predictive();
        loop {
            let acted_on = self.front_state();
            let step = self.episode.step(&u);
            ret += step.reward;
            if predictive {
                // x̂_{k+1|k} against x_{k+1}.
                let x = self.episode.plant().state();
                self.acted_on_error.add(&self.task, &acted_on, x);
            }
            self.sample(&step, false, &mut u);
            if !predictive && !step.truncated {
                // x̂_{k+1} against x_{k+1}.
                let x = self.front.acted_on();
                let truth = self.episode.plant().state();
                self.acted_on_error.add(&self.task, x, truth);
            }
            if step.ended() {
                break;
            }
        }
        ret + self.final_reward()
    }

    /// A trial's start: the plant is put at `x0`, the observer and the agent start from it
    /// (the state is known there); the agent's first action into `u`. In predictive timing
    /// that answer is the first interval's action `u_0`, and the agent, told so, answers
    /// `u_1` into `u` ([`observer::timing`], trial start).
    fn start(&mut self, x0: &[f64], greedy: bool, u: &mut [f64]) {
        let (front, agent) = (&mut self.front, self.agent.as_mut());
        let Ok(()) = self.episode.start(x0, u, |e, primed, u| {
            start_sample(front, agent, e, primed, greedy, u);
            Ok::<(), Infallible>(())
        });
    }

    /// Sample `k + 1` after interval `k` (`step`): measure, estimate, let the agent act
    /// (learn, unless `greedy`), its answer into `u`.
    fn sample(&mut self, step: &Step, greedy: bool, u: &mut [f64]) {
        let (plant, actuator) = (self.episode.plant(), self.episode.actuator());
        self.sensor.measure(plant.state(), &mut self.y);
        let t = self.front.sample(&AtSample {
            step: step.sample,
            start: false,
            primed: false,
            end: step.ended(),
            terminal: step.terminated,
            y: &self.y,
            reward: step.reward,
            u_applied: plant.applied_action(),
            u_next: actuator.next_action().unwrap_or(&[]),
        });
        act(self.agent.as_mut(), greedy, &t, u);
    }

    /// `τ_N(x_N)` of the plant's state after a finite horizon's last sample (Eq. 4.1); 0
    /// for an infinite horizon.
    fn final_reward(&self) -> f64 {
        self.horizon
            .final_reward(&self.task.reward, self.episode.plant().state())
    }

    /// The greedy policy's return without learning: the mean over the task's start
    /// states of one trial from each.
    pub fn greedy_return(&mut self) -> f64 {
        let evaluation = self.schedule.evaluation();
        self.evaluate(&evaluation)
    }

    /// The mean return of the greedy trials of an evaluation.
    fn evaluate(&mut self, evaluation: &[Trial]) -> f64 {
        let total: f64 = evaluation
            .iter()
            .map(|t| self.greedy_return_from(&t.x0))
            .sum();
        total / evaluation.len() as f64
    }

    /// The return of one trial from `x0` under the greedy policy, without learning.
    pub fn greedy_return_from(&mut self, x0: &[f64]) -> f64 {
        let rewards: f64 = self.greedy_trajectory(x0).iter().map(|s| s.reward).sum();
        rewards + self.final_reward()
    }

    /// One greedy trial from `x0`: the time response of the current policy (until the
    /// trial's end or until it terminates: the system left its operating range or reached
    /// its goal).
    pub fn greedy_trajectory(&mut self, x0: &[f64]) -> Vec<ResponseSample> {
        let mut u = vec![0.0; self.task.action_dim()];
        self.start(x0, true, &mut u);
        let mut acted_on = self.front_state();
        let mut out = Vec::with_capacity(self.task.steps_per_trial());
        loop {
            let step = self.episode.step(&u);
            out.push(ResponseSample {
                t: (step.sample - 1) as f64 * self.task.ts,
                x: std::mem::take(&mut acted_on),
                u: self.episode.plant().applied_action().to_vec(),
                reward: step.reward,
            });
            self.sample(&step, true, &mut u);
            if step.ended() {
                return out;
            }
            acted_on = self.front_state();
        }
    }

    /// The state the agent last acted on.
    fn front_state(&self) -> Vec<f64> {
        self.front.acted_on().to_vec()
    }
}

/// The start state as a sample — the trial's start, or (`primed`, predictive timing) the
/// start again with the first interval's action — and the agent's answer into `u`.
fn start_sample(
    front: &mut Front,
    agent: &mut dyn Agent,
    e: &Episode,
    primed: bool,
    greedy: bool,
    u: &mut [f64],
) {
    let t = front.sample(&AtSample {
        step: 0,
        start: !primed,
        primed,
        end: false,
        terminal: false,
        y: e.plant().state(),
        reward: 0.0,
        u_applied: e.plant().applied_action(),
        u_next: e.actuator().next_action().unwrap_or(&[]),
    });
    act(agent, greedy, &t, u);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Overrides, resolve};
    use observer::config::{ObserverKind, SensorKind};

    fn angle_config(observer: ObserverKind, noise: &str) -> ExperimentConfig {
        let text = format!("[observer]\nnoise_std = {noise}\n");
        resolve(
            Some((std::path::Path::new("o.toml"), &text)),
            &Overrides {
                trials: Some(3),
                runs: Some(1),
                sensor: Some(SensorKind::Angle),
                observer: Some(observer),
                ..Default::default()
            },
        )
        .unwrap()
    }

    /// With an encoder the agent acts on quantised angles, never on the true state; the
    /// run stays deterministic with sensor noise.
    #[test]
    fn the_agent_sees_encoder_angles_only() {
        for o in [ObserverKind::FiniteDifference, ObserverKind::Predictive] {
            let cfg = angle_config(o, "0.0");
            let mut e = Experiment::new(&cfg, 0);
            while e.next_trial().is_some() {}
            let q = std::f64::consts::TAU / 4096.0;
            let traj = e.greedy_trajectory(&[std::f64::consts::PI, 0.0]);
            for s in &traj[1..] {
                let counts = s.x[0] / q;
                assert!((counts - counts.round()).abs() < 1e-6, "{o}: {:?}", s.x);
                assert!(s.x.iter().all(|v| v.is_finite()));
            }
            let noisy = |run| {
                let mut e = Experiment::new(&angle_config(o, "0.003"), run);
                (0..3)
                    .map(|_| e.next_trial().unwrap().ret)
                    .collect::<Vec<_>>()
            };
            assert_eq!(noisy(0), noisy(0));
            assert_ne!(noisy(0), noisy(1));
        }
    }
}
