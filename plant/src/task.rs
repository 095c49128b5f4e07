//! Tasks: a system together with everything an experiment on it needs.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use crate::angle::wrap;
use crate::double_integrator::DoubleIntegrator;
use crate::pendulum::Pendulum;
use crate::two_link::TwoLink;
use crate::{Dynamics, QuadraticReward};

/// The systems an experiment can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SystemName {
    /// Pendulum swing-up, §3.6 and §6.4.1 (Appendix A.1).
    Pendulum,
    /// Two-link arm in the vertical plane, Case I (§5.3): inject damping.
    ArmVertical,
    /// Two-link arm in the horizontal plane, Case II (§5.4): reach a reference.
    ArmHorizontal,
    /// Linear double integrator with a quadratic reward (LQR check).
    DoubleIntegrator,
    /// The manipulator of §6.4.2 (Table 6.3): horizontal plane, `|u| ≤ 0.1 N m`, operating
    /// range ±1.2 rad (leaving it ends the trial with reward −4·10⁴), four start states.
    #[serde(rename = "arm-6.4")]
    Arm64,
}

impl SystemName {
    /// All systems, for `--help` texts and validation messages.
    pub const ALL: [SystemName; 5] = [
        SystemName::Pendulum,
        SystemName::ArmVertical,
        SystemName::ArmHorizontal,
        SystemName::Arm64,
        SystemName::DoubleIntegrator,
    ];

    /// The command-line / config spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            SystemName::Pendulum => "pendulum",
            SystemName::ArmVertical => "arm-vertical",
            SystemName::ArmHorizontal => "arm-horizontal",
            SystemName::DoubleIntegrator => "double-integrator",
            SystemName::Arm64 => "arm-6.4",
        }
    }
}

impl std::fmt::Display for SystemName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A system with its sampling, limits, reward and trial definition.
pub struct Task {
    /// Which system this is.
    pub name: SystemName,
    /// `ẋ = f(x, u)`.
    pub dynamics: Box<dyn Dynamics>,
    /// Sampling time `Ts` \[s\].
    pub ts: f64,
    /// RK4 sub-steps per sample period (see [`crate::rk4`]).
    pub substeps: usize,
    /// Lower action bounds.
    pub action_low: Vec<f64>,
    /// Upper action bounds.
    pub action_high: Vec<f64>,
    /// Which state components are angles (wrapped to [-π, π)).
    pub angle_mask: Vec<bool>,
    /// The reward `ρ(x, u)`.
    pub reward: QuadraticReward,
    /// Start states; trial `i` starts in `initial_states[i % len]`.
    pub initial_states: Vec<Vec<f64>>,
    /// Trial length \[s\].
    pub trial_seconds: f64,
    /// The region of the state space that parametric approximators cover (RBF grids,
    /// tilings): `(low, high)` per state component.
    pub state_range: Vec<(f64, f64)>,
    /// Short names of the state components, for files and plots.
    pub state_names: Vec<&'static str>,
    /// Where the system may go; leaving it ends the trial (§6.4.2). `None`: anywhere.
    pub operating_range: Option<OperatingRange>,
}

/// The operating range of a system with physical limits, and the penalty for leaving it.
#[derive(Clone, Debug, PartialEq)]
pub struct OperatingRange {
    /// `(low, high)` per state component; infinite bounds for unlimited components.
    pub limits: Vec<(f64, f64)>,
    /// The reward of the transition that leaves the range, which is the trial's last.
    pub penalty: f64,
}

impl OperatingRange {
    /// Whether `x` lies outside the range (a non-finite component counts as outside).
    pub fn excludes(&self, x: &[f64]) -> bool {
        x.iter()
            .zip(&self.limits)
            .any(|(&xi, &(lo, hi))| !(lo..=hi).contains(&xi))
    }
}

impl Task {
    /// The task for `name` with the thesis's settings.
    pub fn new(name: SystemName) -> Self {
        match name {
            SystemName::Pendulum => Self::pendulum(),
            SystemName::ArmVertical => Self::arm(
                name,
                TwoLink::vertical(),
                vec![-1.1, 1.0, 0.0, 0.0],
                vec![0.0; 4],
                6.0,
            ),
            SystemName::ArmHorizontal => Self::arm(
                name,
                TwoLink::horizontal(),
                vec![-3.0, 1.0, 0.0, 0.0],
                vec![1.1, -0.5, 0.0, 0.0],
                6.0,
            ),
            SystemName::DoubleIntegrator => Self::double_integrator(),
            SystemName::Arm64 => Self::manipulator_6_4(),
        }
    }

    /// Pendulum swing-up (§3.6, Table A.1): `Ts = 0.03 s`, `u ∈ [−3, 3] V`, 3 s trials
    /// from `[π, 0]`, reward Eq. 3.16 with `Q = diag(5, 0.1)`, `P = 1`. Parametric
    /// approximators cover `φ̇ ∈ [−8π, 8π]`, the bound footnote 4 of §3.6 assumes.
    pub fn pendulum() -> Self {
        Self {
            name: SystemName::Pendulum,
            dynamics: Box::new(Pendulum::default()),
            ts: 0.03,
            substeps: 20,
            action_low: vec![-3.0],
            action_high: vec![3.0],
            angle_mask: vec![true, false],
            reward: QuadraticReward {
                q: vec![5.0, 0.1],
                p: vec![1.0],
                reference: vec![0.0, 0.0],
                angle_mask: vec![true, false],
            },
            initial_states: vec![vec![PI, 0.0]],
            trial_seconds: 3.0,
            state_range: vec![(-PI, PI), (-8.0 * PI, 8.0 * PI)],
            state_names: vec!["phi", "phi_dot"],
            operating_range: None,
        }
    }

    /// Two-link arm of Chapter 5 (Table A.2), `Ts = 0.03 s`, reward Eq. 5.1/5.2 with
    /// `Q = diag(5, 5, 0.1, 0.1)`, `P = I`. The thesis gives no torque limit for this
    /// arm; ±1 N m is used here.
    fn arm(
        name: SystemName,
        arm: TwoLink,
        x0: Vec<f64>,
        reference: Vec<f64>,
        trial_seconds: f64,
    ) -> Self {
        let angle_mask = vec![true, true, false, false];
        Self {
            name,
            dynamics: Box::new(arm),
            ts: 0.03,
            substeps: 10,
            action_low: vec![-1.0, -1.0],
            action_high: vec![1.0, 1.0],
            angle_mask: angle_mask.clone(),
            reward: QuadraticReward {
                q: vec![5.0, 5.0, 0.1, 0.1],
                p: vec![1.0, 1.0],
                reference,
                angle_mask,
            },
            initial_states: vec![x0],
            trial_seconds,
            state_range: vec![
                (-PI, PI),
                (-PI, PI),
                (-2.0 * PI, 2.0 * PI),
                (-2.0 * PI, 2.0 * PI),
            ],
            state_names: vec!["phi1", "phi2", "phi1_dot", "phi2_dot"],
            operating_range: None,
        }
    }

    /// Double integrator: `Ts = 0.05 s`, `u ∈ [−5, 5] N`, `Q = diag(1, 0.1)`, `P = 0.1`,
    /// 3 s trials from `[1, 0]`.
    fn double_integrator() -> Self {
        Self {
            name: SystemName::DoubleIntegrator,
            dynamics: Box::new(DoubleIntegrator::default()),
            ts: 0.05,
            substeps: 1,
            action_low: vec![-5.0],
            action_high: vec![5.0],
            angle_mask: vec![false, false],
            reward: QuadraticReward {
                q: vec![1.0, 0.1],
                p: vec![0.1],
                reference: vec![0.0, 0.0],
                angle_mask: vec![false, false],
            },
            initial_states: vec![vec![1.0, 0.0]],
            trial_seconds: 3.0,
            state_range: vec![(-2.0, 2.0), (-2.0, 2.0)],
            state_names: vec!["p", "v"],
            operating_range: None,
        }
    }

    /// The manipulator of §6.4.2 ([`TwoLink::manipulator_6_4`], Table 6.3), with the
    /// state kept in this crate's order `x = [φ₁, φ₂, φ̇₁, φ̇₂]` (the thesis writes
    /// `[φ₁, φ̇₁, φ₂, φ̇₂]` there; every vector below is reordered accordingly):
    ///
    /// * `u ∈ [−0.1, 0.1]² N m`; reward Eq. 6.20 with `Q = diag(200, 50, 1, 1)`,
    ///   `P = diag(2, 2)`;
    /// * operating range `φ₁, φ₂ ∈ [−1.2, 1.2] rad`: leaving it gives reward −4·10⁴ and
    ///   ends the trial. Inside it the angles never wrap, so they are plain coordinates
    ///   (no angle mask: RBF grids over ±1.2 rad are not periodic);
    /// * trials of at most 10 s, starting in turn from `S₀ = {[1, 1, 0, 0], [1, −1, 0, 0],
    ///   [−1, 1, 0, 0], [−1, −1, 0, 0]}`;
    /// * `Ts = 0.05 s`: the text of §6.4.2 says 0.05 s and its discussion blames "the long
    ///   sampling time", Table 6.3 prints 0.01 s. 25 RK4 sub-steps of 2 ms keep the
    ///   friction-dominated second link (time constant ≈ 2.4 ms) stable and accurate;
    /// * the critic's grid covers `φ ∈ [−1.2, 1.2]`, `φ̇ ∈ [−0.8, 0.8]` (Table 6.4).
    fn manipulator_6_4() -> Self {
        let no_mask = vec![false; 4];
        Self {
            name: SystemName::Arm64,
            dynamics: Box::new(TwoLink::manipulator_6_4()),
            ts: 0.05,
            substeps: 25,
            action_low: vec![-0.1, -0.1],
            action_high: vec![0.1, 0.1],
            angle_mask: no_mask.clone(),
            reward: QuadraticReward {
                q: vec![200.0, 50.0, 1.0, 1.0],
                p: vec![2.0, 2.0],
                reference: vec![0.0; 4],
                angle_mask: no_mask,
            },
            initial_states: vec![
                vec![1.0, 1.0, 0.0, 0.0],
                vec![1.0, -1.0, 0.0, 0.0],
                vec![-1.0, 1.0, 0.0, 0.0],
                vec![-1.0, -1.0, 0.0, 0.0],
            ],
            trial_seconds: 10.0,
            state_range: vec![(-1.2, 1.2), (-1.2, 1.2), (-0.8, 0.8), (-0.8, 0.8)],
            state_names: vec!["phi1", "phi2", "phi1_dot", "phi2_dot"],
            operating_range: Some(OperatingRange {
                limits: vec![
                    (-1.2, 1.2),
                    (-1.2, 1.2),
                    (f64::NEG_INFINITY, f64::INFINITY),
                    (f64::NEG_INFINITY, f64::INFINITY),
                ],
                penalty: -4e4,
            }),
        }
    }

    /// State dimension `n`.
    pub fn state_dim(&self) -> usize {
        self.dynamics.state_dim()
    }

    /// Action dimension `m`.
    pub fn action_dim(&self) -> usize {
        self.dynamics.action_dim()
    }

    /// Samples per trial.
    pub fn steps_per_trial(&self) -> usize {
        (self.trial_seconds / self.ts).round() as usize
    }

    /// Simulated learning time after `trials` trials of which `skipped` samples were not
    /// run (trials that left the operating range end early) \[s\].
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
    /// zero (the safe action) if a component is not finite ([`crate::safety::Supervisor`]).
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
mod tests {
    use super::*;
    use crate::Plant;
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
        fine_task.substeps *= 2;
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
        task.dynamics = Box::new(p.clone());
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
        task.substeps = substeps;
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
}
