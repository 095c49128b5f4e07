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
mod tests;
