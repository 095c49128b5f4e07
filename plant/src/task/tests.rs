//! The systems integrated: accuracy, energy, saturation, delays, the operating range.

use super::*;
use crate::Plant;
use crate::pendulum::Pendulum;
use std::f64::consts::PI;
use std::sync::Arc;

fn trajectory(task: Task, u: impl Fn(usize) -> f64) -> Vec<Vec<f64>> {
    let mut plant = Plant::new(Arc::new(task));
    let x0 = plant.task().initial_states[0].clone();
    plant.reset(&x0);
    let steps = plant.task().steps_per_trial();
    (0..steps)
        .map(|k| {
            plant.step(&[u(k)]);
            plant.state().to_vec()
        })
        .collect()
}

#[test]
fn halving_the_substep_changes_little() {
    // A 3 s swing with a sign-alternating input, so the trajectory is far from trivial.
    let u = |k: usize| {
        if (k / 20).is_multiple_of(2) {
            3.0
        } else {
            -3.0
        }
    };
    let coarse = trajectory(Task::pendulum(), u);
    let mut fine_task = Task::pendulum();
    fine_task.simulation.as_mut().unwrap().substeps *= 2;
    let fine = trajectory(fine_task, u);
    let max_dev = coarse
        .iter()
        .zip(&fine)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| wrap(p - q).abs()))
        .fold(0.0, f64::max);
    assert!(max_dev < 1e-6, "max deviation {max_dev}");
    // And the trajectory really moves: it leaves the bottom by more than a radian.
    assert!(coarse.iter().any(|x| x[0].abs() < PI - 1.0));
}

#[test]
fn undamped_pendulum_conserves_energy() {
    let p = Pendulum {
        damping: 0.0,
        torque_constant: 0.0,
        ..Pendulum::default()
    };
    let mut task = Task::pendulum();
    task.simulation.as_mut().unwrap().dynamics = Box::new(p.clone());
    task.initial_states = vec![vec![PI - 0.5, 0.0]];
    let e0 = p.energy(&task.initial_states[0]);
    let traj = trajectory(task, |_| 0.0);
    let max_err = traj
        .iter()
        .map(|x| (p.energy(x) - e0).abs())
        .fold(0.0, f64::max);
    // Relative to the potential-energy scale M g l.
    let scale = p.mass * p.gravity * p.length;
    assert!(
        max_err / scale < 1e-6,
        "relative energy drift {}",
        max_err / scale
    );
    assert!(
        traj.iter().any(|x| x[1].abs() > 1.0),
        "the pendulum must actually swing"
    );
}

/// A delayed period applies the action in effect first, then the new one; the reward
/// is ρ(x_k, u_k); without delay it is `Plant::step`.
#[test]
fn a_delayed_period_applies_the_previous_action_first() {
    let task = Arc::new(Task::pendulum());
    // x_1 with u_0 = −3 in effect.
    let start = || {
        let mut p = Plant::new(task.clone());
        p.reset(&[2.0, 1.0]);
        p.step(&[-3.0]);
        p
    };
    let x1 = start().state().to_vec();
    let mut undelayed = start();
    let r_now = undelayed.step(&[3.0]);
    let mut d0 = start();
    assert_eq!(d0.step_delayed(&[3.0], 0.0), r_now);
    assert_eq!(d0.state(), undelayed.state(), "no delay: Plant::step");
    let d = 0.01;
    let mut delayed = start();
    let r = delayed.step_delayed(&[3.0], d);
    let mut by_hand = start();
    by_hand.advance(&[-3.0], d);
    by_hand.advance(&[3.0], task.ts - d);
    assert_eq!(delayed.state(), by_hand.state());
    assert_eq!(r, task.reward.reward(&x1, &[3.0]), "ρ(x_k, u_k)");
    assert_ne!(delayed.state(), undelayed.state());
}

#[test]
fn actions_are_saturated_and_non_finite_rejected() {
    let mut plant = Plant::new(Arc::new(Task::pendulum()));
    plant.step(&[10.0]);
    assert_eq!(plant.applied_action(), &[3.0]);
    plant.step(&[-1e9]);
    assert_eq!(plant.applied_action(), &[-3.0]);
    plant.step(&[f64::NAN]);
    assert_eq!(plant.applied_action(), &[0.0]);
    plant.step(&[f64::INFINITY]);
    assert_eq!(plant.applied_action(), &[0.0]);
    let c = plant.safety().counts();
    assert_eq!((c.clamped, c.rejected), (2, 2));
    assert!(plant.state().iter().all(|v| v.is_finite()));
}

#[test]
fn advancing_in_pieces_matches_a_whole_step() {
    let task = Arc::new(Task::pendulum());
    let (mut whole, mut pieces) = (Plant::new(task.clone()), Plant::new(task));
    whole.reset(&[2.0, 1.0]);
    pieces.reset(&[2.0, 1.0]);
    whole.step(&[1.5]);
    pieces.advance(&[1.5], 0.0123);
    pieces.advance(&[1.5], 0.03 - 0.0123);
    for (a, b) in whole.state().iter().zip(pieces.state()) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    // A late action: the first part of the interval with the old one.
    pieces.advance(&[-3.0], 0.01);
    pieces.advance(&[9.0], 0.02);
    assert_eq!(pieces.applied_action(), &[3.0]);
}

/// The §6.4.2 manipulator under constant torques `u` from its first start state.
fn manipulator(substeps: usize, u: [f64; 2], seconds: f64) -> Vec<Vec<f64>> {
    let mut task = Task::new(SystemName::Arm64);
    task.simulation.as_mut().unwrap().substeps = substeps;
    task.operating_range = None;
    let mut plant = Plant::new(Arc::new(task));
    plant.reset(&[0.0; 4]);
    let steps = (seconds / 0.05).round() as usize;
    (0..steps)
        .map(|_| {
            plant.step(&u);
            plant.state().to_vec()
        })
        .collect()
}

#[test]
fn manipulator_6_4_integrates_accurately_and_is_friction_limited() {
    // The second link's time constant is ≈ 2.4 ms; 25 sub-steps of 2 ms must be
    // stable and as accurate as 50 of 1 ms.
    let u = [0.1, -0.1];
    let coarse = manipulator(25, u, 1.5);
    let fine = manipulator(50, u, 1.5);
    let max_dev = coarse
        .iter()
        .zip(&fine)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max);
    assert!(max_dev < 1e-6, "max deviation {max_dev}");
    // Friction limits the velocities to about the critic grid's ±0.8 rad/s.
    let x = coarse.last().unwrap();
    assert!(x[2] > 0.6 && x[2] < 0.9, "φ̇₁ = {}", x[2]);
    assert!(x[3].abs() < 3.0, "φ̇₂ = {}", x[3]);
}

#[test]
fn leaving_the_operating_range_ends_the_trial_with_the_penalty() {
    let mut plant = Plant::new(Arc::new(Task::new(SystemName::Arm64)));
    plant.reset(&[1.15, 0.0, 0.0, 0.0]);
    let mut rewards = Vec::new();
    while !plant.terminated() && rewards.len() < 200 {
        rewards.push(plant.step(&[0.1, 0.0]));
    }
    assert!(
        plant.terminated(),
        "pushed outward for 10 s without leaving"
    );
    assert!(plant.state()[0] > 1.2);
    let (last, before) = rewards.split_last().unwrap();
    assert_eq!(*last, -4e4);
    assert!(before.iter().all(|&r| r > -1e3 && r < 0.0));
    // A reset starts a fresh trial.
    plant.reset(&[0.0; 4]);
    assert!(!plant.terminated());
    assert!(plant.step(&[0.0, 0.0]) > -1e-12);
}

#[test]
fn reward_uses_state_before_transition_and_applied_action() {
    let mut plant = Plant::new(Arc::new(Task::pendulum()));
    plant.reset(&[PI, 0.0]);
    let r = plant.step(&[7.0]);
    assert!((r - (-5.0 * PI * PI - 9.0)).abs() < 1e-12);
}

#[test]
fn saturated_input_cannot_lift_the_pendulum_directly() {
    // §3.6: |u| ≤ 3 V makes a direct swing-up impossible. Constant +3 V balances
    // gravity 48° from the bottom (sin φ = (K/R)·3 / (M g l) = 0.75), so the step
    // response overshoots to at most ~96° from the bottom and never comes within 60°
    // of upright.
    let traj = trajectory(Task::pendulum(), |_| 3.0);
    assert!(traj.iter().all(|x| x[0].abs() > PI / 3.0));
    assert!(
        traj.iter().any(|x| x[0].abs() < PI / 2.0),
        "but it does pass the horizontal"
    );
}

#[test]
fn arm_horizontal_without_input_keeps_its_angles() {
    let task = Task::new(SystemName::ArmHorizontal);
    let mut plant = Plant::new(Arc::new(task));
    plant.reset(&[-3.0, 1.0, 0.0, 0.0]);
    for _ in 0..100 {
        plant.step(&[0.0, 0.0]);
    }
    assert!((plant.state()[0] + 3.0).abs() < 1e-12 && (plant.state()[1] - 1.0).abs() < 1e-12);
}

#[test]
fn arm_vertical_swings_without_input() {
    let mut plant = Plant::new(Arc::new(Task::new(SystemName::ArmVertical)));
    plant.reset(&[-1.1, 1.0, 0.0, 0.0]);
    let mut max_speed: f64 = 0.0;
    for _ in 0..200 {
        plant.step(&[0.0, 0.0]);
        max_speed = max_speed.max(plant.state()[2].abs());
    }
    assert!(max_speed > 0.5, "gravity must accelerate link 1");
}
