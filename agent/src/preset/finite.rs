//! Chapter 4's finite-horizon presets (§4.4).

use plant::config::ConfigError;
use plant::{SystemName, Task};

use super::components::rbf;
use super::{Preset, run_section};
use crate::config::{
    AgentConfig, Algo, ApproxKind, HorizonKind, LearningConfig, finite_horizon_unsupported,
};

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
        Algo::Vgbp | Algo::Sarsa => return Err(finite_horizon_unsupported(algo)),
    };
    if approx != ApproxKind::Rbf {
        return Err(ConfigError::new(
            "approx",
            format!(
                "the finite-horizon presets (§4.4) use rbf; there is none for {algo} with {approx}"
            ),
        ));
    }
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
        planning: None,
        lqr: None,
    };
    Ok(Preset {
        agent,
        run: run_section(600, 20, 10),
    })
}
