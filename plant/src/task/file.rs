//! Task files: a system as the rig needs to know it, in TOML (documented key by key in
//! `docs/tasks.md`).
//!
//! A task file names the states (which are angles, the range the approximators cover),
//! the actions and their bounds, the sampling time, the trial and its start states (a
//! list, and optionally a distribution the learning trials draw from), the reward — the
//! quadratic form of Eq. 3.16, 5.1, 5.2, 6.20 and optionally periodic terms, a goal
//! bonus and an absolute action cost; its gradients follow from the terms,
//! [`crate::Reward`] —, how a trial ends besides its time limit (an operating range
//! whose exit ends it, §6.4.2; a goal whose reach ends it), and optionally the built-in
//! simulation that `rig learn` and `rig sim-driver` run it on. [`TaskFile::parse`] reads one; [`TaskFile::task`] checks every value and
//! builds the [`Task`]. Every error is one line naming the file, the key and what is
//! allowed.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::number::Number;
use super::{OperatingRange, Simulation, SystemName, Task};
use crate::Reward;
use crate::config::ConfigError;

mod check;

/// The longest task name: it travels NUL-padded in 32 bytes of the driver contract.
pub const MAX_NAME: usize = 31;
/// The most state components a task may have: a finite-horizon learner appends time to
/// the state, within [`crate::MAX_STATE`].
pub const MAX_STATES: usize = crate::MAX_STATE - 1;

/// A task file as written (numbers may be multiples of π, [`Number`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskFile {
    /// The task's name: ASCII letters, digits, `-`, `_`, `.`; at most [`MAX_NAME`] bytes.
    pub name: String,
    /// A sentence on what the task is (optional).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// The sampling time `Ts` \[s\].
    pub sampling_time: Number,
    /// The length of a trial \[s\].
    pub trial_seconds: Number,
    /// The start states: greedy evaluations start from each; learning trial `i` starts in
    /// `start_states[i % len]` unless `start_distribution` is given.
    pub start_states: Vec<Vec<Number>>,
    /// The state components, in the order of the state vector.
    pub state: Vec<StateSpec>,
    /// The action components, in the order of the action vector.
    pub action: Vec<ActionSpec>,
    /// The reward `ρ(x, u)`.
    pub reward: RewardSpec,
    /// Where the system may go; leaving it ends the trial with a penalty (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub operating_range: Option<RangeSpec>,
    /// Where the trial ends in success, with a reward (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal: Option<GoalSpec>,
    /// The distribution learning trials draw their start states from (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_distribution: Option<StartSpec>,
    /// The built-in simulation of the system (optional: a task without one runs against
    /// a driver).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simulation: Option<SimulationSpec>,
}

/// One state component.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateSpec {
    /// Its short name, for files and plots.
    pub name: String,
    /// Its unit (documentation only).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub unit: String,
    /// Whether it is an angle: wrapped to [−π, π), its errors taken modulo 2π.
    #[serde(default)]
    pub angle: bool,
    /// `[low, high]`, the range the parametric approximators (RBF grids, tilings) cover;
    /// an angle's default is `[-pi, pi]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[Number; 2]>,
}

/// One action component.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActionSpec {
    /// Its short name.
    pub name: String,
    /// Its unit (documentation only).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub unit: String,
    /// The lower bound: the plant saturates every action to `[low, high]`.
    pub low: Number,
    /// The upper bound.
    pub high: Number,
}

/// The reward: the quadratic form `ρ(x, u) = −(x − x_r)ᵀ Q (x − x_r) − uᵀ P u` with
/// diagonal `Q`, `P`, plus the optional terms; and the terminal reward
/// `τ_N(x) = −(x − x_r)ᵀ Q_N (x − x_r)` of a finite horizon.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RewardSpec {
    /// `diag(Q)`, one weight ≥ 0 per state component.
    pub state_weights: Vec<Number>,
    /// `diag(P)`, one weight ≥ 0 per action component.
    pub action_weights: Vec<Number>,
    /// The reference state `x_r` (default: zero).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<Vec<Number>>,
    /// `diag(Q_N)` of the terminal reward (default: `state_weights`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terminal_weights: Option<Vec<Number>>,
    /// `w_i` of `−Σ w_i (1 − cos(x_i − x_r,i))`, one per state (non-zero for angles only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cosine_weights: Option<Vec<Number>>,
    /// `c_j` of `−Σ c_j |u_j|`, one per action.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub action_abs_weights: Option<Vec<Number>>,
    /// A region with a bonus per sample inside (`[reward.goal]`: region and `bonus`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal: Option<GoalSpec>,
}

/// A goal region — a box (`low`, `high`) or a ball (`centre`, `radius`) — with, as the
/// reward's `[reward.goal]`, a `bonus` per sample inside, or, as the task's `[goal]`, the
/// `reward` of the transition that reaches it and ends the trial.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoalSpec {
    /// A box's lower bounds, one per state (`-inf`: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low: Option<Vec<Number>>,
    /// A box's upper bounds, one per state (`inf`: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub high: Option<Vec<Number>>,
    /// A ball's centre, one number per state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<Vec<Number>>,
    /// A ball's radius along each state (`inf`: that state does not count).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<Vec<Number>>,
    /// `[reward.goal]`: the reward per sample inside.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bonus: Option<Number>,
    /// `[goal]`: the reward of the transition that reaches the region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reward: Option<Number>,
}

crate::choice! {
    /// The distributions start states may be drawn from.
    #[derive(Debug, PartialEq, Eq)]
    pub enum StartKind {
        /// Uniform in a box: `low`, `high`.
        Uniform => "uniform",
        /// Normal: `mean`, `std`.
        Normal => "normal",
    }
}

/// `[start_distribution]`: where learning trials start.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// `uniform` or `normal`.
    pub kind: StartKind,
    /// Uniform: the lower bounds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low: Option<Vec<Number>>,
    /// Uniform: the upper bounds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub high: Option<Vec<Number>>,
    /// Normal: the means.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean: Option<Vec<Number>>,
    /// Normal: the standard deviations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std: Option<Vec<Number>>,
}

/// The operating range: `[low[i], high[i]]` per state component (`inf`, `-inf` for no
/// bound).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeSpec {
    /// Lower bounds, one per state component.
    pub low: Vec<Number>,
    /// Upper bounds, one per state component.
    pub high: Vec<Number>,
    /// The reward of the transition that leaves the range, which ends the trial (≤ 0).
    pub penalty: Number,
}

/// The built-in simulation a task runs on in `rig learn` and `rig sim-driver`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// The simulated system: one of the built-in dynamics.
    pub system: SystemName,
    /// RK4 sub-steps per sample period.
    pub substeps: u32,
}

impl TaskFile {
    /// Reads the task file at `path`.
    pub fn read(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError {
            file: Some(path.to_path_buf()),
            key: String::new(),
            message: format!("cannot read: {e}"),
        })?;
        Self::parse(&text, Some(path))
    }

    /// Parses a task file's text (`path`, if any, is named in errors).
    pub fn parse(text: &str, path: Option<&Path>) -> Result<Self, ConfigError> {
        toml::from_str(text).map_err(|e| {
            // A key missing at the top level spans the whole file: no line to name.
            let at = e
                .span()
                .filter(|s| s.start > 0)
                .map(|s| line_of(text, s.start));
            let message = match at {
                Some(line) => format!("line {line}: {}", e.message()),
                None => e.message().to_string(),
            };
            ConfigError {
                file: path.map(Path::to_path_buf),
                key: String::new(),
                message: format!("not a valid task file: {}", one_line(&message)),
            }
        })
    }

    /// The task: every value checked (see `docs/tasks.md`); the error names `path`, the
    /// key and what is allowed.
    pub fn task(&self, path: Option<&Path>) -> Result<Task, ConfigError> {
        self.build().map_err(|mut e| {
            e.file = path.map(Path::to_path_buf);
            e
        })
    }

    /// The file as TOML, numbers written out (π as 3.141592653589793).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a task file always serialises")
    }

    fn build(&self) -> Result<Task, ConfigError> {
        let c = check::Checked::of(self)?;
        let simulation = match &self.simulation {
            Some(s) => Some(c.simulation(s)?),
            None => None,
        };
        let angle_mask = c.angle_mask;
        Ok(Task {
            name: self.name.clone(),
            simulation,
            ts: c.ts,
            action_low: c.action_low,
            action_high: c.action_high,
            reward: Reward {
                q: c.reward.state,
                p: c.reward.action,
                reference: c.reward.reference,
                terminal: c.reward.terminal,
                angle_mask: angle_mask.clone(),
                terms: c.reward.terms,
            },
            angle_mask,
            initial_states: c.start_states,
            start_distribution: c.start_distribution,
            trial_seconds: c.trial_seconds,
            state_range: c.state_range,
            state_names: self.state.iter().map(|s| s.name.clone()).collect(),
            operating_range: c
                .operating_range
                .map(|(limits, penalty)| OperatingRange { limits, penalty }),
            goal: c.goal,
            file: self.clone(),
        })
    }
}

impl Simulation {
    /// The built-in dynamics of `system` with `substeps` RK4 sub-steps per sample.
    pub fn of(system: SystemName, substeps: usize) -> Self {
        Self {
            system,
            dynamics: super::builtin::dynamics(system),
            substeps,
        }
    }
}

/// The 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// `s` with its line breaks replaced by spaces.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}
