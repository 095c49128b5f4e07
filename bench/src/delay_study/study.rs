//! The study: its cells (learner × timing × injected delay), each learned as `rig learn`
//! learns, and their final greedy returns' statistics.

use std::path::PathBuf;

use agent::config::{Algo, ApproxKind};
use observer::config::{ObserverKind, ObserverMode, ObserverModel, SensorKind};
use statrs::distribution::{ContinuousCDF, StudentsT};

use runtime::config::{Overrides, resolve};
use runtime::learn::{LearnOptions, Progress, learn};
use runtime::output::progress_bar;
use runtime::output::runs::final_greedy;
use runtime::report::{CurvePoint, curve};

/// Why the delay study stopped.
#[derive(Debug, thiserror::Error)]
pub enum DelayStudyError {
    /// A cell's configuration.
    #[error(transparent)]
    Config(#[from] plant::config::ConfigError),
    /// A cell could not be learned.
    #[error(transparent)]
    Learn(#[from] runtime::learn::LearnError),
    /// A cell's final greedy returns could not be summarised.
    #[error(transparent)]
    Curve(#[from] runtime::report::CurveError),
    /// An output could not be written.
    #[error(transparent)]
    File(#[from] runtime::error::FileError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] runtime::report::PlotError),
    /// The output folder could not be created.
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

/// The learners of the study.
pub const LEARNERS: [(Algo, ApproxKind); 2] = [
    (Algo::Vgbp, ApproxKind::Lstd),
    (Algo::Mlac, ApproxKind::Llr),
];
/// The injected delays by default \[ms\].
pub const DELAYS_MS: [f64; 4] = [0.0, 5.0, 10.0, 20.0];
/// The swing-up is learned when the mean final greedy return is at least this (this
/// project's criterion for the study, not the thesis's).
pub const SWING_UP: f64 = -900.0;
/// The delay at which predictive and direct timing are compared \[ms\].
pub const COMPARED_AT_MS: f64 = 10.0;

/// What `rig delay-study` runs.
#[derive(Clone, Debug)]
pub struct DelayStudyOptions {
    /// Runs per cell.
    pub runs: u32,
    /// Trials per run (default: the presets').
    pub trials: Option<u32>,
    /// Injected delays \[ms\].
    pub delays_ms: Vec<f64>,
    /// The predictive estimator's process model (`observer.model`): learned (the study)
    /// or known (the reference: how much a perfect model recovers).
    pub model: ObserverModel,
    /// Output directory.
    pub out: PathBuf,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Print a line per cell and the summary.
    pub verbose: bool,
}

/// Final greedy returns across runs.
#[derive(Clone, Debug, PartialEq)]
pub struct ReturnStats {
    /// Runs.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one run).
    pub sd: f64,
    /// 95 % confidence interval of the mean.
    pub ci: (f64, f64),
}

impl ReturnStats {
    /// Of `v` (non-empty, finite).
    pub fn of(v: &[f64]) -> Result<Self, runtime::report::CurveError> {
        let p = &curve(&[0], &[0.0], &[v.to_vec()])?[0];
        let n = v.len();
        let sd = if n > 1 {
            (v.iter().map(|x| (x - p.mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Ok(Self {
            n,
            mean: p.mean,
            sd,
            ci: (p.ci_low, p.ci_high),
        })
    }
}

/// One cell of the study.
#[derive(Clone, Debug)]
pub struct StudyCell {
    /// Learner.
    pub algo: Algo,
    /// Its approximator.
    pub approx: ApproxKind,
    /// Timing.
    pub mode: ObserverMode,
    /// Injected delay \[ms\].
    pub delay_ms: f64,
    /// Final greedy return of each run.
    pub finals: Vec<f64>,
    /// Their statistics.
    pub stats: ReturnStats,
    /// How far the velocity the agent acted on was from the truth, RMSE over the learning
    /// trials, mean over runs \[rad/s\] (`observer.csv` of `rig learn`): the estimate
    /// `x̂_k` in direct timing, the one-step prediction `x̂_{k+1|k}` in predictive timing.
    pub velocity_error: f64,
    /// The greedy learning curve.
    pub greedy_curve: Vec<CurvePoint>,
}

/// One-sided Welch t-test that the mean of `a` exceeds that of `b`: `(t, df, p)`.
pub fn welch(a: &ReturnStats, b: &ReturnStats) -> Option<(f64, f64, f64)> {
    let (va, vb) = (a.sd.powi(2) / a.n as f64, b.sd.powi(2) / b.n as f64);
    if a.n < 2 || b.n < 2 || va + vb <= 0.0 {
        return None;
    }
    let t = (a.mean - b.mean) / (va + vb).sqrt();
    let df = (va + vb).powi(2) / (va.powi(2) / (a.n - 1) as f64 + vb.powi(2) / (b.n - 1) as f64);
    let p = 1.0 - StudentsT::new(0.0, 1.0, df).ok()?.cdf(t);
    Some((t, df, p))
}

/// The mean over runs of the velocity components' RMSE (the second half of the state).
fn velocity_error(acted_on_rmse: &[Vec<f64>]) -> f64 {
    let per_run: Vec<f64> = acted_on_rmse
        .iter()
        .map(|r| {
            let v = &r[r.len() / 2..];
            v.iter().sum::<f64>() / v.len().max(1) as f64
        })
        .collect();
    per_run.iter().sum::<f64>() / per_run.len().max(1) as f64
}

/// The spelling of a delay in directory names and tables.
pub(super) fn ms(d: f64) -> String {
    format!("{d}")
}

/// Learns every cell of the study (the module documentation of [`super`]).
pub fn run(opts: &DelayStudyOptions) -> Result<Vec<StudyCell>, DelayStudyError> {
    std::fs::create_dir_all(&opts.out)?;
    let mut cells = Vec::new();
    // One bar for the whole study, grown by each cell's trials as it starts.
    let bar = progress_bar(0, opts.verbose, "delay study");
    for (algo, approx) in LEARNERS {
        // Predictive timing applies each action at the next sample instant, so a delay
        // below Ts never reaches the plant (tests/rig_run.rs checks the runs are equal):
        // its cell is run once, with no delay, and stands for every delay.
        let mut predictive: Option<StudyCell> = None;
        for mode in ObserverMode::ALL {
            for &delay_ms in &opts.delays_ms {
                if let Some(p) = predictive
                    .as_ref()
                    .filter(|_| mode == ObserverMode::Predictive)
                {
                    cells.push(StudyCell {
                        delay_ms,
                        ..p.clone()
                    });
                    continue;
                }
                let (run_delay, dir) = match mode {
                    ObserverMode::Predictive => (0.0, format!("{mode}")),
                    ObserverMode::Direct => (delay_ms, format!("{mode}-{}ms", ms(delay_ms))),
                };
                let o = Overrides {
                    algo: Some(algo),
                    approx: Some(approx),
                    runs: Some(opts.runs),
                    trials: opts.trials,
                    sensor: Some(SensorKind::Angle),
                    observer: Some(ObserverKind::Predictive),
                    observer_mode: Some(mode),
                    delay_ms: Some(run_delay),
                    ..Overrides::default()
                };
                let mut cfg = resolve(None, &o)?;
                cfg.change_observer(|o| o.model = opts.model)?;
                let dir = opts.out.join(format!("{algo}-{approx}")).join(dir);
                bar.inc_length(u64::from(cfg.run().runs) * u64::from(cfg.run().trials));
                let s = learn(
                    &cfg,
                    &LearnOptions {
                        out: dir,
                        threads: opts.threads,
                        progress: Progress::Shared(bar.clone()),
                    },
                )?;
                let finals = final_greedy(&s.records, cfg.run().runs)?;
                let stats = ReturnStats::of(&finals)?;
                let velocity_error = velocity_error(&s.acted_on_rmse);
                if opts.verbose {
                    let when = match mode {
                        ObserverMode::Predictive => "any delay".to_string(),
                        ObserverMode::Direct => format!("{} ms", ms(delay_ms)),
                    };
                    bar.suspend(|| println!(
                        "{algo}/{approx} {mode:>10} {when:>9}: final greedy {:8.1} [95% CI {:.1} … {:.1}], acted-on velocity error {velocity_error:.3} rad/s ({} runs × {} trials, {:.1} s)",
                        stats.mean,
                        stats.ci.0,
                        stats.ci.1,
                        cfg.run().runs,
                        cfg.run().trials,
                        s.wall.as_secs_f64()
                    ));
                }
                let cell = StudyCell {
                    algo,
                    approx,
                    mode,
                    delay_ms,
                    finals,
                    stats,
                    velocity_error,
                    greedy_curve: s.greedy_curve,
                };
                if mode == ObserverMode::Predictive {
                    predictive = Some(cell.clone());
                }
                cells.push(cell);
            }
        }
    }
    bar.finish_and_clear();
    Ok(cells)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welch_detects_a_clear_difference_and_not_a_tie() {
        let a = ReturnStats::of(&[10.0, 11.0, 12.0, 10.5]).unwrap();
        let b = ReturnStats::of(&[0.0, 1.0, 2.0, 0.5]).unwrap();
        let (_, _, p) = welch(&a, &b).unwrap();
        assert!(p < 1e-4, "{p}");
        let (_, _, p) = welch(&a, &a).unwrap();
        assert!((p - 0.5).abs() < 1e-12);
    }
}
