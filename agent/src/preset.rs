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

use plant::config::{ConfigError, RunConfig};
use plant::{SystemName, Task};

use crate::config::{
    AgentConfig, Algo, ApproxKind, Component, HorizonKind, LearningConfig, LlrConfig, LstdConfig,
    LstdPrior, RbfConfig, SarsaConfig, TilesConfig, VgbpConfig, finite_horizon_unsupported,
};

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

/// LLR memories of actors, critics and reference models replace a stored sample closer
/// than this (in scaled units) instead of purging the oldest; see the module docs.
pub const REDUNDANCY_RADIUS: f64 = 0.05;

/// SAC's actor and critic memories use a wider radius (see the module docs).
pub const SAC_REDUNDANCY_RADIUS: f64 = 0.1;

/// An actor or reference-model memory (redundancy-based management).
fn llr(alpha: f64, memory: usize, neighbours: usize, weights: Vec<f64>) -> Component {
    Component::Llr(LlrConfig {
        alpha,
        memory,
        neighbours,
        weights,
        eviction: "redundant".into(),
        redundancy_radius: REDUNDANCY_RADIUS,
        clip_to_neighbours: false,
    })
}

/// A critic memory: as an actor memory, with predictions clipped to the neighbours'
/// values (see the module docs).
fn llr_critic(alpha: f64, memory: usize, neighbours: usize, weights: Vec<f64>) -> Component {
    match llr(alpha, memory, neighbours, weights) {
        Component::Llr(c) => Component::Llr(LlrConfig {
            clip_to_neighbours: true,
            ..c
        }),
        _ => unreachable!(),
    }
}

/// A process-model memory: it only stores transitions, and the thesis's 100 most recent
/// ones (Table 3.2) are what it is tuned for, so the oldest is purged.
fn llr_model(memory: usize, neighbours: usize, weights: Vec<f64>) -> Component {
    Component::Llr(LlrConfig {
        alpha: 0.0,
        memory,
        neighbours,
        weights,
        eviction: "oldest".into(),
        redundancy_radius: 0.0,
        clip_to_neighbours: false,
    })
}

fn rbf(alpha: f64, centres: Vec<usize>, intersection: f64) -> Component {
    Component::Rbf(RbfConfig {
        alpha,
        centres,
        intersection,
    })
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
    let task = Task::new(system);
    let (n, m) = (task.state_dim(), task.action_dim());
    // The §6.4.2 manipulator has no actor-critic settings in the thesis; it takes those
    // of Chapter 5's horizontal arm (Case II), untuned.
    let arm = matches!(
        system,
        SystemName::ArmVertical | SystemName::ArmHorizontal | SystemName::Arm64
    );
    let (w_state, w_model) = input_scaling(system);
    let grid =
        |per_axis: [usize; 2]| -> Vec<usize> { if arm { vec![9; n] } else { per_axis.to_vec() } };
    let model_grid = |per_axis: [usize; 2]| -> Vec<usize> {
        let mut g = grid(per_axis);
        g.extend(std::iter::repeat_n(5, m));
        g
    };
    use Algo::*;
    use ApproxKind::*;
    use SystemName::*;
    let (mut actor, mut critic, model) = match (algo, approx) {
        (Sac, Tiles) => (
            Component::Tiles(TilesConfig {
                alpha: 0.005,
                tilings: 16,
                tiles: vec![7; n],
            }),
            Component::Tiles(TilesConfig {
                alpha: 0.1,
                tilings: 16,
                tiles: vec![7; n],
            }),
            None,
        ),
        (Sac, Rbf) => match system {
            ArmVertical => (
                rbf(0.25, grid([9, 9]), 0.9),
                rbf(0.4, grid([9, 9]), 0.9),
                None,
            ),
            ArmHorizontal | Arm64 => (
                rbf(0.1, grid([9, 9]), 0.7),
                rbf(0.3, grid([9, 9]), 0.7),
                None,
            ),
            _ => (
                rbf(0.05, grid([20, 10]), 0.9),
                rbf(0.4, grid([20, 10]), 0.5),
                None,
            ),
        },
        (Mlac, Rbf) => (
            rbf(0.05, grid([15, 10]), 0.9),
            rbf(0.1, grid([15, 10]), 0.7),
            Some(rbf(0.5, model_grid([15, 10]), 0.9)),
        ),
        (Rmac, Rbf) => (
            rbf(0.5, grid([10, 10]), 0.9),
            rbf(0.15, grid([10, 10]), 0.7),
            Some(rbf(0.7, model_grid([10, 10]), 0.7)),
        ),
        (Sac, Llr) => match system {
            ArmVertical => (
                llr(0.05, 6000, 30, w_state.clone()),
                llr_critic(0.4, 6000, 30, w_state.clone()),
                None,
            ),
            ArmHorizontal | Arm64 => (
                llr(0.05, 5000, 30, w_state.clone()),
                llr_critic(0.35, 5000, 30, w_state.clone()),
                None,
            ),
            _ => (
                llr(0.05, 2000, 20, w_state.clone()),
                llr_critic(0.3, 1000, 10, w_state.clone()),
                None,
            ),
        },
        (Mlac, Llr) => match system {
            ArmVertical => (
                llr(0.15, 6000, 30, w_state.clone()),
                llr_critic(0.35, 6000, 30, w_state.clone()),
                Some(llr_model(600, 25, w_model.clone())),
            ),
            ArmHorizontal | Arm64 => (
                llr(0.1, 7000, 20, w_state.clone()),
                llr_critic(0.4, 7000, 20, w_state.clone()),
                Some(llr_model(500, 15, w_model.clone())),
            ),
            _ => (
                llr(0.05, 2000, 25, w_state.clone()),
                llr_critic(0.3, 2000, 15, w_state.clone()),
                Some(llr_model(100, 10, w_model.clone())),
            ),
        },
        (Rmac, Llr) => {
            // Input scaling of the reference and process models: not given by the thesis
            // (see the module docs).
            let (w_ref, w_ref_model) = match system {
                Pendulum => (vec![1.0, 0.04], vec![1.0, 0.1, 0.5]),
                _ => (w_state.clone(), w_model.clone()),
            };
            (
                llr(0.04, 2000, 15, w_ref),
                llr_critic(0.2, 2000, 15, w_state.clone()),
                Some(llr_model(100, 10, w_ref_model)),
            )
        }
        (Mlac | Rmac, Tiles) | (_, Lstd) | (Vgbp | Sarsa, _) => unreachable!("rejected above"),
    };
    if (algo, approx) == (Sac, Llr) {
        for c in [&mut actor, &mut critic] {
            if let Component::Llr(l) = c {
                l.redundancy_radius = SAC_REDUNDANCY_RADIUS;
            }
        }
    }
    let agent = AgentConfig {
        algo,
        approx,
        horizon: HorizonKind::Infinite,
        learning: LearningConfig {
            gamma: 0.97,
            lambda: 0.65,
            sigma: 1.0,
            explore_every: 1,
            saturation_margin: if approx == Rbf { 0.1 } else { 0.0 },
            bounded_actor: true,
        },
        actor: Some(actor),
        critic,
        model,
        vgbp: None,
        sarsa: None,
    };
    let run = if arm {
        run_section(600, 20, 10)
    } else {
        run_section(400, 30, 10)
    };
    Ok(Preset { agent, run })
}

/// Chapter 4's finite-horizon learners, SAC-FH, MLAC-FH and RMAC-FH (Algorithms 4–6),
/// with the parameters of §4.4: 600 trials (episodes) of 3 s, 20 runs, RBFs with 9
/// centres along every input — `φ ∈ [−π, π]`, `φ̇ ∈ [−8π, 8π]` and time
/// `k ∈ {0, …, 99}` for actor, critic and reference model (729 RBFs each). "Widths" are
/// intersection heights, as in Table 3.1 (§5.3 calls Table 3.1's intersection 0.9 a
/// "width of 0.9").
///
/// | | learning rates | widths |
/// |---|---|---|
/// | SAC-FH (§4.4.1) | `α_a = 0.05`, `α_c = 0.2` | 0.55 |
/// | MLAC-FH (§4.4.2) | `α_a = 0.15`, `α_c = 0.4`, `α_p = 0.8` | actor 0.55, critic 0.65, model 0.75 |
/// | RMAC-FH (§4.4.3) | `α_r = 0.6`, `α_c = 0.2`, `α_p = 0.6` | reference and critic 0.7, model 0.6 |
///
/// Where §4.4 is silent or inconsistent, the choice made here:
///
/// * §4.4.3 prints "`α_r = 0.6`, `α_c = 0.2`, `α_r = 0.6`"; the second `α_r` is read as
///   the process model's `α_p`, the one rate not otherwise given.
/// * §4.4 counts 81 RBFs in the process model, over `(φ, φ̇)` only; but the model is
///   `f̂(x, u)` and MLAC and RMAC need `∂f̂/∂u`, so the action is an input too, with 9
///   centres as every other input (729 RBFs).
/// * Not given in Chapter 4, taken from Chapter 3 (§3.6, Table 3.1 presets): `λ = 0.65`,
///   `σ = 1` on every step, and MLAC's saturation margin 0.1 of the RBF presets.
/// * `γ = 1`: Algorithms 4–6 have no discount.
/// * A greedy evaluation every 10 trials: the one after trial 600 is Table 4.1's "last
///   episode … carried out *without* exploration".
/// * Other systems (not in the thesis) take the same values with 9 centres along every
///   input.
///
/// The thesis used RBFs only for Chapter 4; LLR and tile coding have no finite-horizon
/// preset.
pub fn finite_horizon(
    system: SystemName,
    algo: Algo,
    approx: ApproxKind,
) -> Result<Preset, ConfigError> {
    if !algo.has_actor() {
        return Err(finite_horizon_unsupported(algo));
    }
    if approx != ApproxKind::Rbf {
        return Err(ConfigError::new(
            "approx",
            format!(
                "the finite-horizon presets (§4.4) use rbf; there is none for {algo} with {approx}"
            ),
        ));
    }
    let task = Task::new(system);
    let (n, m) = (task.state_dim(), task.action_dim());
    // Actor, critic, reference model: state and time; process model: state and action.
    let timed = vec![9; n + 1];
    let model = vec![9; n + m];
    let (actor, critic, model) = match algo {
        Algo::Sac => (rbf(0.05, timed.clone(), 0.55), rbf(0.2, timed, 0.55), None),
        Algo::Mlac => (
            rbf(0.15, timed.clone(), 0.55),
            rbf(0.4, timed, 0.65),
            Some(rbf(0.8, model, 0.75)),
        ),
        Algo::Rmac => (
            rbf(0.6, timed.clone(), 0.7),
            rbf(0.2, timed, 0.7),
            Some(rbf(0.6, model, 0.6)),
        ),
        Algo::Vgbp | Algo::Sarsa => unreachable!("rejected above"),
    };
    let agent = AgentConfig {
        algo,
        approx,
        horizon: HorizonKind::Finite,
        learning: LearningConfig {
            gamma: 1.0,
            lambda: 0.65,
            sigma: 1.0,
            explore_every: 1,
            saturation_margin: 0.1,
            bounded_actor: true,
        },
        actor: Some(actor),
        critic,
        model,
        vgbp: None,
        sarsa: None,
    };
    Ok(Preset {
        agent,
        run: run_section(600, 20, 10),
    })
}

/// VGBP's look-ahead iterations in the presets without the action search
/// ([`VGBP_ACTION_GRID`]: VGBP-RBF, VGBP-LLR, the §6.4.2 manipulator). Eq. 6.21 takes
/// `∂V/∂x` at the current state; two iterations at the predicted next state, keeping the
/// iterate with the best right-hand side of Eq. 6.6, improved VGBP-LSTD on the pendulum
/// (`rig learn --algo vgbp --approx lstd`, 20 runs × 200 trials, seed 1, mean greedy
/// return, before the model's neighbours were chosen by the state): trial 20
/// −1802 → −1255, trial 40 −1139 → −1033, mean of the last three evaluations −1074 →
/// −926. One iteration: −918, four: −875 (6 runs each; odd counts without the best-of
/// choice oscillate between the extreme actions). With the neighbours chosen by the state
/// (Algorithm 7 line 12): two iterations −1367 / −934, none −1627 / −1143 (trial 20 /
/// last three; the trial-20 means are dominated by one or two runs spinning the pendulum
/// in that evaluation, the medians are −1054 and −1163).
pub const VGBP_LOOKAHEAD: u32 = 2;

/// Action levels of VGBP's search of Eq. 6.6 ([`crate::vgbp`], "Search") in the
/// VGBP-LSTD pendulum preset, which starts it from Eq. 6.21 as printed (no look-ahead):
/// 0.1 V steps over ±3 V, the action resolution of `rig optimal`. Measured (20 runs ×
/// 200 trials, mean greedy return at trial 20 / mean of each run's last three
/// evaluations, seed 1): Eq. 6.21 −1627 / −1143, with two look-ahead iterations
/// −1367 / −934, with the search −1265 / −847 (median at trial 20 −989; worst run's
/// last three −944); seed 2: look-ahead −1764 / −915, search −958 / −855. The search is not
/// used on the 4-dimensional manipulator, where a 2-component search costs about four
/// times the run time (5 runs: −10 930 / −5576 against −9647 / −6599 over 20 runs
/// without it), nor in the presets whose critics it was not measured with.
pub const VGBP_ACTION_GRID: u32 = 61;

/// Chapter 6's critic-only learners on the pendulum (§6.4.1, Tables 6.1 and 6.2): 200
/// trials, 20 runs, `γ = 0.97`, `σ = 1`, exploration once every three steps.
///
/// * VGBP's process model: LLR, `N = 2500`, `K = 30`, `W = [1, 0.1, 1]` (Table 6.2).
/// * VGBP-LSTD: 20 × 20 RBFs with intersection 0.5 (the grid of SARSA), `λ = 0.3`,
///   `A_0 = 0.5 I` (§6.4.1, "LSTD Critic").
/// * VGBP-LLR: the critic of Table 6.2, `α_c = 0.1`, `N = 2000`, `K = 20`, `λ = 0.65`.
/// * VGBP with an RBF TD(λ) critic (not in the thesis): the LSTD grid with `α_c = 0.3`,
///   `λ = 0.65`.
/// * VGBP's action: VGBP-LSTD on the pendulum maximises Eq. 6.6 by a search over
///   [`VGBP_ACTION_GRID`] levels, from Eq. 6.21 as printed; the other VGBP presets take
///   Eq. 6.21 refined by [`VGBP_LOOKAHEAD`] look-ahead iterations (see [`crate::vgbp`]);
///   `lookahead = 0` and `grid = 0` is Eq. 6.21 exactly as printed.
/// * SARSA: 20 × 20 RBFs with intersection 0.5, actions `{−3, 0, 3}`, `α = 0.5`,
///   `λ = 0.85`, `ε = max(0.1, 0.96^(trial−1))` (§6.4.1, "SARSA").
///
/// * The §6.4.2 manipulator (`arm-6.4`, Tables 6.3 and 6.4): process model LLR
///   `N = 5000`, `K = 80`, `W = [1, 1, 0.05, 0.05, 5, 5]` (in this crate's state order
///   `[φ₁, φ₂, φ̇₁, φ̇₂]`); critic grid 5 × 5 × 3 × 3 (angles × velocities); `σ = 0.05`;
///   a greedy evaluation after every sequence of the four start states (`eval_every = 4`,
///   the mean over the four). The thesis gives no trial count: 200 trials.
///
/// The RBF grids cover the task's state range (`φ̇ ∈ [−8π, 8π]` on the pendulum; the
/// thesis's SARSA grid spans ±25 rad/s, 0.5 % narrower). Other systems take the same
/// values with the grid and scaling per state component as for the actor-critics.
fn critic_only(system: SystemName, algo: Algo, approx: ApproxKind) -> Preset {
    let task = Task::new(system);
    let n = task.state_dim();
    let arm_6_4 = system == SystemName::Arm64;
    let (w_state, w_model) = input_scaling(system);
    // 20 × 20 on the pendulum; 5 per angle and 3 per velocity on the arms (Table 6.4).
    let grid: Vec<usize> = if n == 2 {
        vec![20, 20]
    } else {
        vec![5, 5, 3, 3]
    };
    let (critic, lambda) = match (algo, approx) {
        (Algo::Vgbp, ApproxKind::Lstd) => (
            Component::Lstd(LstdConfig {
                centres: grid.clone(),
                intersection: 0.5,
                initial_a: 0.5,
                prior: LstdPrior::Zero,
            }),
            0.3,
        ),
        (Algo::Vgbp, ApproxKind::Llr) => (llr_critic(0.1, 2000, 20, w_state.clone()), 0.65),
        (Algo::Vgbp, _) => (rbf(0.3, grid.clone(), 0.5), 0.65),
        (_, _) => (rbf(0.5, grid.clone(), 0.5), 0.85),
    };
    let vgbp = algo == Algo::Vgbp;
    let agent = AgentConfig {
        algo,
        approx,
        horizon: HorizonKind::Infinite,
        learning: LearningConfig {
            gamma: 0.97,
            lambda,
            sigma: match (vgbp, arm_6_4) {
                (false, _) => 0.0,
                (true, false) => 1.0,
                (true, true) => 0.05,
            },
            explore_every: if vgbp { 3 } else { 1 },
            saturation_margin: 0.0,
            bounded_actor: true,
        },
        actor: None,
        critic,
        model: vgbp.then(|| {
            if arm_6_4 {
                llr_model(5000, 80, w_model)
            } else {
                llr_model(2500, 30, w_model)
            }
        }),
        vgbp: vgbp.then(|| {
            let search = system == SystemName::Pendulum && approx == ApproxKind::Lstd;
            VgbpConfig {
                lookahead: if search { 0 } else { VGBP_LOOKAHEAD },
                grid: if search { VGBP_ACTION_GRID } else { 0 },
                // VGBP-RBF (not in the thesis) measured worse with the model fitted at
                // the state: 20 runs, trial 20 / last three −1277 / −915 → −2087 / −1268.
                fit_at_zero_action: approx == ApproxKind::Rbf,
            }
        }),
        sarsa: (!vgbp).then(|| SarsaConfig {
            actions: vec![task.action_low[0], 0.0, task.action_high[0]],
            epsilon_decay: 0.96,
            epsilon_min: 0.1,
        }),
    };
    // One greedy evaluation per sequence of the four start states (§6.4.2).
    let eval_every = if arm_6_4 { 4 } else { 5 };
    Preset {
        agent,
        run: run_section(200, 20, eval_every),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_supported_preset_validates() {
        for system in SystemName::ALL {
            for algo in Algo::ALL {
                for approx in ApproxKind::ALL {
                    for horizon in HorizonKind::ALL {
                        let supported = algo.approximators().contains(&approx)
                            && (horizon == HorizonKind::Infinite
                                || (algo.has_actor() && approx == ApproxKind::Rbf));
                        let task = Task::new(system);
                        match preset(system, algo, approx, horizon) {
                            Ok(p) => p
                                .agent
                                .validate(&task)
                                .and_then(|()| p.run.validate(&task))
                                .unwrap_or_else(|e| {
                                    panic!("{system}/{algo}/{approx}/{horizon}: {e}")
                                }),
                            Err(e) => assert!(!supported, "{e}"),
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn finite_horizon_presets_are_those_of_section_4_4() {
        let rates = |algo| {
            let Preset { agent: c, run } = preset(
                SystemName::Pendulum,
                algo,
                ApproxKind::Rbf,
                HorizonKind::Finite,
            )
            .unwrap();
            assert_eq!((run.trials, run.runs, c.learning.gamma), (600, 20, 1.0));
            let Some(Component::Rbf(a)) = c.actor else {
                panic!()
            };
            let Component::Rbf(v) = c.critic else {
                panic!()
            };
            assert_eq!((&a.centres, &v.centres), (&vec![9; 3], &vec![9; 3]));
            let p = c.model.map(|m| m.alpha());
            (a.alpha, v.alpha, p, a.intersection, v.intersection)
        };
        assert_eq!(rates(Algo::Sac), (0.05, 0.2, None, 0.55, 0.55));
        assert_eq!(rates(Algo::Mlac), (0.15, 0.4, Some(0.8), 0.55, 0.65));
        assert_eq!(rates(Algo::Rmac), (0.6, 0.2, Some(0.6), 0.7, 0.7));
    }
}
