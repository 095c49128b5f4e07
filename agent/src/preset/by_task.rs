//! The learner a task gets when none is named: chosen from the task itself, for a task
//! the rig does not simulate (a task file without `[simulation]`; the thesis's systems
//! keep their presets).
//!
//! The task says what kind of problem it is, and each kind has the learner that solved
//! it on the systems the rules were chosen on (docs/results/systems.md):
//!
//! | kind | what the task says | learner |
//! |---|---|---|
//! | [`TaskKind::Goal`] | its reward has no state cost: a region is reached, no reference held | MLAC/LLR ([`rules`]) |
//! | [`TaskKind::Balance`] | every start lies within [`BALANCE_ANGLE`] of the reward's reference in every angle | MLAC/LLR, its actions from the LQR of its learned model ([`crate::lqr`]) |
//! | [`TaskKind::SwingUp`] | a start lies further from the reference | MLAC/LLR, its actions planned by the iterative LQR with its learned model ([`crate::ilqr`]), each plan started from the regulator's rollout where that predicts less cost |
//!
//! Near the reference the learned model's local fit is the linear model a regulator
//! needs, and the regulator acts well from the first trials on; far from it no linear
//! controller reaches it, and a plan through the model's nonlinear fits does. Neither
//! plans for a reward of a state region alone (no state cost): there MLAC's actor and
//! critic learn as the thesis has them.
//!
//! The regulator's and the planner's costs are the reward's quadratic approximation at the
//! reference: they need a cost on every action (`P > 0`). A task without one is refused
//! in one line that says what to add to its `[reward]`.

use plant::angle::wrap;
use plant::config::ConfigError;
use plant::reward::Term;
use plant::start::StartDistribution;
use plant::{Reward, Task};

use super::{Preset, for_task};
use crate::config::{
    Algo, ApproxKind, Component, EvictionRule, HorizonKind, LqrConfig, PlanningConfig,
    PlanningMethod,
};

/// The largest angle error from the reference at which a task still starts near it:
/// `π/6`, where `sin e` is within 5 % of `e` — the linear model the regulator assumes.
pub const BALANCE_ANGLE: f64 = std::f64::consts::FRAC_PI_6;

/// What kind of control problem a task is, as its reward and its starts say.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskKind {
    /// Reach a region: the reward has no state cost to regulate.
    Goal,
    /// Hold the reward's reference from starts near it.
    Balance,
    /// Bring the system to the reward's reference from far away, and hold it there.
    SwingUp,
}

/// The learner chosen for a task, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// The task's kind.
    pub kind: TaskKind,
    /// The learner, in words: "MLAC/LLR with the LQR of its learned model".
    pub learner: &'static str,
    /// Why, in words: what of the task made it that kind.
    pub reason: String,
}

impl std::fmt::Display for Choice {
    /// One line: the learner and why, and how to choose another.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "learner: {} — {} (--algo or a configuration file chooses another)",
            self.learner, self.reason
        )
    }
}

/// The kind of `task` and the reason, in words.
pub fn kind(task: &Task) -> (TaskKind, String) {
    let reward = &task.reward;
    let cosine =
        |t: &Term| matches!(t, Term::Cosine { weights, .. } if weights.iter().any(|&w| w > 0.0));
    let state_cost = reward.q.iter().any(|&q| q > 0.0) || reward.terms.iter().any(cosine);
    if !state_cost {
        return (
            TaskKind::Goal,
            format!(
                "task \"{}\" has no state cost in its reward, a goal to reach",
                task.name
            ),
        );
    }
    let far = farthest_start_angle(task, reward);
    match far {
        None => (
            TaskKind::Balance,
            format!(
                "task \"{}\" has no angle and a reference to regulate to",
                task.name
            ),
        ),
        Some(e) if e <= BALANCE_ANGLE => (
            TaskKind::Balance,
            format!(
                "task \"{}\" starts within {e:.2} rad of its reward's reference (at most {BALANCE_ANGLE:.2}: a balance)",
                task.name
            ),
        ),
        Some(e) => (
            TaskKind::SwingUp,
            format!(
                "task \"{}\" starts up to {e:.2} rad from its reward's reference (more than {BALANCE_ANGLE:.2}: a swing-up)",
                task.name
            ),
        ),
    }
}

/// The learner for `task` (one without a simulation) when none is named, and why.
pub fn learner(task: &Task) -> Result<(Preset, Choice), ConfigError> {
    let (kind, reason) = kind(task);
    let mut preset = for_task(task, Algo::Mlac, ApproxKind::Llr, HorizonKind::Infinite)?;
    let learner = match kind {
        TaskKind::Goal => "MLAC/LLR",
        TaskKind::Balance => {
            needs_action_cost(task, "the LQR of its learned model")?;
            preset.agent.lqr = Some(LqrConfig::default());
            preset.agent.learning.gamma = preset.agent.learning.gamma.max(regulator_discount(task));
            "MLAC/LLR with the LQR of its learned model"
        }
        TaskKind::SwingUp => {
            needs_action_cost(task, "planning by the iterative LQR")?;
            preset.agent.planning = Some(planning(task));
            if let Some(model) = &mut preset.agent.model {
                remember_the_goal(model);
            }
            "MLAC/LLR planning by the iterative LQR with its learned model"
        }
    };
    Ok((
        preset,
        Choice {
            kind,
            learner,
            reason,
        },
    ))
}

/// The discount of a regulator: its horizon `Ts / (1 − γ)` the whole trial,
/// `γ = 1 − Ts / T_trial`. The discounted LQR's closed loop may grow by up to `γ^(−1/2)`
/// per sample (only `√γ (A − BK)` is certain to be stable): at most `e^(1/2)` over a
/// trial with this `γ`, where the rules' (a third of the trial) allow `e^(3/2)`. On the
/// acrobot's balance the rules' 0.95 let the state drift out of the upright band at three
/// of the first four evaluations; 0.983 held it from the tenth trial on, as 0.99 did.
pub fn regulator_discount(task: &Task) -> f64 {
    1.0 - task.ts / task.trial_seconds
}

/// The plan of a swing-up: a tenth of the trial ahead (the acrobot's measured 1 s of its
/// 10 s trials, docs/results/acrobot.md), [`PLAN_SAMPLES`] samples at most and fewest,
/// [`PLAN_ITERATIONS`] iterations per sample, each sample's search started from the best of
/// the last plan, the actor's rollout and the regulator's (the LQR of the model's fit at
/// the reference). The most is counted in samples, not seconds: the learned model predicts
/// one sample at a time and its errors compound with each (the Furuta pendulum's
/// swing-up, 8 s trials of 20 ms: plans of 40 samples never held it up in 60 trials, plans
/// of 20 held it from trial 20 on, docs/results/systems.md). The regulator's rollout is
/// the start the plan lacks near the reference: on the Furuta pendulum's swing-up, first
/// upright after 27–40 s of interaction with it, 61–118 s without (five seeds each,
/// docs/results/systems.md, "The regulator's rollout as a plan's start").
fn planning(task: &Task) -> PlanningConfig {
    let samples = (PLAN_FRACTION * task.trial_seconds / task.ts).round() as u32;
    PlanningConfig {
        method: PlanningMethod::Ilqr,
        horizon: samples.clamp(PLAN_SAMPLES.0, PLAN_SAMPLES.1),
        samples: None,
        elites: None,
        iterations: PLAN_ITERATIONS,
        start_from_regulator: true,
    }
}

/// The iterative LQR's iterations per sample of a swing-up's plan. With three, the
/// acrobot's swing-up was upright at 49 of 50 evaluations (the last ten of five seeds),
/// the one missed seed 4's last (the first link up, the second still swinging through
/// hanging); with five, at 50 of 50, for a median step 1.2–1.4 times longer
/// (docs/results/systems.md, "Iterations per sample of a swing-up's plan").
pub const PLAN_ITERATIONS: u32 = 5;

/// The part of a trial a swing-up's plan looks ahead.
pub const PLAN_FRACTION: f64 = 0.1;

/// The fewest and the most samples a swing-up's plan looks ahead.
pub const PLAN_SAMPLES: (u32, u32) = (10, 20);

/// A swing-up's process model keeps [`SWING_UP_MEMORY`] samples, a new one replacing the
/// most redundant: the few samples near the reference that the first swings leave would
/// be forgotten within a trial, oldest first (the acrobot's and the Furuta pendulum's
/// swing-ups, docs/results/systems.md).
fn remember_the_goal(model: &mut Component) {
    if let Component::Llr(l) = model {
        l.memory = l.memory.max(SWING_UP_MEMORY);
        l.eviction = EvictionRule::Redundant;
        l.redundancy_radius = SWING_UP_REDUNDANCY;
    }
}

/// The samples a swing-up's process model keeps.
pub const SWING_UP_MEMORY: usize = 8000;

/// The scaled distance within which a new sample replaces a stored one.
pub const SWING_UP_REDUNDANCY: f64 = 0.02;

/// The regulator's and the planner's cost needs `P > 0`: the error says what to add.
fn needs_action_cost(task: &Task, what: &str) -> Result<(), ConfigError> {
    let p = &task.reward.p;
    if p.iter().all(|&p| p > 0.0) {
        return Ok(());
    }
    let suggested: Vec<String> = p
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            if p > 0.0 {
                format!("{p}")
            } else {
                format!("{}", suggested_action_weight(task, j))
            }
        })
        .collect();
    Err(ConfigError::new(
        "reward.action_weights",
        format!(
            "task \"{}\" has no cost on every action ({:?}), which its default learner, MLAC/LLR with {what}, needs: add one to its [reward], e.g. action_weights = [{}], or name a learner with --algo",
            task.name,
            p,
            suggested.join(", ")
        ),
    ))
}

/// An action weight to suggest: the full action costs a hundredth of the largest state
/// weight per unit error, `P_j = 0.01 max_i Q_i / u_max,j²` (at least 10⁻⁶), rounded to
/// one significant digit.
fn suggested_action_weight(task: &Task, j: usize) -> f64 {
    let q = task.reward.q.iter().copied().fold(0.0, f64::max).max(1.0);
    let half = 0.5 * (task.action_high[j] - task.action_low[j]);
    let p = (0.01 * q / (half * half)).max(1e-6);
    let magnitude = 10f64.powf(p.log10().floor());
    (p / magnitude).round() * magnitude
}

/// The largest angle error from the reference over every start (`None`: no angle):
/// the fixed start states, and a start distribution's extent (a uniform's box, a
/// normal's three standard deviations either side of its mean).
fn farthest_start_angle(task: &Task, reward: &Reward) -> Option<f64> {
    let angles: Vec<usize> = (0..task.state_dim())
        .filter(|&i| task.angle_mask[i])
        .collect();
    if angles.is_empty() {
        return None;
    }
    let fixed = task
        .initial_states
        .iter()
        .flat_map(|x| angles.iter().map(move |&i| reward.error(x, i).abs()));
    let drawn = angles.iter().map(|&i| {
        let r = reward.reference[i];
        match &task.start_distribution {
            Some(StartDistribution::Uniform { low, high }) => farthest_in(low[i], high[i], r),
            Some(StartDistribution::Normal { mean, std }) => {
                farthest_in(mean[i] - 3.0 * std[i], mean[i] + 3.0 * std[i], r)
            }
            None => 0.0,
        }
    });
    Some(fixed.chain(drawn).fold(0.0, f64::max))
}

/// The largest angle error from `r` of an angle in `[lo, hi]`: `π` if the interval holds
/// the point opposite `r`, else the larger of its ends' errors.
fn farthest_in(lo: f64, hi: f64, r: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let opposite = r + PI;
    let k = ((lo - opposite) / TAU).ceil();
    if opposite + k * TAU <= hi {
        return PI;
    }
    wrap(lo - r).abs().max(wrap(hi - r).abs())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::FitAt;

    /// A cart-pole's shape: cart position and pole angle (upright 0), their velocities,
    /// a force within ±10 N; `starts` and `extra` complete it.
    fn cart_pole(starts: &str, reward: &str, extra: &str) -> Task {
        let text = format!(
            r#"
name = "cart"
sampling_time = 0.02
trial_seconds = 5
start_states = {starts}
[[state]]
name = "x"
range = [-2.4, 2.4]
[[state]]
name = "theta"
angle = true
[[state]]
name = "x_dot"
range = [-5, 5]
[[state]]
name = "theta_dot"
range = ["-4pi", "4pi"]
[[action]]
name = "f"
low = -10
high = 10
[reward]
{reward}
{extra}
"#
        );
        plant::TaskFile::parse(&text, None)
            .and_then(|f| f.task(None))
            .unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    const QUADRATIC: &str = "state_weights = [1, 5, 0.1, 0.1]\naction_weights = [0.01]";

    #[test]
    fn a_task_starting_near_its_reference_is_a_balance_and_gets_the_regulator() {
        let task = cart_pole("[[0, 0.1, 0, 0], [0, -0.1, 0, 0]]", QUADRATIC, "");
        let (kind, why) = kind(&task);
        assert_eq!(kind, TaskKind::Balance, "{why}");
        let (preset, choice) = learner(&task).unwrap();
        assert_eq!(choice.kind, TaskKind::Balance);
        assert_eq!(preset.agent.algo, Algo::Mlac);
        assert_eq!(preset.agent.approx, ApproxKind::Llr);
        let lqr = preset.agent.lqr.as_ref().expect("a regulator");
        assert_eq!((lqr.region.as_ref(), lqr.fit_at), (None, FitAt::Reference));
        assert!(preset.agent.planning.is_none());
        // The whole 5 s trial at 20 ms: 1 − 1/250.
        assert!((preset.agent.learning.gamma - 0.996).abs() < 1e-12);
        preset.agent.validate(&task).unwrap();
        let line = choice.to_string();
        assert!(line.contains("LQR") && line.contains("0.10 rad"), "{line}");
    }

    #[test]
    fn a_task_starting_far_from_its_reference_is_a_swing_up_and_plans() {
        let task = cart_pole("[[0, \"pi\", 0, 0]]", QUADRATIC, "");
        let (preset, choice) = learner(&task).unwrap();
        assert_eq!(choice.kind, TaskKind::SwingUp, "{choice}");
        let planning = preset.agent.planning.as_ref().expect("a planner");
        assert_eq!(planning.method, PlanningMethod::Ilqr);
        // A tenth of the 5 s trial at 20 ms, 25 samples, is more than the most, 20.
        assert_eq!(planning.horizon, 20);
        assert!(planning.start_from_regulator);
        assert!(preset.agent.lqr.is_none());
        let Some(Component::Llr(model)) = &preset.agent.model else {
            panic!("an LLR model")
        };
        assert_eq!(model.memory, SWING_UP_MEMORY);
        assert_eq!(model.eviction, EvictionRule::Redundant);
        preset.agent.validate(&task).unwrap();
    }

    #[test]
    fn a_start_distribution_counts_by_its_extent() {
        let near = "[start_distribution]\nkind = \"uniform\"\nlow = [-1, -0.2, 0, 0]\nhigh = [1, 0.2, 0, 0]";
        let task = cart_pole("[[0, 0, 0, 0]]", QUADRATIC, near);
        assert_eq!(kind(&task).0, TaskKind::Balance);
        let around = near.replace("-0.2", "\"-pi\"").replace(" 0.2", " \"pi\"");
        let task = cart_pole("[[0, 0, 0, 0]]", QUADRATIC, &around);
        assert_eq!(kind(&task).0, TaskKind::SwingUp);
        let normal =
            "[start_distribution]\nkind = \"normal\"\nmean = [0, 0, 0, 0]\nstd = [0, 0.2, 0, 0]";
        let task = cart_pole("[[0, 0, 0, 0]]", QUADRATIC, normal);
        assert_eq!(kind(&task).0, TaskKind::SwingUp, "3 σ = 0.6 rad > π/6");
    }

    #[test]
    fn the_farthest_angle_of_an_interval_is_opposite_the_reference_when_it_holds_it() {
        use std::f64::consts::PI;
        assert_eq!(farthest_in(-0.1, 0.2, 0.0), 0.2);
        assert_eq!(farthest_in(3.0, 3.5, 0.0), PI);
        assert_eq!(farthest_in(-3.5, -3.0, 0.0), PI);
        assert!((farthest_in(0.9 * PI, 1.1 * PI, PI) - 0.1 * PI).abs() < 1e-12);
        assert_eq!(farthest_in(-10.0, 10.0, 1.0), PI);
    }

    #[test]
    fn a_reward_without_a_state_cost_is_a_goal_and_keeps_mlac() {
        let goal = "[goal]\nlow = [2, -inf, -inf, -inf]\nhigh = [inf, inf, inf, inf]\nreward = 100";
        let task = cart_pole(
            "[[0, \"pi\", 0, 0]]",
            "state_weights = [0, 0, 0, 0]\naction_weights = [0]",
            goal,
        );
        let (preset, choice) = learner(&task).unwrap();
        assert_eq!(choice.kind, TaskKind::Goal, "{choice}");
        assert!(preset.agent.lqr.is_none() && preset.agent.planning.is_none());
        assert_eq!(
            preset,
            for_task(&task, Algo::Mlac, ApproxKind::Llr, HorizonKind::Infinite).unwrap()
        );
    }

    #[test]
    fn a_periodic_angle_cost_is_a_state_cost() {
        let task = cart_pole(
            "[[0, \"pi\", 0, 0]]",
            "state_weights = [0, 0, 0, 0]\naction_weights = [0.01]\ncosine_weights = [0, 1, 0, 0]",
            "",
        );
        assert_eq!(kind(&task).0, TaskKind::SwingUp);
    }

    #[test]
    fn a_regulator_without_an_action_cost_is_refused_with_what_to_add() {
        let task = cart_pole(
            "[[0, 0.1, 0, 0]]",
            "state_weights = [1, 5, 0.1, 0.1]\naction_weights = [0]",
            "",
        );
        let e = learner(&task).unwrap_err();
        assert_eq!(e.key, "reward.action_weights");
        // 0.01 × 5 / 10² = 5e-4.
        assert!(e.message.contains("action_weights = [0.0005]"), "{e}");
        assert!(!e.message.contains('\n'), "one line: {e}");
    }
}
