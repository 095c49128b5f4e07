//! A task file's values checked against their allowed ranges and each other's
//! dimensions, key by key.

use std::f64::consts::PI;

use super::{MAX_NAME, MAX_STATES, Number, RangeSpec, RewardSpec, SimulationSpec, TaskFile};
use crate::config::{ConfigError, check_float, check_int, check_len};
use crate::reward::Term;
use crate::start::StartDistribution;
use crate::task::{Goal, Simulation};

mod goals;
mod start;

/// The checked values of a task file, as plain numbers.
pub(super) struct Checked {
    pub ts: f64,
    pub trial_seconds: f64,
    pub angle_mask: Vec<bool>,
    pub state_range: Vec<(f64, f64)>,
    pub action_low: Vec<f64>,
    pub action_high: Vec<f64>,
    pub start_states: Vec<Vec<f64>>,
    pub reward: Weights,
    pub operating_range: Option<(Vec<(f64, f64)>, f64)>,
    pub goal: Option<Goal>,
    pub start_distribution: Option<StartDistribution>,
}

/// The reward's weights, reference and further terms.
pub(super) struct Weights {
    pub state: Vec<f64>,
    pub action: Vec<f64>,
    pub reference: Vec<f64>,
    pub terminal: Vec<f64>,
    pub terms: Vec<Term>,
}

/// `(low, high)` per component.
type Bounds = Vec<(f64, f64)>;

/// The longest trial, in samples.
const MAX_STEPS: f64 = 1e7;

impl Checked {
    pub fn of(f: &TaskFile) -> Result<Self, ConfigError> {
        check_name("name", &f.name, MAX_NAME)?;
        let ts = f.sampling_time.0;
        check_float("sampling_time", ts, 0.0, 60.0, true)?;
        let trial_seconds = f.trial_seconds.0;
        check_float("trial_seconds", trial_seconds, ts, ts * MAX_STEPS, false)?;
        let (angle_mask, state_range) = states(f)?;
        let (action_low, action_high) = actions(f)?;
        let n = angle_mask.len();
        let mut reward = weights(&f.reward, n, action_low.len())?;
        reward.terms = terms(&f.reward, &angle_mask, &reward.reference, action_low.len())?;
        let operating_range = f
            .operating_range
            .as_ref()
            .map(|r| range(r, n))
            .transpose()?;
        let start_states = start_states(f, n, operating_range.as_ref())?;
        let goal = f.goal.as_ref().map(|g| goals::terminal(g, n)).transpose()?;
        let start_distribution = f
            .start_distribution
            .as_ref()
            .map(|s| start::distribution(s, n, operating_range.as_ref()))
            .transpose()?;
        Ok(Self {
            goal,
            start_distribution,
            ts,
            trial_seconds,
            angle_mask,
            state_range,
            action_low,
            action_high,
            start_states,
            reward,
            operating_range,
        })
    }

    /// The simulation, whose dynamics must have the task's dimensions.
    pub fn simulation(&self, s: &SimulationSpec) -> Result<Simulation, ConfigError> {
        check_int("simulation.substeps", s.substeps.into(), 1, 10_000)?;
        let sim = Simulation::of(s.system, s.substeps as usize);
        let (n, m) = (sim.dynamics.state_dim(), sim.dynamics.action_dim());
        if (n, m) != (self.angle_mask.len(), self.action_low.len()) {
            return Err(ConfigError::new(
                "simulation.system",
                format!(
                    "\"{}\" has {n} states and {m} actions; the task has {} and {}",
                    s.system,
                    self.angle_mask.len(),
                    self.action_low.len()
                ),
            ));
        }
        Ok(sim)
    }
}

/// A name of letters, digits, `-`, `_`, `.`, not empty, at most `max` bytes.
fn check_name(key: &str, name: &str, max: usize) -> Result<(), ConfigError> {
    let ok = |c: char| c.is_ascii_alphanumeric() || "-_.".contains(c);
    if name.is_empty() || name.len() > max || !name.chars().all(ok) {
        return Err(ConfigError::new(
            key,
            format!("\"{name}\" must be 1 to {max} ASCII letters, digits, '-', '_' or '.'"),
        ));
    }
    Ok(())
}

/// The angle mask and the approximators' ranges of `[[state]]`.
fn states(f: &TaskFile) -> Result<(Vec<bool>, Bounds), ConfigError> {
    check_int("state", f.state.len() as u64, 1, MAX_STATES as u64).map_err(|_| {
        ConfigError::new(
            "state",
            format!(
                "has {} entries; a task has 1 to {MAX_STATES} [[state]] tables",
                f.state.len()
            ),
        )
    })?;
    let mut ranges = Vec::with_capacity(f.state.len());
    for (i, s) in f.state.iter().enumerate() {
        check_name(&format!("state[{i}].name"), &s.name, 32)?;
        if f.state[..i].iter().any(|o| o.name == s.name) {
            return Err(ConfigError::new(
                &format!("state[{i}].name"),
                format!("\"{}\" names two states: names must differ", s.name),
            ));
        }
        let key = format!("state[{i}].range");
        let (lo, hi) = match (&s.range, s.angle) {
            (Some([lo, hi]), _) => (lo.0, hi.0),
            (None, true) => (-PI, PI),
            (None, false) => {
                return Err(ConfigError::new(
                    &key,
                    "is missing: a state that is not an angle needs [low, high], the range its approximators cover",
                ));
            }
        };
        check_bounds(&key, lo, hi, false)?;
        ranges.push((lo, hi));
    }
    Ok((f.state.iter().map(|s| s.angle).collect(), ranges))
}

/// The action bounds of `[[action]]`.
fn actions(f: &TaskFile) -> Result<(Vec<f64>, Vec<f64>), ConfigError> {
    let max = crate::MAX_ACTION;
    if f.action.is_empty() || f.action.len() > max {
        return Err(ConfigError::new(
            "action",
            format!(
                "has {} entries; a task has 1 to {max} [[action]] tables",
                f.action.len()
            ),
        ));
    }
    for (i, a) in f.action.iter().enumerate() {
        check_name(&format!("action[{i}].name"), &a.name, 32)?;
        check_bounds(&format!("action[{i}].low"), a.low.0, a.high.0, false)?;
    }
    Ok((
        f.action.iter().map(|a| a.low.0).collect(),
        f.action.iter().map(|a| a.high.0).collect(),
    ))
}

/// `lo < hi`, both finite (or, with `infinite`, possibly infinite); the error names
/// `key`.
pub(super) fn check_bounds(key: &str, lo: f64, hi: f64, infinite: bool) -> Result<(), ConfigError> {
    let ok = |v: f64| v.is_finite() || (infinite && v.is_infinite());
    if !(ok(lo) && ok(hi)) {
        let what = if infinite {
            "numbers or ±inf"
        } else {
            "finite numbers"
        };
        return Err(ConfigError::new(
            key,
            format!("[{lo}, {hi}]: the bounds must be {what}"),
        ));
    }
    if lo >= hi {
        return Err(ConfigError::new(
            key,
            format!("[{lo}, {hi}]: the lower bound must be below the upper"),
        ));
    }
    Ok(())
}

/// `values` as plain numbers: `n` of them (one per `what`), each finite and, with
/// `non_negative`, at least 0.
pub(super) fn vector(
    key: &str,
    values: &[Number],
    n: usize,
    what: &str,
    non_negative: bool,
) -> Result<Vec<f64>, ConfigError> {
    check_len(key, values.len(), n, what)?;
    for (i, v) in values.iter().enumerate() {
        finite(&format!("{key}[{i}]"), v.0, non_negative)?;
    }
    Ok(values.iter().map(|v| v.0).collect())
}

/// `v` is finite (and, with `non_negative`, at least 0).
pub(super) fn finite(key: &str, v: f64, non_negative: bool) -> Result<(), ConfigError> {
    match (v.is_finite(), non_negative && v < 0.0) {
        (true, false) => Ok(()),
        (_, true) => Err(ConfigError::new(
            key,
            format!("{v} must be a finite number ≥ 0"),
        )),
        (false, _) => Err(ConfigError::new(
            key,
            format!("{v} must be a finite number"),
        )),
    }
}

/// `[reward]`: the weights' sizes and signs.
fn weights(r: &RewardSpec, n: usize, m: usize) -> Result<Weights, ConfigError> {
    let state = vector("reward.state_weights", &r.state_weights, n, "state", true)?;
    let action = vector(
        "reward.action_weights",
        &r.action_weights,
        m,
        "action",
        true,
    )?;
    let reference = match &r.reference {
        Some(v) => vector("reward.reference", v, n, "state", false)?,
        None => vec![0.0; n],
    };
    let terminal = match &r.terminal_weights {
        Some(v) => vector("reward.terminal_weights", v, n, "state", true)?,
        None => state.clone(),
    };
    Ok(Weights {
        state,
        action,
        reference,
        terminal,
        terms: Vec::new(),
    })
}

/// The reward's terms beyond the quadratic form, in the order the hash takes them:
/// periodic, absolute action cost, goal bonus.
fn terms(
    r: &RewardSpec,
    angles: &[bool],
    reference: &[f64],
    m: usize,
) -> Result<Vec<Term>, ConfigError> {
    let mut terms = Vec::new();
    if let Some(w) = &r.cosine_weights {
        let key = "reward.cosine_weights";
        let weights = vector(key, w, angles.len(), "state", true)?;
        if let Some(i) = (0..weights.len()).find(|&i| weights[i] != 0.0 && !angles[i]) {
            return Err(ConfigError::new(
                &format!("{key}[{i}]"),
                format!(
                    "{} weighs a state that is not an angle: 1 − cos applies to angles only; give 0",
                    weights[i]
                ),
            ));
        }
        terms.push(Term::Cosine {
            weights,
            reference: reference.to_vec(),
        });
    }
    if let Some(c) = &r.action_abs_weights {
        let weights = vector("reward.action_abs_weights", c, m, "action", true)?;
        terms.push(Term::AbsAction { weights });
    }
    if let Some(g) = &r.goal {
        terms.push(goals::bonus(g, angles)?);
    }
    Ok(terms)
}

/// `[operating_range]`: bounds per state component and a finite penalty.
fn range(r: &RangeSpec, n: usize) -> Result<(Vec<(f64, f64)>, f64), ConfigError> {
    check_len("operating_range.low", r.low.len(), n, "state")?;
    check_len("operating_range.high", r.high.len(), n, "state")?;
    let mut limits = Vec::with_capacity(n);
    for (i, (lo, hi)) in r.low.iter().zip(&r.high).enumerate() {
        check_bounds(&format!("operating_range[{i}]"), lo.0, hi.0, true)?;
        limits.push((lo.0, hi.0));
    }
    let penalty = r.penalty.0;
    finite("operating_range.penalty", penalty, false)?;
    if penalty > 0.0 {
        return Err(ConfigError::new(
            "operating_range.penalty",
            format!(
                "{penalty} must be a finite number ≤ 0: it is the reward of leaving the range, a failure; reward a region with [goal]'s `reward` (reaching it ends the trial) or [reward.goal]'s `bonus` (per sample inside)"
            ),
        ));
    }
    Ok((limits, penalty))
}

/// `start_states`: at least one, each with `n` finite components inside the operating
/// range.
fn start_states(
    f: &TaskFile,
    n: usize,
    range: Option<&(Vec<(f64, f64)>, f64)>,
) -> Result<Vec<Vec<f64>>, ConfigError> {
    if f.start_states.is_empty() {
        return Err(ConfigError::new(
            "start_states",
            "is empty: give at least one start state",
        ));
    }
    let mut starts = Vec::with_capacity(f.start_states.len());
    for (s, x0) in f.start_states.iter().enumerate() {
        let key = format!("start_states[{s}]");
        let x0 = vector(&key, x0, n, "state", false)?;
        if let Some((limits, _)) = range {
            for (i, (&v, &(lo, hi))) in x0.iter().zip(limits).enumerate() {
                check_float(&format!("{key}[{i}]"), v, lo, hi, false).map_err(|e| {
                    ConfigError::new(
                        &e.key,
                        format!("{v} lies outside the operating range [{lo}, {hi}]"),
                    )
                })?;
            }
        }
        starts.push(x0);
    }
    Ok(starts)
}
