//! What is measured on each learning curve: the final greedy return, the rise time t₉₀,
//! the swings of the final policies, the trials that left the operating range.

use std::collections::BTreeMap;
use std::time::Duration;

use plant::SystemName;

use runtime::config::ExperimentConfig;
use runtime::learn::LearnSummary;
use runtime::report::{self};

use super::ReproduceError;

/// What was measured for one curve.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The curve's label.
    pub label: String,
    /// Runs × trials.
    pub runs: usize,
    /// Trials per run.
    pub trials: usize,
    /// Final greedy return: mean over runs of each run's last three evaluations.
    pub final_greedy: f64,
    /// Its sample standard deviation over runs.
    pub final_greedy_sd: f64,
    /// The median over runs of each run's final greedy return.
    pub final_greedy_median: f64,
    /// The worst run's final greedy return.
    pub final_greedy_worst: f64,
    /// Rise time t₉₀: simulated minutes until the smoothed learning curve first covers
    /// 90 % of its improvement from the first trial to its final level.
    pub reaches_min: f64,
    /// The learning curve's start level (mean return of the first trial).
    pub start_level: f64,
    /// The learning curve's final level (mean return over the last 10 % of trials).
    pub final_level: f64,
    /// Learning trials (of all runs) that ended before the trial's length, having left
    /// the operating range (§6.4.2).
    pub ended_early: usize,
    /// Share of the samples of the final greedy policies (one trial per run) with an
    /// action at a bound.
    pub at_bound: f64,
    /// On the pendulum, per run, the swings of the final greedy policy's swing-up
    /// (`swings`); empty for other systems.
    pub swings: Vec<Option<usize>>,
    /// The smoothed learning curve: (simulated minutes, 10-trial moving mean of the mean
    /// return).
    pub smoothed: Vec<(f64, f64)>,
    /// Wall-clock time of its experiments.
    pub wall: Duration,
}

impl Measured {
    /// Simulated minutes until the smoothed learning curve first reaches `level`.
    pub(super) fn minutes_to(&self, level: f64) -> f64 {
        self.smoothed
            .iter()
            .find(|p| p.1 >= level)
            .map_or(f64::INFINITY, |p| p.0)
    }
}

/// The level 90 % of the way from `start` to `end` (the target of a rise time t₉₀; `end`
/// itself if the curve did not improve).
pub(super) fn rise_target(start: f64, end: f64) -> f64 {
    end - 0.1 * (end - start).max(0.0)
}

/// The common target of curves compared for speed: 90 % of the way from the lowest start
/// level to the lowest final level, so that a curve that stays low does not "converge"
/// at once to its own level.
pub(super) fn common_target<'a>(curves: impl IntoIterator<Item = &'a Measured> + Clone) -> f64 {
    let low = |f: fn(&Measured) -> f64| {
        curves
            .clone()
            .into_iter()
            .map(f)
            .fold(f64::INFINITY, f64::min)
    };
    rise_target(low(|c| c.start_level), low(|c| c.final_level))
}

/// The measures of one experiment of `cfg`.
pub(super) fn measure(
    label: &str,
    cfg: &ExperimentConfig,
    summary: &LearnSummary,
) -> Result<Measured, ReproduceError> {
    let (records, runs, trials) = (
        &summary.records,
        cfg.run().runs as usize,
        cfg.run().trials as usize,
    );
    let task = cfg.task();
    let mut ended_early = 0;
    let mut by_trial: BTreeMap<u32, (f64, f64, usize)> = BTreeMap::new();
    let mut skipped = (u32::MAX, 0);
    for r in records {
        // Samples not run grow in a trial that left the operating range (§6.4.2).
        let now = task.skipped_samples(r.trial.into(), r.sim_time_s);
        if now > if skipped.0 == r.run { skipped.1 } else { 0 } {
            ended_early += 1;
        }
        skipped = (r.run, now);
        let e = by_trial.entry(r.trial).or_insert((0.0, 0.0, 0));
        e.0 += r.ret;
        e.1 += r.sim_time_s;
        e.2 += 1;
    }
    let finals = runtime::output::runs::final_greedy(records, runs as u32).map_err(|source| {
        ReproduceError::Measure {
            label: label.to_string(),
            source,
        }
    })?;
    let n = finals.len() as f64;
    let final_greedy = finals.iter().sum::<f64>() / n;
    let final_greedy_sd = if finals.len() > 1 {
        (finals
            .iter()
            .map(|v| (v - final_greedy).powi(2))
            .sum::<f64>()
            / (n - 1.0))
            .sqrt()
    } else {
        0.0
    };
    let final_greedy_median = report::curve::median(&finals);
    let mean: Vec<f64> = by_trial.values().map(|v| v.0 / v.2 as f64).collect();
    let minutes: Vec<f64> = by_trial.values().map(|v| v.1 / v.2 as f64 / 60.0).collect();
    let smooth: Vec<f64> = (0..mean.len())
        .map(|i| {
            let w = &mean[i.saturating_sub(9)..=i];
            w.iter().sum::<f64>() / w.len() as f64
        })
        .collect();
    let tail = &mean[mean.len() - (mean.len() / 10).max(1)..];
    let final_level = tail.iter().sum::<f64>() / tail.len() as f64;
    let start_level = mean[0];
    let target = rise_target(start_level, final_level);
    let reach = smooth
        .iter()
        .position(|v| *v >= target)
        .unwrap_or(smooth.len() - 1);
    Ok(Measured {
        label: label.to_string(),
        runs,
        trials,
        final_greedy,
        final_greedy_sd,
        final_greedy_median,
        final_greedy_worst: finals.iter().copied().fold(f64::INFINITY, f64::min),
        reaches_min: minutes[reach],
        start_level,
        final_level,
        ended_early,
        at_bound: {
            let samples = summary.responses.iter().flatten();
            let n = samples.clone().count().max(1);
            let hits = samples
                .filter(|s| {
                    s.u.iter().enumerate().any(|(j, &u)| {
                        let (lo, hi) = (task.action_low[j], task.action_high[j]);
                        u <= lo + 1e-3 * (hi - lo) || u >= hi - 1e-3 * (hi - lo)
                    })
                })
                .count();
            hits as f64 / n as f64
        },
        swings: if cfg.system() == SystemName::Pendulum {
            summary.responses.iter().map(|r| swings(r)).collect()
        } else {
            Vec::new()
        },
        smoothed: minutes
            .iter()
            .copied()
            .zip(smooth.iter().copied())
            .collect(),
        wall: summary.wall,
    })
}

/// Swings of a pendulum swing-up (§6.5: VGBP "needed two or three swings to get the
/// pendulum upright"): the reversals of the direction of rotation (sign changes of φ̇)
/// before the pendulum first comes within 0.3 rad of upright (φ = 0); `None` if it never
/// does in the trial.
pub(super) fn swings(response: &[runtime::response::ResponseSample]) -> Option<usize> {
    let mut reversals = 0;
    let mut direction = 0.0;
    for s in response {
        if s.x[0].abs() < 0.3 {
            return Some(reversals);
        }
        let d = s.x[1].signum();
        if s.x[1] != 0.0 && d != direction {
            if direction != 0.0 {
                reversals += 1;
            }
            direction = d;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use runtime::response::ResponseSample;

    fn response(states: &[(f64, f64)]) -> Vec<ResponseSample> {
        states
            .iter()
            .enumerate()
            .map(|(k, &(phi, omega))| ResponseSample {
                t: 0.03 * k as f64,
                x: vec![phi, omega],
                u: vec![0.0],
                reward: 0.0,
            })
            .collect()
    }

    #[test]
    fn swings_count_the_reversals_before_the_pendulum_is_up() {
        // Pushed one way, back through the bottom (1), back again (2) and up.
        let two = response(&[
            (3.1, 0.0),
            (2.8, -3.0),
            (2.5, -1.0),
            (2.6, 2.0),
            (3.0, 4.0),
            (-2.9, 5.0),
            (-2.5, 0.5),
            (-2.8, -1.0),
            (2.0, -6.0),
            (0.2, -3.0),
        ]);
        assert_eq!(swings(&two), Some(2));
        // Straight up without a reversal.
        assert_eq!(
            swings(&response(&[(3.0, 0.0), (1.0, -5.0), (0.1, -1.0)])),
            Some(0)
        );
        // Never within 0.3 rad of upright.
        assert_eq!(
            swings(&response(&[(3.0, 0.0), (2.0, 1.0), (0.4, 2.0)])),
            None
        );
    }

    #[test]
    fn the_rise_time_target_is_ninety_percent_of_the_improvement() {
        assert_eq!(rise_target(-4000.0, -1000.0), -1300.0);
        // No improvement: the final level itself.
        assert_eq!(rise_target(-1000.0, -2000.0), -2000.0);
    }
}
