//! `rig delay-study`: how a sample-to-actuation delay hurts learning, and how much
//! predictive timing recovers (thesis §6.4.1; docs/latency.md).
//!
//! Every cell is one `rig learn` experiment ([`runtime::learn::learn`], runs in parallel) on
//! the pendulum with angle-only sensing and the predictive (model-based) estimator:
//! learner × timing × injected delay, the learners VGBP-LSTD and MLAC/LLR with their
//! presets, the timings direct (`x̂_k`, action applied `D` after the sample) and
//! predictive (`x̂_{k+1|k}`, action applied at the next sample instant), the delays
//! `D` = 0, 5, 10, 20 ms by default. A cell's score per run is its *final greedy return*:
//! the mean of the run's last [`LAST_EVALUATIONS`] greedy evaluations (as `rig learn`
//! summarises); across runs its mean, sample standard deviation and 95 % confidence
//! interval of the mean (Student's t).
//!
//! Outputs in `DIR`:
//! * `cells.csv` — `algo,approx,mode,delay_ms,runs,mean,sd,ci_low,ci_high,velocity_error`
//!   (the last: how far the velocity the agent acted on was from the truth, [`Cell`]);
//! * `final_return.png` / `.svg` — final greedy return against the delay, direct and
//!   predictive per learner, with 95 % CIs;
//! * `curves-ALGO-APPROX.png` / `.svg` — the greedy learning curves (means) of every cell
//!   of a learner;
//! * `summary.txt` — the table and the acceptance checks: at 10 ms, is predictive timing
//!   better than direct (one-sided Welch t-test, p < 0.05; whether the CIs overlap is
//!   reported too), and does each learner learn the swing-up in predictive timing (mean
//!   final greedy return ≥ [`SWING_UP`])?
//! * `ALGO-APPROX/direct-Dms/`, `ALGO-APPROX/predictive/` — each cell's `rig learn`
//!   output. Predictive timing applies an action at the next sample instant, so a delay
//!   below `Ts` never reaches the plant: its cell is run once (no delay) and stands for
//!   every delay.
//!
//! `--observer-model known` runs the same study with the plant's own dynamics as the
//! estimator's model: the reference for what a perfect one-step prediction recovers.

use std::fmt::Write as _;
use std::path::PathBuf;

use agent::config::{Algo, ApproxKind};
use observer::config::{ObserverKind, ObserverMode, ObserverModel, SensorKind};
use statrs::distribution::{ContinuousCDF, StudentsT};

use runtime::config::{Overrides, resolve};
use runtime::learn::{LearnOptions, Progress, learn};
use runtime::output::runs::{LAST_EVALUATIONS, final_greedy};
use runtime::output::{progress_bar, write_atomic};
use runtime::report::plot::{PointSeries, plot_points};
use runtime::report::{CurvePoint, Series, SeriesStyle, curve, plot_curves};

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
pub struct Stats {
    /// Runs.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one run).
    pub sd: f64,
    /// 95 % confidence interval of the mean.
    pub ci: (f64, f64),
}

impl Stats {
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
pub struct Cell {
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
    pub stats: Stats,
    /// How far the velocity the agent acted on was from the truth, RMSE over the learning
    /// trials, mean over runs \[rad/s\] (`observer.csv` of `rig learn`): the estimate
    /// `x̂_k` in direct timing, the one-step prediction `x̂_{k+1|k}` in predictive timing.
    pub velocity_error: f64,
    /// The greedy learning curve.
    pub greedy_curve: Vec<CurvePoint>,
}

/// One-sided Welch t-test that the mean of `a` exceeds that of `b`: `(t, df, p)`.
pub fn welch(a: &Stats, b: &Stats) -> Option<(f64, f64, f64)> {
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
fn ms(d: f64) -> String {
    format!("{d}")
}

/// Runs the study; see the module documentation.
pub fn delay_study(opts: &DelayStudyOptions) -> Result<Vec<Cell>, DelayStudyError> {
    std::fs::create_dir_all(&opts.out)?;
    let mut cells = Vec::new();
    // One bar for the whole study, grown by each cell's trials as it starts.
    let bar = progress_bar(0, opts.verbose, "delay study");
    for (algo, approx) in LEARNERS {
        // Predictive timing applies each action at the next sample instant, so a delay
        // below Ts never reaches the plant (tests/rig_run.rs checks the runs are equal):
        // its cell is run once, with no delay, and stands for every delay.
        let mut predictive: Option<Cell> = None;
        for mode in ObserverMode::ALL {
            for &delay_ms in &opts.delays_ms {
                if let Some(p) = predictive
                    .as_ref()
                    .filter(|_| mode == ObserverMode::Predictive)
                {
                    cells.push(Cell {
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
                let stats = Stats::of(&finals)?;
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
                let cell = Cell {
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
    write_outputs(opts, &cells)?;
    Ok(cells)
}

/// `cells.csv`, the plots and `summary.txt`.
fn write_outputs(opts: &DelayStudyOptions, cells: &[Cell]) -> Result<(), DelayStudyError> {
    let mut csv =
        String::from("algo,approx,mode,delay_ms,runs,mean,sd,ci_low,ci_high,velocity_error\n");
    for c in cells {
        let s = &c.stats;
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{}",
            c.algo,
            c.approx,
            c.mode,
            ms(c.delay_ms),
            s.n,
            s.mean,
            s.sd,
            s.ci.0,
            s.ci.1,
            c.velocity_error
        );
    }
    write_atomic(&opts.out.join("cells.csv"), &csv)?;

    let of = |algo, mode| -> Vec<&Cell> {
        cells
            .iter()
            .filter(|c| c.algo == algo && c.mode == mode)
            .collect()
    };
    let mut labels = Vec::new();
    let mut points = Vec::new();
    for (algo, approx) in LEARNERS {
        for mode in ObserverMode::ALL {
            labels.push(format!(
                "{}/{} {mode}",
                algo.as_str().to_uppercase(),
                approx.as_str().to_uppercase()
            ));
            points.push(
                of(algo, mode)
                    .iter()
                    .map(|c| (c.delay_ms, c.stats.mean, c.stats.ci.0, c.stats.ci.1))
                    .collect::<Vec<_>>(),
            );
        }
    }
    let series: Vec<PointSeries> = labels
        .iter()
        .zip(&points)
        .enumerate()
        .map(|(i, (label, points))| PointSeries {
            label,
            points,
            dashed: i % 2 == 1,
            colour: i / 2,
        })
        .collect();
    plot_points(
        &opts.out.join("final_return.png"),
        &opts.out.join("final_return.svg"),
        &format!(
            "Pendulum, angle-only, {} observer model: final greedy return vs delay ({} runs, 95 % CI)",
            opts.model, opts.runs
        ),
        (
            "Injected sample-to-actuation delay [ms]",
            "Final greedy return",
        ),
        &series,
    )?;
    for (algo, approx) in LEARNERS {
        let mine: Vec<&Cell> = cells.iter().filter(|c| c.algo == algo).collect();
        let labels: Vec<String> = mine
            .iter()
            .map(|c| format!("{} {} ms", c.mode, ms(c.delay_ms)))
            .collect();
        let series: Vec<Series> = mine
            .iter()
            .zip(&labels)
            .filter(|(c, _)| !c.greedy_curve.is_empty())
            .map(|(c, label)| Series {
                label: label.clone(),
                points: &c.greedy_curve,
                style: SeriesStyle::Line,
            })
            .collect();
        if series.is_empty() {
            continue;
        }
        plot_curves(
            &opts.out.join(format!("curves-{algo}-{approx}.png")),
            &opts.out.join(format!("curves-{algo}-{approx}.svg")),
            &format!(
                "{}/{}, angle-only: greedy learning curves (mean of {} runs)",
                algo.as_str().to_uppercase(),
                approx.as_str().to_uppercase(),
                opts.runs
            ),
            &series,
            None,
        )?;
    }
    let summary = summary(opts.model, cells);
    write_atomic(&opts.out.join("summary.txt"), &summary)?;
    if opts.verbose {
        print!("{summary}");
    }
    Ok(())
}

/// The table and the acceptance checks.
pub fn summary(model: ObserverModel, cells: &[Cell]) -> String {
    let mut s = format!(
        "Final greedy return (per run: mean of its last {LAST_EVALUATIONS} greedy evaluations), pendulum, angle-only sensing, predictive estimator with the {model} model; v_err: RMSE of the velocity the agent acted on against the truth (x̂_k direct, x̂_(k+1|k) predictive), mean over runs; predictive timing is run once and stands for every delay < Ts\n\n",
    );
    let _ = writeln!(
        s,
        "{:<10} {:<10} {:>8} {:>5} {:>9} {:>8} {:>21} {:>13}",
        "learner", "timing", "delay_ms", "runs", "mean", "sd", "95% CI", "v_err [rad/s]"
    );
    for c in cells {
        let st = &c.stats;
        let _ = writeln!(
            s,
            "{:<10} {:<10} {:>8} {:>5} {:>9.1} {:>8.1} {:>21} {:>13.3}",
            format!("{}/{}", c.algo, c.approx),
            c.mode.as_str(),
            ms(c.delay_ms),
            st.n,
            st.mean,
            st.sd,
            format!("[{:.1}, {:.1}]", st.ci.0, st.ci.1),
            c.velocity_error
        );
    }
    let cell = |algo, mode, d: f64| {
        cells
            .iter()
            .find(|c| c.algo == algo && c.mode == mode && c.delay_ms == d)
    };
    let _ = writeln!(
        s,
        "\nAcceptance 1: at {COMPARED_AT_MS} ms, predictive timing better than direct (one-sided Welch t-test, p < 0.05):"
    );
    for (algo, approx) in LEARNERS {
        let (Some(p), Some(d)) = (
            cell(algo, ObserverMode::Predictive, COMPARED_AT_MS),
            cell(algo, ObserverMode::Direct, COMPARED_AT_MS),
        ) else {
            let _ = writeln!(
                s,
                "  {algo}/{approx}: not measured ({COMPARED_AT_MS} ms is not among the delays)"
            );
            continue;
        };
        let overlap = p.stats.ci.0 <= d.stats.ci.1 && d.stats.ci.0 <= p.stats.ci.1;
        let verdict = match welch(&p.stats, &d.stats) {
            Some((t, df, pv)) => format!(
                "t = {t:.2}, df = {df:.1}, p {} → {}",
                if pv < 0.001 {
                    "< 0.001".to_string()
                } else {
                    format!("= {pv:.3}")
                },
                if pv < 0.05 { "HOLDS" } else { "does NOT hold" }
            ),
            None => "no test (fewer than 2 runs or no spread)".into(),
        };
        let _ = writeln!(
            s,
            "  {algo}/{approx}: predictive {:.1} [{:.1}, {:.1}] vs direct {:.1} [{:.1}, {:.1}]; difference {:+.1}; CIs {}; {verdict}",
            p.stats.mean,
            p.stats.ci.0,
            p.stats.ci.1,
            d.stats.mean,
            d.stats.ci.0,
            d.stats.ci.1,
            p.stats.mean - d.stats.mean,
            if overlap { "overlap" } else { "do not overlap" },
        );
    }
    let _ = writeln!(
        s,
        "\nAcceptance 2: predictive timing learns the swing-up (mean final greedy return ≥ {SWING_UP}):"
    );
    for (algo, approx) in LEARNERS {
        for c in cells
            .iter()
            .filter(|c| c.algo == algo && c.mode == ObserverMode::Predictive)
        {
            let _ = writeln!(
                s,
                "  {algo}/{approx} at {} ms: {:.1} over {} runs → {}",
                ms(c.delay_ms),
                c.stats.mean,
                c.stats.n,
                if c.stats.mean >= SWING_UP {
                    "HOLDS"
                } else {
                    "does NOT hold"
                }
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welch_detects_a_clear_difference_and_not_a_tie() {
        let a = Stats::of(&[10.0, 11.0, 12.0, 10.5]).unwrap();
        let b = Stats::of(&[0.0, 1.0, 2.0, 0.5]).unwrap();
        let (_, _, p) = welch(&a, &b).unwrap();
        assert!(p < 1e-4, "{p}");
        let (_, _, p) = welch(&a, &a).unwrap();
        assert!((p - 0.5).abs() < 1e-12);
    }
}
