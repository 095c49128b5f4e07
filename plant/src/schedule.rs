//! The trial schedule of a run (§3.6): which trial comes next — a learning trial or a
//! greedy evaluation trial, from which start state, with which number and at which
//! simulated time.
//!
//! A run is `trials` consecutive learning trials; learning trial `n` (from 1) starts from
//! the task's start state `n − 1` modulo their number (§6.4.2 cycles through several), or,
//! when the task has a start distribution, from its draw for trial `n` of the run seed
//! ([`crate::start`]). Every `eval_every` learning trials (0: never) an evaluation
//! follows: one greedy trial from each of the task's fixed start states — no exploration,
//! no learning, the same states at every evaluation, so that evaluations compare — whose
//! returns' mean is the greedy return. Greedy trials carry the number of the learning trial they
//! evaluate, do not count as learning trials and add nothing to the simulated learning
//! time. A learning trial that leaves the operating range ends early (§6.4.2), as does
//! one that reaches the task's goal: the samples it did not run do not count either.
//!
//! The in-process runner and the plant process (simulated or with an external driver)
//! iterate the same schedule:
//!
//! ```text
//! while let Some(trial) = schedule.next_trial() {
//!     let skipped = run(&trial);                           // the learning trial
//!     for greedy in schedule.end_trial(skipped).into_iter().flatten() {
//!         run(&greedy);                                    // its evaluation, if due
//!     }
//! }
//! ```

use std::sync::Arc;

use crate::Task;

/// One trial the schedule asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct Trial {
    /// The learning trial's number (from 1); a greedy trial carries the number of the
    /// learning trial it evaluates (the one just ended).
    pub number: u32,
    /// A greedy evaluation trial: no exploration, no learning, no learning time.
    pub greedy: bool,
    /// The start state `x_0`.
    pub x0: Vec<f64>,
    /// The simulated learning time at the trial's start \[s\].
    pub t0: f64,
}

/// The trials of one run, in order ([module documentation](self)).
pub struct Schedule {
    task: Arc<Task>,
    /// Learning trials in the run.
    trials: u32,
    /// An evaluation after every this many learning trials (0: none).
    eval_every: u32,
    /// Learning trials ended so far.
    done: u32,
    /// Samples the learning trials so far did not run (they ended early).
    skipped: u64,
    /// The run's seed, which start distributions draw from.
    run_seed: u64,
}

impl Schedule {
    /// A run of `trials` learning trials of `task`, evaluated every `eval_every` (0:
    /// never), its start distribution (if any) drawn from `run_seed`.
    pub fn new(task: Arc<Task>, trials: u32, eval_every: u32, run_seed: u64) -> Self {
        Self {
            task,
            trials,
            eval_every,
            done: 0,
            skipped: 0,
            run_seed,
        }
    }

    /// Continues the run after learning trial `after` (its evaluation done), which ended
    /// at simulated learning time `sim_time_s`: that time tells how many samples the
    /// trials before skipped ([`Task::skipped_samples`]).
    pub fn resume(&mut self, after: u32, sim_time_s: f64) {
        self.done = after;
        self.skipped = self.task.skipped_samples(after.into(), sim_time_s);
    }

    /// The next learning trial — the same until [`Schedule::end_trial`] ends it — or
    /// `None` when the run's learning trials are done.
    pub fn next_trial(&self) -> Option<Trial> {
        (self.done < self.trials).then(|| {
            let number = self.done + 1;
            let task = &self.task;
            let x0 = match &task.start_distribution {
                Some(d) => d.draw(self.run_seed, number, task.operating_range.as_ref()),
                None => task.initial_states[self.done as usize % task.initial_states.len()].clone(),
            };
            self.trial(number, false, &x0)
        })
    }

    /// Ends the learning trial [`Schedule::next_trial`] gave, which did not run `skipped`
    /// of its samples (it ended early). Returns the greedy trials of the
    /// evaluation that follows it, if one is due.
    pub fn end_trial(&mut self, skipped: usize) -> Option<Vec<Trial>> {
        debug_assert!(self.done < self.trials, "no learning trial is running");
        self.done += 1;
        self.skipped += skipped as u64;
        (self.eval_every > 0 && self.done.is_multiple_of(self.eval_every))
            .then(|| self.evaluation())
    }

    /// The greedy trials of an evaluation now: one from each of the task's start states,
    /// in their order.
    pub fn evaluation(&self) -> Vec<Trial> {
        let starts = &self.task.initial_states;
        starts
            .iter()
            .map(|x0| self.trial(self.done, true, x0))
            .collect()
    }

    fn trial(&self, number: u32, greedy: bool, x0: &[f64]) -> Trial {
        Trial {
            number,
            greedy,
            x0: x0.to_vec(),
            t0: self.sim_time_s(),
        }
    }

    /// Learning trials ended so far.
    pub fn done(&self) -> u32 {
        self.done
    }

    /// Samples the learning trials so far did not run.
    pub fn skipped_samples(&self) -> u64 {
        self.skipped
    }

    /// The simulated learning time so far \[s\]: the learning trials', less the samples
    /// they did not run ([`Task::sim_time`]).
    pub fn sim_time_s(&self) -> f64 {
        self.task.sim_time(self.done.into(), self.skipped)
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::SystemName;

    /// Learning trials cycle through the start states, evaluations follow every
    /// `eval_every` with one greedy trial per start state, and only learning trials —
    /// less their skipped samples — advance the simulated time.
    #[test]
    fn trials_cycle_start_states_and_evaluations_take_no_learning_time() {
        let task = Arc::new(Task::new(SystemName::Arm64));
        let starts = task.initial_states.len();
        assert!(starts > 1);
        let mut s = Schedule::new(task.clone(), 5, 2, 1);
        let mut seen = Vec::new();
        while let Some(t) = s.next_trial() {
            assert!(!t.greedy);
            assert_eq!(t.x0, task.initial_states[(t.number as usize - 1) % starts]);
            assert_eq!(t.t0, s.sim_time_s());
            let evaluation = s.end_trial(usize::from(t.number == 2) * 3);
            seen.push((t.number, evaluation.as_ref().map(Vec::len)));
            for g in evaluation.into_iter().flatten() {
                assert!(g.greedy && g.number == t.number && g.t0 == s.sim_time_s());
            }
        }
        assert_eq!(
            seen,
            [
                (1, None),
                (2, Some(starts)),
                (3, None),
                (4, Some(starts)),
                (5, None)
            ]
        );
        assert_eq!((s.done(), s.skipped_samples()), (5, 3));
        assert_eq!(s.sim_time_s(), task.sim_time(5, 3));
    }

    /// A resumed schedule continues where the straight one stood.
    #[test]
    fn a_resumed_schedule_continues_the_run() {
        let task = Arc::new(Task::new(SystemName::Arm64));
        let mut straight = Schedule::new(task.clone(), 6, 0, 1);
        for skipped in [0, 7, 2] {
            straight.end_trial(skipped);
        }
        let mut resumed = Schedule::new(task, 6, 0, 1);
        resumed.resume(3, straight.sim_time_s());
        assert_eq!(resumed.next_trial(), straight.next_trial());
        assert_eq!(resumed.skipped_samples(), 9);
    }

    /// With a start distribution, learning trials start from the run seed's draws — the
    /// same for the same seed, also after a resume; others for another seed — and
    /// evaluations from the fixed start states.
    #[test]
    fn learning_trials_draw_their_starts_and_evaluations_keep_the_fixed_ones() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../examples/tasks/pendulum-reach.toml");
        let task = Arc::new(Task::from_file(&path).unwrap());
        let starts = |seed: u64| -> Vec<Vec<f64>> {
            let mut s = Schedule::new(task.clone(), 6, 2, seed);
            let mut x0s = Vec::new();
            while let Some(t) = s.next_trial() {
                x0s.push(t.x0);
                for g in s.end_trial(0).into_iter().flatten() {
                    assert!(task.initial_states.contains(&g.x0), "{:?}", g.x0);
                }
            }
            x0s
        };
        let a = starts(11);
        assert_eq!(a, starts(11));
        assert_ne!(a, starts(12));
        assert!(
            a.iter()
                .all(|x| (0.9 * PI..=1.1 * PI).contains(&x[0]) && x[1].abs() <= 0.5)
        );
        assert!(a.windows(2).all(|w| w[0] != w[1]), "{a:?}");
        let mut resumed = Schedule::new(task.clone(), 6, 2, 11);
        resumed.resume(4, 0.0);
        assert_eq!(resumed.next_trial().unwrap().x0, a[4]);
    }
}
