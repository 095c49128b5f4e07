//! Presets for a task the rig does not simulate, by rules: the pendulum's preset of the
//! same algorithm, approximator and horizon — the thesis's most tuned — carried over to
//! the task's dimensions and ranges.
//!
//! 1. **Inputs.** The first `⌈n/2⌉` state components are positions, the rest velocities
//!    (the state order the driver contract prescribes); actions follow in a process
//!    model's input, time in a finite-horizon actor's or critic's. Each takes the
//!    pendulum value of its kind: the angle's, the angular velocity's, the voltage's.
//! 2. **LLR input weights** are scaled by the ranges: `w = w_pendulum × h_pendulum / h`,
//!    with `h` the half-width of the component's approximator range (the action's bounds
//!    for an action): the pendulum's ranges `π`, `8π`, `3 V` map to its own weights.
//! 3. **RBF, LSTD and tile grids** take the pendulum's count per kind of input; a grid of
//!    more than [`MAX_GRID`] basis functions — an LSTD critic's: more than the pendulum's
//!    400, as it solves a dense system each step — shrinks by a common factor (each count
//!    at least 2).
//! 4. **LLR memories** hold `n/2` times the pendulum's samples; `K` is at least
//!    `2 (d + 1)` for `d` inputs (an affine fit needs more than `d + 1` neighbours).
//! 5. **Exploration** `σ` and the saturation margin scale with the smallest action
//!    half-width over the pendulum's 3 V; SARSA's actions are the lowest common bound,
//!    the midpoint and the highest common bound.
//! 6. **The discount** comes from the task's time scale, in seconds: its horizon
//!    `Ts / (1 − γ)` is a third of the trial, `γ = 1 − 3 Ts / T_trial` ([`discount`]) —
//!    the pendulum's `0.97` at `Ts = 0.03 s`, `T_trial = 3 s`, and the same horizon in
//!    seconds for the same task sampled faster. With a finite horizon `γ = 1` stays.
//! 7. Learning rates, `λ`, trials, runs and the evaluation cadence are the pendulum's.
//!
//! Applied to the pendulum's own task the rules give its preset (tested).

use std::f64::consts::PI;

use plant::Task;

use super::Preset;
use crate::config::{Component, HorizonKind};

/// Discount horizons per trial: the pendulum's `γ = 0.97` looks `Ts / (1 − γ) = 1 s`
/// ahead in its 3 s trials (docs/configuration.md, "The discount of a task": measured on
/// a goal task at two sampling times).
pub const HORIZONS_PER_TRIAL: f64 = 3.0;

/// The least discount [`discount`] gives (a trial of fewer than 6 samples).
pub const MIN_DISCOUNT: f64 = 0.5;

/// The discount of `task` (rule 6): `γ = 1 − 3 Ts / T_trial`, its horizon `Ts / (1 − γ)`
/// a third of the trial in seconds; at least [`MIN_DISCOUNT`].
pub fn discount(task: &Task) -> f64 {
    (1.0 - HORIZONS_PER_TRIAL * task.ts / task.trial_seconds).max(MIN_DISCOUNT)
}

/// The most basis functions a derived grid has: LSTD's limit, and a bound on every RBF
/// step's cost.
pub const MAX_GRID: usize = 5000;

/// Half-widths of the pendulum's inputs: angle, angular velocity, voltage.
const PENDULUM: [f64; 3] = [PI, 8.0 * PI, 3.0];

/// What an approximator input is.
#[derive(Clone, Copy, PartialEq)]
enum Input {
    /// A state component: its index, and whether it is a position.
    State(usize, bool),
    /// An action component.
    Action(usize),
    /// Time, a finite horizon's extra input.
    Time,
}

impl Input {
    /// The index of the pendulum's input of the same kind in a vector of `len` inputs.
    fn pendulum_index(self, len: usize) -> usize {
        match self {
            Input::State(_, true) => 0,
            Input::State(_, false) => 1,
            Input::Action(_) => 2,
            Input::Time => len - 1,
        }
    }
}

/// The inputs of `task` as an actor or critic (`action = false`) or a process model sees
/// them.
fn inputs(task: &Task, action: bool, time: bool) -> Vec<Input> {
    let n = task.state_dim();
    let positions = n.div_ceil(2);
    let mut v: Vec<Input> = (0..n).map(|i| Input::State(i, i < positions)).collect();
    if action {
        v.extend((0..task.action_dim()).map(Input::Action));
    }
    if time {
        v.push(Input::Time);
    }
    v
}

/// The half-width of `task`'s range for `input`, over the pendulum's of its kind (1 for
/// time).
fn ratio(task: &Task, input: Input) -> f64 {
    let half = |(lo, hi): (f64, f64)| 0.5 * (hi - lo);
    match input {
        Input::State(i, position) => {
            half(task.state_range[i]) / PENDULUM[if position { 0 } else { 1 }]
        }
        Input::Action(j) => half((task.action_low[j], task.action_high[j])) / PENDULUM[2],
        Input::Time => 1.0,
    }
}

/// `pendulum`'s preset carried over to `task` by the rules of the module documentation.
pub(super) fn adapt(mut preset: Preset, task: &Task) -> Preset {
    let time = preset.agent.horizon == HorizonKind::Finite;
    let agent = &mut preset.agent;
    let state_inputs = inputs(task, false, time);
    if let Some(actor) = &mut agent.actor {
        adapt_component(actor, task, &state_inputs);
    }
    adapt_component(&mut agent.critic, task, &state_inputs);
    if let Some(model) = &mut agent.model {
        adapt_component(model, task, &inputs(task, true, false));
    }
    let u_ratio = (0..task.action_dim())
        .map(|j| ratio(task, Input::Action(j)))
        .fold(f64::INFINITY, f64::min);
    if !time {
        agent.learning.gamma = discount(task);
    }
    agent.learning.sigma *= u_ratio;
    agent.learning.saturation_margin *= u_ratio;
    if let Some(sarsa) = &mut agent.sarsa {
        let lo = task
            .action_low
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let hi = task
            .action_high
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        sarsa.actions = vec![lo, 0.5 * (lo + hi), hi];
    }
    preset
}

/// One component carried over to `inputs`.
fn adapt_component(c: &mut Component, task: &Task, inputs: &[Input]) {
    match c {
        Component::Llr(l) => {
            let len = l.weights.len();
            l.weights = inputs
                .iter()
                .map(|&i| l.weights[i.pendulum_index(len)] / ratio(task, i))
                .collect();
            l.memory = (l.memory * task.state_dim()).div_ceil(2);
            let k = 2 * (inputs.len() + 1);
            let k_max = crate::approx::kdtree::MAX_K.min(l.memory);
            l.neighbours = l.neighbours.max(k).min(k_max);
        }
        Component::Rbf(r) => r.centres = grid(&r.centres, inputs, MAX_GRID),
        Component::Lstd(l) => {
            let pendulum = l.centres.iter().product();
            l.centres = grid(&l.centres, inputs, pendulum);
        }
        Component::Tiles(t) => t.tiles = grid(&t.tiles, inputs, MAX_GRID),
    }
}

/// The pendulum's counts per kind of input, shrunk to at most `max` in all.
fn grid(pendulum: &[usize], inputs: &[Input], max: usize) -> Vec<usize> {
    let len = pendulum.len();
    let counts: Vec<usize> = inputs
        .iter()
        .map(|i| pendulum[i.pendulum_index(len)])
        .collect();
    let total: f64 = counts.iter().map(|&c| c as f64).product();
    if total <= max as f64 {
        return counts;
    }
    let mut factor = (max as f64 / total).powf(1.0 / counts.len() as f64);
    loop {
        let shrunk: Vec<usize> = counts
            .iter()
            .map(|&c| ((c as f64 * factor).floor() as usize).max(2))
            .collect();
        if shrunk.iter().product::<usize>() <= max || shrunk.iter().all(|&c| c == 2) {
            return shrunk;
        }
        factor *= 0.95;
    }
}
