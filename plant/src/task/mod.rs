//! Tasks: a system together with everything an experiment on it needs, described by a
//! task file ([`mod@file`]); the built-in systems' files ship in `plant/tasks/` ([`builtin`]).

use std::path::Path;

pub use crate::operating_range::OperatingRange;

use crate::angle::wrap;
use crate::config::ConfigError;
use crate::region::Region;
use crate::start::StartDistribution;
use crate::{Dynamics, Reward};

pub mod builtin;
pub mod digest;
pub mod file;
mod number;

pub use file::TaskFile;
pub use number::Number;

crate::choice! {
    /// The built-in systems: simulated dynamics, each with its shipped task file and the
    /// thesis's tuned presets. Any other system is a task file a driver serves.
    #[derive(Debug, PartialEq, Eq, Hash)]
    pub enum SystemName {
        /// Pendulum swing-up, §3.6 and §6.4.1 (Appendix A.1).
        Pendulum => "pendulum",
        /// Two-link arm in the vertical plane, Case I (§5.3): inject damping.
        ArmVertical => "arm-vertical",
        /// Two-link arm in the horizontal plane, Case II (§5.4): reach a reference.
        ArmHorizontal => "arm-horizontal",
        /// The manipulator of §6.4.2 (Table 6.3): horizontal plane, `|u| ≤ 0.1 N m`, operating
        /// range ±1.2 rad (leaving it ends the trial with reward −4·10⁴), four start states.
        Arm64 => "arm-6.4",
        /// Linear double integrator with a quadratic reward (LQR check).
        DoubleIntegrator => "double-integrator",
    }
}

/// A system with its sampling, limits, reward and trial definition: what a task file
/// says ([`TaskFile`]), checked, with the built-in simulation it names, if any.
pub struct Task {
    /// The task's name (the built-in systems': their `--system` spelling).
    pub name: String,
    /// The built-in simulation of the system; `None` for a task only a driver serves.
    pub simulation: Option<Simulation>,
    /// Sampling time `Ts` \[s\].
    pub ts: f64,
    /// Lower action bounds.
    pub action_low: Vec<f64>,
    /// Upper action bounds.
    pub action_high: Vec<f64>,
    /// Which state components are angles (wrapped to [-π, π)).
    pub angle_mask: Vec<bool>,
    /// The reward `ρ(x, u)`.
    pub reward: Reward,
    /// The fixed start states: greedy evaluations start from each; learning trial `i`
    /// starts in `initial_states[i % len]` unless there is a `start_distribution`.
    pub initial_states: Vec<Vec<f64>>,
    /// Where learning trials start instead, drawn from the run seed ([`crate::start`]).
    pub start_distribution: Option<StartDistribution>,
    /// Trial length \[s\].
    pub trial_seconds: f64,
    /// The region of the state space that parametric approximators cover (RBF grids,
    /// tilings): `(low, high)` per state component.
    pub state_range: Vec<(f64, f64)>,
    /// Short names of the state components, for files and plots.
    pub state_names: Vec<String>,
    /// Where the system may go; leaving it ends the trial (§6.4.2), a failure. `None`:
    /// anywhere.
    pub operating_range: Option<OperatingRange>,
    /// Where the trial ends in success; `None`: it ends at its time limit (or on
    /// leaving the operating range).
    pub goal: Option<Goal>,
    /// The task file this task was built from.
    pub file: TaskFile,
}

impl std::fmt::Debug for Task {
    /// The task's name and its file (the dynamics are code).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Task")
            .field("name", &self.name)
            .field("file", &self.file)
            .finish_non_exhaustive()
    }
}

/// A built-in simulation of a task's system: `ẋ = f(x, u)` integrated by RK4.
pub struct Simulation {
    /// Which built-in system.
    pub system: SystemName,
    /// `ẋ = f(x, u)`.
    pub dynamics: Box<dyn Dynamics>,
    /// RK4 sub-steps per sample period (see [`crate::rk4`]).
    pub substeps: usize,
}

/// A terminal goal: the transition that reaches `region` ends the trial (termination,
/// as leaving the operating range does) with `reward` as its reward, in place of `ρ`.
#[derive(Clone, Debug, PartialEq)]
pub struct Goal {
    /// Where the trial ends.
    pub region: Region,
    /// The reward of the transition that reaches it.
    pub reward: f64,
}

impl Task {
    /// The built-in system `name`, from its shipped task file (`plant/tasks/`): the
    /// thesis's settings.
    pub fn new(name: SystemName) -> Self {
        builtin::task(name)
    }

    /// Pendulum swing-up (§3.6, Table A.1): `Ts = 0.03 s`, `u ∈ [−3, 3] V`, 3 s trials
    /// from `[π, 0]`, reward Eq. 3.16 with `Q = diag(5, 0.1)`, `P = 1`.
    pub fn pendulum() -> Self {
        Self::new(SystemName::Pendulum)
    }

    /// The task of the file at `path`, checked; the error names the file, the key and
    /// what is allowed.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        TaskFile::read(path)?.task(Some(path))
    }

    /// The built-in simulation.
    ///
    /// # Panics
    /// If the task has none: a configuration that simulates a task is refused before
    /// (`[simulation]` is missing).
    pub fn simulation(&self) -> &Simulation {
        self.simulation.as_ref().unwrap_or_else(|| {
            panic!(
                "task \"{}\" has no [simulation]: it runs against a driver only",
                self.name
            )
        })
    }

    /// The task's content hash, which drivers advertise ([`digest`]).
    pub fn hash(&self) -> u64 {
        digest::hash(self)
    }

    /// State dimension `n`.
    pub fn state_dim(&self) -> usize {
        self.angle_mask.len()
    }

    /// Action dimension `m`.
    pub fn action_dim(&self) -> usize {
        self.action_low.len()
    }

    /// Samples per trial.
    pub fn steps_per_trial(&self) -> usize {
        (self.trial_seconds / self.ts).round() as usize
    }

    /// Simulated learning time after `trials` trials of which `skipped` samples were not
    /// run (trials that left the operating range or reached the goal end early) \[s\].
    pub fn sim_time(&self, trials: u64, skipped: u64) -> f64 {
        trials as f64 * self.trial_seconds - skipped as f64 * self.ts
    }

    /// The samples not run in the first `trials` trials, from the simulated time at their
    /// end (the inverse of [`Task::sim_time`]; a resumed run continues from it).
    pub fn skipped_samples(&self, trials: u64, sim_time_s: f64) -> u64 {
        ((self.sim_time(trials, 0) - sim_time_s) / self.ts)
            .round()
            .max(0.0) as u64
    }

    /// The action the plant applies for `u`, into `out`: clamped to the action bounds, or
    /// zero (the safe action) if a component is not finite ([`crate::safety::SafetyLayer`]).
    pub fn saturate(&self, u: &[f64], out: &mut [f64]) -> crate::safety::Admission {
        crate::safety::limit(&self.action_low, &self.action_high, u, out)
    }

    /// Wraps the angle components of `x` to [-π, π).
    pub fn wrap_state(&self, x: &mut [f64]) {
        for (xi, &is_angle) in x.iter_mut().zip(&self.angle_mask) {
            if is_angle {
                *xi = wrap(*xi);
            }
        }
    }
}

#[cfg(test)]
mod tests;
