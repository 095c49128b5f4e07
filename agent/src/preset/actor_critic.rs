//! The actor-critic presets of Chapters 3 and 5 (Tables 3.1, 3.2, §5.3, §5.4): actor,
//! critic and model per system, algorithm and approximator.

use plant::config::ConfigError;
use plant::{SystemName, Task};

use super::components::{SAC_REDUNDANCY_RADIUS, llr, llr_critic, llr_model, rbf};
use super::input_scaling;
use crate::config::{Algo, ApproxKind, Component, TilesConfig};

/// The actor (or reference model), the critic and the process model of the
/// infinite-horizon preset for `(system, algo, approx)`; `algo` has an actor and
/// supports `approx` (else the error names `approx`).
pub(super) fn components(
    system: SystemName,
    algo: Algo,
    approx: ApproxKind,
) -> Result<(Component, Component, Option<Component>), ConfigError> {
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
                decay_trials: None,
                decay_power: None,
            }),
            Component::Tiles(TilesConfig {
                alpha: 0.1,
                tilings: 16,
                tiles: vec![7; n],
                decay_trials: None,
                decay_power: None,
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
        (Mlac | Rmac, Tiles) | (_, Lstd) | (Vgbp | Sarsa, _) => {
            return Err(ConfigError::new(
                "approx",
                format!("{algo} with {approx} has no actor-critic preset"),
            ));
        }
    };
    if (algo, approx) == (Sac, Llr) {
        for c in [&mut actor, &mut critic] {
            if let Component::Llr(l) = c {
                l.redundancy_radius = SAC_REDUNDANCY_RADIUS;
            }
        }
    }
    Ok((actor, critic, model))
}
