//! Goal regions checked: `[reward.goal]` (a bonus per sample inside) and `[goal]` (the
//! trial ends on reaching it, with its reward).

use super::{check_bounds, finite, vector};
use crate::config::ConfigError;
use crate::region::Region;
use crate::reward::Term;
use crate::task::Goal;
use crate::task::file::GoalSpec;

/// `[reward.goal]`: a region and its bonus (> 0), no `reward`.
pub(super) fn bonus(g: &GoalSpec, angles: &[bool]) -> Result<Term, ConfigError> {
    let key = "reward.goal";
    if g.reward.is_some() {
        return Err(ConfigError::new(
            &format!("{key}.reward"),
            "a bonus region takes `bonus`, the reward per sample inside; a goal that ends the trial with a reward is the task's [goal]",
        ));
    }
    let region = region(key, g, angles.len())?;
    let bonus = g.bonus.ok_or_else(|| {
        ConfigError::new(
            &format!("{key}.bonus"),
            "is missing: the reward per sample inside, a finite number > 0",
        )
    })?;
    finite(&format!("{key}.bonus"), bonus.0, false)?;
    if bonus.0 <= 0.0 {
        return Err(ConfigError::new(
            &format!("{key}.bonus"),
            format!("{} must be a finite number > 0", bonus.0),
        ));
    }
    Ok(Term::Goal {
        region,
        bonus: bonus.0,
        angles: angles.to_vec(),
    })
}

/// `[goal]`: a region and the reward of reaching it (finite), no `bonus`.
pub(super) fn terminal(g: &GoalSpec, n: usize) -> Result<Goal, ConfigError> {
    if g.bonus.is_some() {
        return Err(ConfigError::new(
            "goal.bonus",
            "[goal] ends the trial and takes `reward`, the reward of the transition that reaches it; a bonus per sample inside is [reward.goal]'s `bonus`",
        ));
    }
    let region = region("goal", g, n)?;
    let reward = g.reward.ok_or_else(|| {
        ConfigError::new(
            "goal.reward",
            "is missing: the reward of the transition that reaches the goal, a finite number",
        )
    })?;
    finite("goal.reward", reward.0, false)?;
    Ok(Goal {
        region,
        reward: reward.0,
    })
}

/// The region of `g`: a box (`low`, `high`: numbers or ±inf, `low < high`) or a ball
/// (`centre`: finite; `radius`: > 0 or inf), `n` numbers each.
fn region(key: &str, g: &GoalSpec, n: usize) -> Result<Region, ConfigError> {
    match (&g.low, &g.high, &g.centre, &g.radius) {
        (Some(low), Some(high), None, None) => {
            let low = numbers(&format!("{key}.low"), low, n)?;
            let high = numbers(&format!("{key}.high"), high, n)?;
            for i in 0..n {
                check_bounds(&format!("{key}[{i}]"), low[i], high[i], true)?;
            }
            Ok(Region::Box { low, high })
        }
        (None, None, Some(centre), Some(radius)) => {
            let centre = vector(&format!("{key}.centre"), centre, n, "state", false)?;
            let radius = numbers(&format!("{key}.radius"), radius, n)?;
            if let Some(i) = (0..n).find(|&i| radius[i] <= 0.0) {
                return Err(ConfigError::new(
                    &format!("{key}.radius[{i}]"),
                    format!("{} must be a number > 0, or inf", radius[i]),
                ));
            }
            Ok(Region::Ball { centre, radius })
        }
        _ => Err(ConfigError::new(
            key,
            "give a box (`low` and `high`) or a ball (`centre` and `radius`), one number per state each",
        )),
    }
}

/// `n` numbers, not NaN (infinities allowed).
fn numbers(key: &str, v: &[crate::task::Number], n: usize) -> Result<Vec<f64>, ConfigError> {
    crate::config::check_len(key, v.len(), n, "state")?;
    if let Some(i) = v.iter().position(|x| x.0.is_nan()) {
        return Err(ConfigError::new(
            &format!("{key}[{i}]"),
            "NaN must be a number, or ±inf",
        ));
    }
    Ok(v.iter().map(|x| x.0).collect())
}
