//! The thesis's tuned parameters as presets, one per (system, algorithm, approximator).
//!
//! * Pendulum (§3.6): `γ = 0.97`, `λ = 0.65`, `σ = 1` every step, 400 trials, 30 runs;
//!   RBF values from Table 3.1, LLR values from Table 3.2 with the input scaling of
//!   Table 6.2 (`[1, 0.1]` for states, `[1, 0.1, 1]` for the process model); tile coding
//!   with 16 tilings of 7 × 7 and `α_a = 0.005`, `α_c = 0.1` (§3.6.1).
//!   Table 3.1 gives no grid size for the RBF process model: the actor's grid is used with
//!   5 centres along the action.
//! * RMAC/LLR on the pendulum: Table 6.2's scaling is for MLAC and VGBP; for RMAC the
//!   thesis gives none. The reference model uses `[1, 0.04]` and the process model
//!   `[1, 0.1, 0.5]`: a wider velocity neighbourhood averages the reference's bang-bang
//!   targets (every `x_r` comes from an extreme action, §3.4) into a smoother desired
//!   state near the upright position, where `[1, 0.1]` chatters between ±3 V. Measured
//!   with `rig learn`, 30 runs, mean greedy return of the last three evaluations:
//!   −1443 → −992 (seed 1), −924 (seed 2).
//! * Two-link arm (§5.3, §5.4): the learning rates, memory sizes and neighbours given in
//!   the text for SAC/RBF, SAC/LLR and MLAC/LLR, 600 trials, 20 runs. The thesis gives no
//!   LLR input scaling for the arm; `[1, 1, 0.1, 0.1]` (and `1` per torque) is used,
//!   matching the pendulum's angle-to-velocity ratio.
//! * LLR memory management (§3.5.2 lists options and leaves the choice open): actor,
//!   critic and reference-model memories use the redundancy rule with radius
//!   [`REDUNDANCY_RADIUS`] in scaled units — a new sample replaces a stored one that
//!   close instead of purging the oldest. Every trial starts at `[π, 0]`, so with
//!   oldest-first purging the memories fill with exact duplicates there; their local fit
//!   has no slope, and the value gradient MLAC needs vanishes at the start state.
//!   Measured with `rig learn`, 8 runs of MLAC/LLR: mean greedy return over the last
//!   three evaluations −1865 (oldest) → −841 (redundant, 0.05). SAC's memories use
//!   [`SAC_REDUNDANCY_RADIUS`]: with 0.05 a few of 30 runs still spin the pendulum in the
//!   greedy evaluation at trial 60 (mean −1649, median −972); with 0.1 the mean is −1087
//!   (seed 1) and −1071 (seed 2). Process models keep the thesis's oldest-first window of
//!   recent transitions.
//! * LLR critics clip their predictions to the range of their neighbours' values
//!   ([`crate::approx::llr::LlrParams::clip_to_neighbours`]). Unclipped, the first trial
//!   leaves the states visited once (far from the start) near their initial value 0 and
//!   the start region well below it; the affine fit extrapolates that slope outwards,
//!   and MLAC's model-based gradient drives the pendulum into spinning in trial 2 (mean
//!   return −9541 over 30 runs, against −5400 in trial 1). Clipped: −4686, and the
//!   learning curve rises from there.
//! * Combinations the thesis did not tune (RMAC on the arm, anything on the double
//!   integrator) start from the pendulum values of the same algorithm and approximator.
//! * Finite horizon (Chapter 4, §4.4): see [`finite_horizon`].
//! * A task the rig does not simulate (a task file without `[simulation]`): the
//!   pendulum's preset carried over by [`rules`] ([`for_task`]).

use plant::config::{ConfigError, RunConfig};
use plant::{SystemName, Task};

use crate::config::{AgentConfig, Algo, ApproxKind, HorizonKind, LearningConfig};

mod actor_critic;
pub mod by_task;
mod components;
mod critic_only;
mod finite;
pub mod rules;
#[cfg(test)]
mod tests;

pub use components::{REDUNDANCY_RADIUS, SAC_REDUNDANCY_RADIUS};
use critic_only::critic_only;
pub use critic_only::{VGBP_ACTION_GRID, VGBP_LOOKAHEAD};
pub use finite::finite_horizon;

/// A preset: the agent's part of the configuration and the `[run]` section the thesis
/// used with it.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    /// The learner and its parameters.
    pub agent: AgentConfig,
    /// Trials, runs, seed and evaluation.
    pub run: RunConfig,
}

/// `[run]` with seed 1 and no delay.
fn run_section(trials: u32, runs: u32, eval_every: u32) -> RunConfig {
    RunConfig {
        trials,
        runs,
        seed: 1,
        eval_every,
        delay_ms: 0.0,
        delay_from: String::new(),
        delay_column: String::new(),
    }
}

/// LLR input scaling `diag(W)` of state memories and of the process model: angles 1,
/// velocities 0.1, actions 1 (Table 6.2); on the §6.4.2 manipulator velocities 0.05 and
/// actions 5 (Table 6.4).
fn input_scaling(system: SystemName) -> (Vec<f64>, Vec<f64>) {
    let (w_state, w_action): (Vec<f64>, f64) = match system {
        SystemName::Pendulum => (vec![1.0, 0.1], 1.0),
        SystemName::ArmVertical | SystemName::ArmHorizontal => (vec![1.0, 1.0, 0.1, 0.1], 1.0),
        SystemName::Arm64 => (vec![1.0, 1.0, 0.05, 0.05], 5.0),
        SystemName::DoubleIntegrator => (vec![1.0, 1.0], 1.0),
    };
    let m = Task::new(system).action_dim();
    let w_model = w_state
        .iter()
        .copied()
        .chain(std::iter::repeat_n(w_action, m))
        .collect();
    (w_state, w_model)
}

/// The preset for `task`: its simulated system's ([`preset`]), or, for a task the rig
/// does not simulate, the pendulum's carried over by [`rules`].
pub fn for_task(
    task: &Task,
    algo: Algo,
    approx: ApproxKind,
    horizon: HorizonKind,
) -> Result<Preset, ConfigError> {
    match &task.simulation {
        Some(sim) => preset(sim.system, algo, approx, horizon),
        None => Ok(rules::adapt(
            preset(SystemName::Pendulum, algo, approx, horizon)?,
            task,
        )),
    }
}

/// The preset for `(system, algo, approx)` with the given horizon.
pub fn preset(
    system: SystemName,
    algo: Algo,
    approx: ApproxKind,
    horizon: HorizonKind,
) -> Result<Preset, ConfigError> {
    algo.check_approx(approx)?;
    if horizon == HorizonKind::Finite {
        return finite_horizon(system, algo, approx);
    }
    if matches!(algo, Algo::Vgbp | Algo::Sarsa) {
        return Ok(critic_only(system, algo, approx));
    }
    let (actor, critic, model) = actor_critic::components(system, algo, approx)?;
    // The §6.4.2 manipulator takes the settings of Chapter 5's arms (see
    // [`actor_critic::components`]).
    let arm = matches!(
        system,
        SystemName::ArmVertical | SystemName::ArmHorizontal | SystemName::Arm64
    );
    let agent = AgentConfig {
        algo,
        approx,
        horizon: HorizonKind::Infinite,
        learning: LearningConfig {
            gamma: 0.97,
            lambda: 0.65,
            sigma: 1.0,
            explore_every: 1,
            saturation_margin: if approx == ApproxKind::Rbf { 0.1 } else { 0.0 },
            bounded_actor: true,
        },
        actor: Some(actor),
        critic,
        model,
        vgbp: None,
        sarsa: None,
        planning: None,
        lqr: None,
    };
    let run = if arm {
        run_section(600, 20, 10)
    } else {
        run_section(400, 30, 10)
    };
    Ok(Preset { agent, run })
}
