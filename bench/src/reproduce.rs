//! `rig reproduce`: regenerates the thesis's learning-curve figures from the presets, with
//! the thesis's numbers of runs, and writes `REPORT.md` — per figure the plot, a table
//! "thesis says / we measured" and the figure's qualitative claims checked against the
//! regenerated data.
//!
//! Each figure is a set of experiments ([`Figure::curves`]), run with `rig learn`'s
//! machinery ([`crate::learn::learn`]: all runs in parallel, a progress bar each) into
//! `DIR/<figure>/<curve>/`; an experiment that two figures share (3.23 gathers those of
//! 3.12, 3.17 and 3.22) runs once. Per figure: `figure.png`/`.svg` (the learning curves
//! over simulated minutes, as the thesis plots them; on the pendulum with the optimal
//! return of [`crate::optimal`] as a reference line) and `summary.csv`.
//!
//! Measures, per curve (from `runs.csv`):
//! * **final greedy return** — per run the mean of its last three greedy evaluations;
//!   mean and sample standard deviation over runs;
//! * **reaches final level** — the learning curve (mean over runs of each trial's
//!   return), smoothed by a 10-trial moving mean, first within 10 % of its final level
//!   (the mean over the last 10 % of trials), in simulated minutes;
//! * on the pendulum, the final greedy return as a percentage of the optimum
//!   (`optimum / final`, 100 % = optimal).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use agent::config::{
    Algo, ApproxKind, Component, ExperimentConfig, HorizonKind, Overrides, resolve,
};
use anyhow::{Context, Result, anyhow, bail};
use plant::SystemName;

use crate::experiment::TrialRecord;
use crate::learn::{LearnOptions, LearnSummary, learn, write_atomic};
use crate::report::{self, CurvePoint, Series, SeriesStyle};

/// The ids `--only` takes: the figures in the thesis's order, and the sensitivity
/// analysis.
pub const FIGURES: [&str; 10] = [
    "3.12",
    "3.17",
    "3.22",
    "3.23",
    "4.4",
    "5.5",
    "5.9",
    "6.1",
    "6.5",
    "sensitivity",
];

/// What to regenerate and where.
#[derive(Clone, Debug)]
pub struct ReproduceOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Only these figures (default: all).
    pub only: Vec<String>,
    /// Runs per experiment (default: the thesis's, 30 or 20).
    pub runs: Option<u32>,
    /// Trials per run (default: the presets'); for quick looks only.
    pub trials: Option<u32>,
    /// Progress bars.
    pub progress: bool,
}

/// One learning curve of a figure.
struct Curve {
    label: &'static str,
    cfg: ExperimentConfig,
}

/// A qualitative claim of the thesis about a figure, checked on the measured curves.
struct Claim {
    /// What the thesis says.
    says: &'static str,
    /// The check: `Ok(explanation)` if confirmed, `Err(explanation)` if not.
    check: fn(&[Measured]) -> std::result::Result<String, String>,
}

/// A figure of the thesis.
struct Figure {
    id: &'static str,
    title: &'static str,
    curves: Vec<Curve>,
    /// The thesis's numbers for the table, per curve label.
    thesis: &'static [(&'static str, &'static str)],
    claims: Vec<Claim>,
}

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
    /// Simulated minutes until the smoothed learning curve is within 10 % of its final
    /// level.
    pub reaches_min: f64,
    /// The learning curve's final level (mean return over the last 10 % of trials).
    pub final_level: f64,
    /// The smoothed learning curve: (simulated minutes, 10-trial moving mean of the mean
    /// return).
    pub smoothed: Vec<(f64, f64)>,
    /// Wall-clock time of its experiments.
    pub wall: Duration,
}

impl Measured {
    /// Simulated minutes until the smoothed learning curve first comes within 10 % of
    /// `level` (from below).
    fn minutes_to(&self, level: f64) -> f64 {
        self.smoothed
            .iter()
            .find(|p| p.1 >= level - 0.1 * level.abs())
            .map_or(f64::INFINITY, |p| p.0)
    }
}

fn preset(
    system: SystemName,
    algo: Algo,
    approx: ApproxKind,
    horizon: HorizonKind,
) -> ExperimentConfig {
    agent::preset::preset(system, algo, approx, horizon).expect("every figure's preset exists")
}

/// Chapter 6's MLAC/LLR (Table 6.2), shipped as `bench/configs/fig6.1-mlac-llr.toml`.
fn mlac_chapter6() -> ExperimentConfig {
    let text = include_str!("../configs/fig6.1-mlac-llr.toml");
    resolve(
        Some((Path::new("bench/configs/fig6.1-mlac-llr.toml"), text)),
        &Overrides::default(),
    )
    .expect("the shipped configuration resolves")
}

fn find<'a>(m: &'a [Measured], label: &str) -> &'a Measured {
    m.iter()
        .find(|c| c.label == label)
        .expect("a curve of the figure")
}

/// `a` learns faster than `b`: its smoothed learning curve reaches the lower of the two
/// final levels first (a curve that stays low "converges" at once to its own level).
fn faster(m: &[Measured], a: &str, b: &str) -> std::result::Result<String, String> {
    let (x, y) = (find(m, a), find(m, b));
    let level = x.final_level.min(y.final_level);
    let (tx, ty) = (x.minutes_to(level), y.minutes_to(level));
    let text = format!("to the common level {level:.0}: {a} {tx:.1} min, {b} {ty:.1} min");
    if tx < ty { Ok(text) } else { Err(text) }
}

/// `a`'s final greedy return is higher than `b`'s.
fn better(m: &[Measured], a: &str, b: &str) -> std::result::Result<String, String> {
    let (x, y) = (find(m, a), find(m, b));
    let text = format!(
        "final greedy return {a} {:.1} ± {:.1}, {b} {:.1} ± {:.1}",
        x.final_greedy, x.final_greedy_sd, y.final_greedy, y.final_greedy_sd
    );
    if x.final_greedy > y.final_greedy {
        Ok(text)
    } else {
        Err(text)
    }
}

/// SAC/LLR needs at most half the simulated time SAC/RBF needs to the common level.
fn llr_share(m: &[Measured]) -> std::result::Result<String, String> {
    let (x, y) = (find(m, "SAC/LLR"), find(m, "SAC/RBF"));
    let level = x.final_level.min(y.final_level);
    let share = x.minutes_to(level) / y.minutes_to(level);
    let text = format!(
        "to the common level {level:.0}: SAC/LLR {:.1} min, SAC/RBF {:.1} min ({:.0} %)",
        x.minutes_to(level),
        y.minutes_to(level),
        100.0 * share
    );
    if share <= 0.5 { Ok(text) } else { Err(text) }
}

fn both(
    a: std::result::Result<String, String>,
    b: std::result::Result<String, String>,
) -> std::result::Result<String, String> {
    match (a, b) {
        (Ok(x), Ok(y)) => Ok(format!("{x}; {y}")),
        (Ok(x) | Err(x), Ok(y) | Err(y)) => Err(format!("{x}; {y}")),
    }
}

fn figures() -> Vec<Figure> {
    use Algo::*;
    use ApproxKind::*;
    use HorizonKind::{Finite, Infinite};
    use SystemName::*;
    let c = |label, cfg| Curve { label, cfg };
    vec![
        Figure {
            id: "3.12",
            title: "Figure 3.12: SAC with tile coding, RBF and LLR (pendulum)",
            curves: vec![
                c("SAC/tiles", preset(Pendulum, Sac, Tiles, Infinite)),
                c("SAC/RBF", preset(Pendulum, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(Pendulum, Sac, Llr, Infinite)),
            ],
            thesis: &[
                ("SAC/RBF", "learning dip at the start (Fig. 3.10)"),
                (
                    "SAC/LLR",
                    "no learning dip; converged in about 3 min (§3.6.3)",
                ),
            ],
            claims: vec![Claim {
                says: "LLR comes out on top in learning speed (§3.6.1, Fig. 3.12)",
                check: |m| {
                    both(
                        faster(m, "SAC/LLR", "SAC/RBF"),
                        faster(m, "SAC/LLR", "SAC/tiles"),
                    )
                },
            }],
        },
        Figure {
            id: "3.17",
            title: "Figure 3.17: MLAC with RBF and LLR (pendulum)",
            curves: vec![
                c("MLAC/RBF", preset(Pendulum, Mlac, Rbf, Infinite)),
                c("MLAC/LLR", preset(Pendulum, Mlac, Llr, Infinite)),
            ],
            thesis: &[
                ("MLAC/RBF", "converges in over 10 min"),
                (
                    "MLAC/LLR",
                    "converges in just over 3 min; maximum after about 2–2.5 min",
                ),
            ],
            claims: vec![Claim {
                says: "LLR is far superior to RBF in learning speed and performance (§3.6.2)",
                check: |m| {
                    both(
                        faster(m, "MLAC/LLR", "MLAC/RBF"),
                        better(m, "MLAC/LLR", "MLAC/RBF"),
                    )
                },
            }],
        },
        Figure {
            id: "3.22",
            title: "Figure 3.22: RMAC with RBF and LLR (pendulum)",
            curves: vec![
                c("RMAC/RBF", preset(Pendulum, Rmac, Rbf, Infinite)),
                c("RMAC/LLR", preset(Pendulum, Rmac, Llr, Infinite)),
            ],
            thesis: &[
                ("RMAC/RBF", "a tad slower than LLR, better final policy"),
                ("RMAC/LLR", "faster, but a final policy not near as good"),
            ],
            claims: vec![
                Claim {
                    says: "LLR still outperforms RBF in learning speed (§3.6.3)",
                    check: |m| faster(m, "RMAC/LLR", "RMAC/RBF"),
                },
                Claim {
                    says: "but the final policy with LLR is not near as good (§3.6.3)",
                    check: |m| better(m, "RMAC/RBF", "RMAC/LLR"),
                },
            ],
        },
        Figure {
            id: "3.23",
            title: "Figure 3.23: SAC, MLAC and RMAC with RBF and LLR (pendulum)",
            curves: vec![
                c("SAC/RBF", preset(Pendulum, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(Pendulum, Sac, Llr, Infinite)),
                c("MLAC/RBF", preset(Pendulum, Mlac, Rbf, Infinite)),
                c("MLAC/LLR", preset(Pendulum, Mlac, Llr, Infinite)),
                c("RMAC/RBF", preset(Pendulum, Rmac, Rbf, Infinite)),
                c("RMAC/LLR", preset(Pendulum, Rmac, Llr, Infinite)),
            ],
            thesis: &[],
            claims: vec![
                Claim {
                    says: "LLR is the approximator of choice for quick learning: with each algorithm it learns faster than RBFs (§3.7)",
                    check: |m| {
                        both(
                            both(
                                faster(m, "SAC/LLR", "SAC/RBF"),
                                faster(m, "MLAC/LLR", "MLAC/RBF"),
                            ),
                            faster(m, "RMAC/LLR", "RMAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "MLAC and RMAC only show their power with LLR: with LLR they learn faster than SAC/LLR (§3.7)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "SAC/LLR"),
                            faster(m, "RMAC/LLR", "SAC/LLR"),
                        )
                    },
                },
                Claim {
                    says: "model learning speeds learning up: MLAC/LLR learns fastest of all (§3.7)",
                    check: |m| {
                        let level = m
                            .iter()
                            .map(|c| c.final_level)
                            .fold(f64::INFINITY, f64::min);
                        let best = find(m, "MLAC/LLR").minutes_to(level);
                        let text = format!(
                            "to the lowest final level {level:.0}: {}",
                            m.iter()
                                .map(|c| format!("{} {:.1} min", c.label, c.minutes_to(level)))
                                .collect::<Vec<_>>()
                                .join(", ")
                        );
                        if m.iter().all(|c| c.minutes_to(level) >= best) {
                            Ok(text)
                        } else {
                            Err(text)
                        }
                    },
                },
            ],
        },
        Figure {
            id: "4.4",
            title: "Figure 4.4: SAC-FH, MLAC-FH and RMAC-FH (pendulum, finite horizon)",
            curves: vec![
                c("SAC-FH", preset(Pendulum, Sac, Rbf, Finite)),
                c("MLAC-FH", preset(Pendulum, Mlac, Rbf, Finite)),
                c("RMAC-FH", preset(Pendulum, Rmac, Rbf, Finite)),
            ],
            thesis: &[
                ("SAC-FH", "last episode −995.7 ± 199.4 (Table 4.1)"),
                ("MLAC-FH", "last episode −835.4 ± 55.4 (Table 4.1)"),
                ("RMAC-FH", "last episode −840.8 ± 38.0 (Table 4.1)"),
            ],
            claims: vec![Claim {
                says: "a learned model enhances the policy's quality, and MLAC-FH's learning speed (§4.5)",
                check: |m| {
                    both(
                        both(
                            better(m, "MLAC-FH", "SAC-FH"),
                            better(m, "RMAC-FH", "SAC-FH"),
                        ),
                        faster(m, "MLAC-FH", "SAC-FH"),
                    )
                },
            }],
        },
        Figure {
            id: "5.5",
            title: "Figure 5.5: two-link arm, Case I (vertical, damping injection)",
            curves: vec![
                c("SAC/RBF", preset(ArmVertical, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(ArmVertical, Sac, Llr, Infinite)),
                c("MLAC/LLR", preset(ArmVertical, Mlac, Llr, Infinite)),
            ],
            thesis: &[
                ("SAC/RBF", "reaches it after more than 45 min"),
                ("SAC/LLR", "a similar result after 10 min"),
                ("MLAC/LLR", "close to its final result in less than 3 min"),
            ],
            claims: vec![
                Claim {
                    says: "MLAC/LLR reaches its final level first, then SAC/LLR, then SAC/RBF (§5.3)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "SAC/LLR"),
                            faster(m, "SAC/LLR", "SAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "LLR learns a good policy in about 25–50 % of the time RBFs take (§5.5)",
                    check: |m| llr_share(m),
                },
                Claim {
                    says: "SAC/RBF's final policy is better than those learned with LLR (§5.5)",
                    check: |m| {
                        both(
                            better(m, "SAC/RBF", "SAC/LLR"),
                            better(m, "SAC/RBF", "MLAC/LLR"),
                        )
                    },
                },
            ],
        },
        Figure {
            id: "5.9",
            title: "Figure 5.9: two-link arm, Case II (horizontal, reaching)",
            curves: vec![
                c("SAC/RBF", preset(ArmHorizontal, Sac, Rbf, Infinite)),
                c("SAC/LLR", preset(ArmHorizontal, Sac, Llr, Infinite)),
                c("MLAC/LLR", preset(ArmHorizontal, Mlac, Llr, Infinite)),
            ],
            thesis: &[
                (
                    "SAC/RBF",
                    "≥ 40 min more than MLAC/LLR to an equivalent return",
                ),
                (
                    "SAC/LLR",
                    "≥ 20 min more than MLAC/LLR to an equivalent return",
                ),
                ("MLAC/LLR", "close to its final policy after 5 min"),
            ],
            claims: vec![
                Claim {
                    says: "MLAC/LLR reaches its final policy a lot sooner than both others (§5.4)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "SAC/LLR"),
                            faster(m, "MLAC/LLR", "SAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "LLR learns a good policy in about 25–50 % of the time RBFs take (§5.5)",
                    check: |m| llr_share(m),
                },
                Claim {
                    says: "in final return MLAC/LLR outperforms SAC/LLR and is only slightly behind SAC/RBF (§5.4)",
                    check: |m| better(m, "MLAC/LLR", "SAC/LLR"),
                },
            ],
        },
        Figure {
            id: "6.1",
            title: "Figure 6.1: MLAC, VGBP-LLR, VGBP-LSTD and SARSA (pendulum)",
            curves: vec![
                c("MLAC/LLR", mlac_chapter6()),
                c("VGBP-LLR", preset(Pendulum, Vgbp, Llr, Infinite)),
                c("VGBP-LSTD", preset(Pendulum, Vgbp, Lstd, Infinite)),
                c("SARSA", preset(Pendulum, Sarsa, Rbf, Infinite)),
            ],
            thesis: &[
                ("MLAC/LLR", "converges in about 9 min"),
                (
                    "VGBP-LLR",
                    "converges after 3 min; final slightly worse than MLAC",
                ),
                ("VGBP-LSTD", "≥ −1000 within one simulated minute (§6.5)"),
                (
                    "SARSA",
                    "needs more interaction; final slightly better than VGBP-LLR",
                ),
            ],
            claims: vec![
                Claim {
                    says: "VGBP-LLR converges faster than MLAC (3 vs 9 min), to a slightly worse policy (§6.4.1)",
                    check: |m| {
                        both(
                            faster(m, "VGBP-LLR", "MLAC/LLR"),
                            better(m, "MLAC/LLR", "VGBP-LLR"),
                        )
                    },
                },
                Claim {
                    says: "SARSA needs more interaction than the model-learning algorithms (§6.4.1)",
                    check: |m| {
                        both(
                            faster(m, "VGBP-LLR", "SARSA"),
                            faster(m, "MLAC/LLR", "SARSA"),
                        )
                    },
                },
            ],
        },
        Figure {
            id: "6.5",
            title: "Figure 6.5: VGBP-LSTD on the 2-DOF manipulator (§6.4.2)",
            curves: vec![c("VGBP-LSTD", preset(Arm64, Vgbp, Lstd, Infinite))],
            thesis: &[(
                "VGBP-LSTD",
                "a proper policy in a short time; a low minimum bound from runs leaving the range",
            )],
            claims: vec![Claim {
                says: "VGBP finds a proper policy in a short amount of time (§6.4.2)",
                check: |m| {
                    let v = &m[0];
                    let text = format!(
                        "final greedy return {:.0} ± {:.0}; the learning curve reaches its final level after {:.1} min",
                        v.final_greedy, v.final_greedy_sd, v.reaches_min
                    );
                    if v.reaches_min < 10.0 {
                        Ok(text)
                    } else {
                        Err(text)
                    }
                },
            }],
        },
    ]
}

/// The measures of one experiment's records.
fn measure(
    label: &str,
    records: &[TrialRecord],
    runs: usize,
    trials: usize,
    wall: Duration,
) -> Result<Measured> {
    let mut per_run: BTreeMap<u32, Vec<f64>> = BTreeMap::new();
    let mut by_trial: BTreeMap<u32, (f64, f64, usize)> = BTreeMap::new();
    for r in records {
        if let Some(g) = r.greedy {
            per_run.entry(r.run).or_default().push(g);
        }
        let e = by_trial.entry(r.trial).or_insert((0.0, 0.0, 0));
        e.0 += r.ret;
        e.1 += r.sim_time_s;
        e.2 += 1;
    }
    let finals: Vec<f64> = per_run
        .values()
        .filter(|g| !g.is_empty())
        .map(|g| {
            let last = &g[g.len().saturating_sub(3)..];
            last.iter().sum::<f64>() / last.len() as f64
        })
        .collect();
    if finals.is_empty() {
        bail!("{label}: no greedy evaluations");
    }
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
    let reach = smooth
        .iter()
        .position(|v| (v - final_level).abs() <= 0.1 * final_level.abs())
        .unwrap_or(smooth.len() - 1);
    Ok(Measured {
        label: label.to_string(),
        runs,
        trials,
        final_greedy,
        final_greedy_sd,
        reaches_min: minutes[reach],
        final_level,
        smoothed: minutes
            .iter()
            .copied()
            .zip(smooth.iter().copied())
            .collect(),
        wall,
    })
}

fn slug(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect()
}

/// What one figure produced.
pub struct FigureResult {
    /// The figure id.
    pub id: String,
    /// Per curve, what was measured.
    pub measured: Vec<Measured>,
    /// Per claim: what the thesis says, whether it is confirmed, and the numbers.
    pub claims: Vec<(String, bool, String)>,
    /// Wall-clock time of the figure: its experiments not shared with an earlier figure
    /// (as measured when they ran), and its plots.
    pub wall: Duration,
}

/// Regenerates the figures and writes `REPORT.md`.
pub fn reproduce(opts: &ReproduceOptions) -> Result<Vec<FigureResult>> {
    for id in &opts.only {
        if !FIGURES.contains(&id.as_str()) {
            bail!(
                "`--only` {id:?}: not a figure this command regenerates; one of {}",
                FIGURES.join(", ")
            );
        }
    }
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create output directory {}", opts.out.display()))?;
    let optimum = crate::optimal::pendulum_optimum(&crate::optimal::OptimumOptions {
        grid: 201,
        actions: 61,
    })
    .map_err(|e| anyhow!(e))?
    .simulated_return;
    let mut runner = Runner {
        opts,
        done: BTreeMap::new(),
        spent: Duration::ZERO,
    };
    let mut results = Vec::new();
    let wanted = |id: &str| opts.only.is_empty() || opts.only.iter().any(|o| o == id);
    for fig in figures() {
        if !wanted(fig.id) {
            continue;
        }
        let spent = runner.spent;
        let dir = opts.out.join(fig.id);
        std::fs::create_dir_all(&dir)?;
        let mut measured = Vec::new();
        let mut curves: Vec<Vec<CurvePoint>> = Vec::new();
        let mut responses = Vec::new();
        for curve in &fig.curves {
            let (m, summary) = runner.run(&dir, fig.id, curve.label, &curve.cfg, None)?;
            measured.push(m);
            curves.push(summary.curve);
            responses.push(summary.response);
        }
        let t_plots = Instant::now();
        let labelled: Vec<(&str, &[crate::experiment::Sample])> = fig
            .curves
            .iter()
            .zip(&responses)
            .map(|(c, r)| (c.label, &r[..]))
            .collect();
        report::plot_responses(
            &dir.join("response.png"),
            &dir.join("response.svg"),
            &format!(
                "{}: final policies (run 0, greedy)",
                fig.title.split(':').next().unwrap_or(fig.id)
            ),
            &labelled,
            match fig.curves[0].cfg.system {
                SystemName::Pendulum => ("angle φ [rad]", "action u [V]"),
                _ => ("angle φ₁ [rad]", "torque u₁ [N m]"),
            },
        )?;
        let style = if curves.len() > 3 {
            SeriesStyle::Line
        } else {
            SeriesStyle::Band
        };
        let series: Vec<Series> = fig
            .curves
            .iter()
            .zip(&curves)
            .map(|(c, points)| Series {
                label: c.label.to_string(),
                points,
                style,
            })
            .collect();
        let pendulum = fig.curves[0].cfg.system == SystemName::Pendulum
            && fig.curves[0].cfg.horizon == HorizonKind::Infinite;
        report::plot_curves(
            &dir.join("figure.png"),
            &dir.join("figure.svg"),
            fig.title,
            &series,
            pendulum.then_some(("optimal (DP)", optimum)),
        )?;
        let claims: Vec<(String, bool, String)> = fig
            .claims
            .iter()
            .map(|c| match (c.check)(&measured) {
                Ok(t) => (c.says.to_string(), true, t),
                Err(t) => (c.says.to_string(), false, t),
            })
            .collect();
        write_summary(
            &dir.join("summary.csv"),
            &measured,
            pendulum.then_some(optimum),
        )?;
        let result = FigureResult {
            id: fig.id.to_string(),
            measured,
            claims,
            wall: runner.spent - spent + t_plots.elapsed(),
        };
        results.push((result, fig));
        write_report(&opts.out, &results, None, optimum, runner.spent)?;
    }
    if wanted("sensitivity") {
        let s = sensitivity(&mut runner)?;
        write_report(&opts.out, &results, Some(&s), optimum, runner.spent)?;
    }
    Ok(results.into_iter().map(|(r, _)| r).collect())
}

/// Runs experiments, each configuration once.
struct Runner<'a> {
    opts: &'a ReproduceOptions,
    /// Experiments already run, by configuration.
    done: BTreeMap<String, LearnSummary>,
    /// Wall-clock time of the experiments in `done`, as measured when each ran (now or
    /// by an earlier `rig reproduce` whose outputs are reused).
    spent: Duration,
}

impl Runner<'_> {
    /// Runs `cfg` (with the options' runs and trials, or `runs` if given) into
    /// `dir/<label>`, unless an identical experiment ran before; returns its measures.
    fn run(
        &mut self,
        dir: &Path,
        id: &str,
        label: &str,
        cfg: &ExperimentConfig,
        runs: Option<u32>,
    ) -> Result<(Measured, LearnSummary)> {
        let mut cfg = cfg.clone();
        if let Some(r) = runs.or(self.opts.runs) {
            cfg.run.runs = r;
        }
        if let Some(t) = self.opts.trials {
            cfg.run.trials = t;
        }
        let key = cfg.to_toml();
        let out = dir.join(slug(label));
        if !self.done.contains_key(&key)
            && let Some(s) = load_finished(&out, &cfg)
        {
            if self.opts.progress {
                eprintln!(
                    "{id} {label}: reusing the finished experiment in {}",
                    out.display()
                );
            }
            self.spent += s.wall;
            self.done.insert(key.clone(), s);
        }
        let summary = match self.done.get(&key) {
            Some(s) => s.clone(),
            None => {
                if self.opts.progress {
                    eprintln!(
                        "{id} {label}: {} runs × {} trials",
                        cfg.run.runs, cfg.run.trials
                    );
                }
                let s = learn(
                    &cfg,
                    &LearnOptions {
                        out: out.clone(),
                        threads: None,
                        progress: self.opts.progress,
                    },
                )?;
                write_atomic(
                    &out.join("wall_s.txt"),
                    &format!("{}\n", s.wall.as_secs_f64()),
                )?;
                self.spent += s.wall;
                self.done.insert(key, s.clone());
                s
            }
        };
        let m = measure(
            label,
            &summary.records,
            cfg.run.runs as usize,
            cfg.run.trials as usize,
            summary.wall,
        )?;
        Ok((m, summary))
    }
}

/// The outputs of a finished experiment of `cfg` in `dir` (written by an earlier
/// `rig reproduce`: the same `config.toml`, every row of `runs.csv`, `response.csv` and
/// `wall_s.txt`), or `None`.
fn load_finished(dir: &Path, cfg: &ExperimentConfig) -> Option<LearnSummary> {
    if std::fs::read_to_string(dir.join("config.toml")).ok()? != cfg.to_toml() {
        return None;
    }
    let wall: f64 = std::fs::read_to_string(dir.join("wall_s.txt"))
        .ok()?
        .trim()
        .parse()
        .ok()?;
    let mut records = Vec::new();
    for row in csv::Reader::from_path(dir.join("runs.csv")).ok()?.records() {
        let row = row.ok()?;
        let num = |i: usize| row.get(i)?.parse::<f64>().ok();
        records.push(TrialRecord {
            run: row.get(0)?.parse().ok()?,
            trial: row.get(1)?.parse().ok()?,
            sim_time_s: num(2)?,
            ret: num(3)?,
            greedy: num(4),
        });
    }
    let (runs, trials) = (cfg.run.runs as usize, cfg.run.trials as usize);
    if records.len() != runs * trials {
        return None;
    }
    let (curve, greedy_curve) = crate::learn::curves(&records, runs, trials).ok()?;
    let mut response = Vec::new();
    let mut reader = csv::Reader::from_path(dir.join("response.csv")).ok()?;
    let n = reader
        .headers()
        .ok()?
        .iter()
        .filter(|h| h.starts_with("x_"))
        .count();
    for row in reader.records() {
        let v: Vec<f64> = row
            .ok()?
            .iter()
            .map(|f| f.parse().ok())
            .collect::<Option<_>>()?;
        let last = v.len().checked_sub(1)?;
        response.push(crate::experiment::Sample {
            t: v[0],
            x: v.get(1..1 + n)?.to_vec(),
            u: v.get(1 + n..last)?.to_vec(),
            reward: v[last],
        });
    }
    Some(LearnSummary {
        records,
        curve,
        greedy_curve,
        wall: Duration::from_secs_f64(wall),
        response,
    })
}

/// The parameters the sensitivity analysis varies, and how.
/// Scales a parameter of a configuration by a factor.
type Scale = fn(&mut ExperimentConfig, f64);

/// `(name, short name for directories, how)` of each parameter.
const PARAMETERS: [(&str, &str, Scale); 5] = [
    ("α_a (actor rate)", "alpha_a", |c, f| {
        if let Some(Component::Llr(l)) = &mut c.actor {
            l.alpha *= f;
        }
    }),
    ("α_c (critic rate)", "alpha_c", |c, f| {
        if let Component::Llr(l) = &mut c.critic {
            l.alpha *= f;
        }
    }),
    ("K (neighbours, every memory)", "K", |c, f| {
        for_each_llr(c, |l| {
            l.neighbours = ((l.neighbours as f64 * f).round() as usize).max(3)
        })
    }),
    ("N (memory size, every memory)", "N", |c, f| {
        for_each_llr(c, |l| {
            l.memory = ((l.memory as f64 * f).round() as usize).max(10)
        })
    }),
    ("σ (exploration)", "sigma", |c, f| c.learning.sigma *= f),
];

/// Factors applied to each parameter (the preset is factor 1).
pub const FACTORS: [f64; 4] = [0.25, 0.5, 2.0, 4.0];

fn for_each_llr(c: &mut ExperimentConfig, mut f: impl FnMut(&mut agent::config::LlrConfig)) {
    for comp in [c.actor.as_mut(), Some(&mut c.critic), c.model.as_mut()]
        .into_iter()
        .flatten()
    {
        if let Component::Llr(l) = comp {
            f(l);
        }
    }
}

/// One algorithm's sensitivity: its name, its preset's measures, and per parameter, per
/// factor, the measures (`None`: not a valid configuration).
pub type AlgoSensitivity = (
    String,
    Measured,
    Vec<(String, Vec<(f64, Option<Measured>)>)>,
);

/// The sensitivity analysis (§3.7 and §7.2.1 leave it as future work): final greedy
/// return and learning speed of SAC/LLR and MLAC/LLR on the pendulum when each main
/// parameter is scaled by [`FACTORS`] around the preset.
pub struct Sensitivity {
    /// Runs per variation.
    pub runs: u32,
    /// Per algorithm: the preset's measures and, per parameter, per factor, the measures
    /// (`None`: the variation is not a valid configuration).
    pub algos: Vec<AlgoSensitivity>,
    /// Wall-clock time.
    pub wall: Duration,
}

fn sensitivity(runner: &mut Runner) -> Result<Sensitivity> {
    use agent::config::{Algo::*, ApproxKind::Llr, HorizonKind::Infinite};
    let spent = runner.spent;
    let runs = runner.opts.runs.unwrap_or(10);
    let dir = runner.opts.out.join("sensitivity");
    let mut algos = Vec::new();
    for (name, algo) in [("SAC/LLR", Sac), ("MLAC/LLR", Mlac)] {
        let base = preset(SystemName::Pendulum, algo, Llr, Infinite);
        let (at_preset, _) = runner.run(
            &dir,
            "sensitivity",
            &format!("{name} preset"),
            &base,
            Some(runs),
        )?;
        let mut params = Vec::new();
        for (param, key, apply) in PARAMETERS {
            let mut row = Vec::new();
            for f in FACTORS {
                let mut cfg = base.clone();
                apply(&mut cfg, f);
                if cfg == base || cfg.validate().is_err() {
                    row.push((f, None));
                    continue;
                }
                let label = format!("{name} {key} x{f}");
                let (m, _) = runner.run(&dir, "sensitivity", &label, &cfg, Some(runs))?;
                row.push((f, Some(m)));
            }
            params.push((param.to_string(), row));
        }
        algos.push((name.to_string(), at_preset, params));
    }
    let mut csv =
        String::from("algo,parameter,factor,final_greedy_mean,final_greedy_sd,reaches_final_min\n");
    for (name, p, params) in &algos {
        let _ = writeln!(
            csv,
            "{name},preset,1,{},{},{}",
            p.final_greedy, p.final_greedy_sd, p.reaches_min
        );
        for (param, row) in params {
            for (f, m) in row {
                if let Some(m) = m {
                    let _ = writeln!(
                        csv,
                        "{name},{param},{f},{},{},{}",
                        m.final_greedy, m.final_greedy_sd, m.reaches_min
                    );
                }
            }
        }
    }
    write_atomic(&dir.join("sensitivity.csv"), &csv)?;
    Ok(Sensitivity {
        runs,
        algos,
        wall: runner.spent - spent,
    })
}

impl Sensitivity {
    /// Per algorithm, the worst final greedy return over all variations, and the
    /// largest loss against the preset.
    fn worst(&self) -> Vec<(String, f64, f64)> {
        self.algos
            .iter()
            .map(|(name, p, params)| {
                let worst = params
                    .iter()
                    .flat_map(|(_, row)| row.iter().filter_map(|(_, m)| m.as_ref()))
                    .map(|m| m.final_greedy)
                    .fold(p.final_greedy, f64::min);
                (name.clone(), worst, p.final_greedy - worst)
            })
            .collect()
    }
}

fn write_summary(path: &Path, m: &[Measured], optimum: Option<f64>) -> Result<()> {
    let mut s = String::from(
        "curve,runs,trials,final_greedy_mean,final_greedy_sd,final_level,reaches_final_min,percent_of_optimal,wall_s\n",
    );
    for c in m {
        let pct = optimum.map_or(String::new(), |o| {
            format!("{:.1}", 100.0 * o / c.final_greedy)
        });
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{:.1}",
            c.label,
            c.runs,
            c.trials,
            c.final_greedy,
            c.final_greedy_sd,
            c.final_level,
            c.reaches_min,
            pct,
            c.wall.as_secs_f64()
        );
    }
    write_atomic(path, &s)
}

fn write_report(
    out: &Path,
    results: &[(FigureResult, Figure)],
    sensitivity: Option<&Sensitivity>,
    optimum: f64,
    wall: Duration,
) -> Result<()> {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Reproducing Grondman's thesis: figures regenerated by `rig reproduce`\n\n\
         Machine: {} cores. Wall time of all experiments below, as measured when they ran: \
         {:.0} s ({:.1} min). Optimal return of the pendulum \
         swing-up from [π, 0] (finite-horizon DP on a 201² grid, its policy run on the plant; \
         `rig optimal`): **{optimum:.1}**.\n\n\
         Measures: *final greedy* = per run the mean of the last three greedy evaluations, \
         mean ± sample sd over runs; *final level* = the learning curve's (mean over runs of \
         each trial's return, with exploration) mean over the last 10 % of trials; *reaches* \
         = simulated minutes until the learning curve (10-trial moving mean) is within 10 % \
         of its final level; *% of optimal* = optimum / final greedy. \"Faster\" in the \
         claims compares the minutes until each curve first comes within 10 % of the lower of \
         the final levels compared (a curve that stays low reaches its own level at once).\n",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        wall.as_secs_f64(),
        wall.as_secs_f64() / 60.0
    );
    for (r, fig) in results {
        let _ = writeln!(
            s,
            "## {}\n\n![{}]({}/figure.png)\n\n![{} time responses]({}/response.png)\n",
            fig.title, fig.id, fig.id, fig.id, fig.id
        );
        let _ = writeln!(
            s,
            "Wall time: {:.0} s (experiments shared with earlier figures not counted).\n",
            r.wall.as_secs_f64()
        );
        let _ = writeln!(
            s,
            "| curve | runs × trials | final greedy | final level | reaches [min] | % of optimal | thesis says |\n|---|---|---|---|---|---|---|"
        );
        let pendulum = fig.curves[0].cfg.system == SystemName::Pendulum
            && fig.curves[0].cfg.horizon == HorizonKind::Infinite;
        for m in &r.measured {
            let says = fig
                .thesis
                .iter()
                .find(|t| t.0 == m.label)
                .map_or("", |t| t.1);
            let pct = if pendulum {
                format!("{:.0} %", 100.0 * optimum / m.final_greedy)
            } else {
                "–".to_string()
            };
            let _ = writeln!(
                s,
                "| {} | {} × {} | {:.1} ± {:.1} | {:.0} | {:.1} | {} | {} |",
                m.label,
                m.runs,
                m.trials,
                m.final_greedy,
                m.final_greedy_sd,
                m.final_level,
                m.reaches_min,
                pct,
                says
            );
        }
        let _ = writeln!(s);
        for (says, ok, text) in &r.claims {
            let _ = writeln!(
                s,
                "- {} — **{}**: {text}.",
                says,
                if *ok { "confirmed" } else { "not confirmed" }
            );
        }
        let _ = writeln!(s);
    }
    if let Some(sens) = sensitivity {
        write_sensitivity(&mut s, sens);
    }
    write_atomic(&out.join("REPORT.md"), &s)
}

/// The sensitivity section of `REPORT.md`.
fn write_sensitivity(s: &mut String, sens: &Sensitivity) {
    let _ = writeln!(
        s,
        "## Sensitivity analysis (SAC/LLR and MLAC/LLR, pendulum)\n\n\
         Each main parameter scaled by {} around the preset (K and N in every LLR memory), \
         {} runs per variation, final greedy return (mean of each run's last three \
         evaluations) and, in brackets, the minutes until the learning curve is within 10 % \
         of its final level. Wall time {:.0} s; data in `sensitivity/sensitivity.csv`.\n",
        FACTORS.map(|f| format!("×{f}")).join(", "),
        sens.runs,
        sens.wall.as_secs_f64()
    );
    for (name, preset, params) in &sens.algos {
        let _ = writeln!(
            s,
            "**{name}** (preset: {:.0} [{:.1} min])\n\n| parameter | {} |\n|---|{}",
            preset.final_greedy,
            preset.reaches_min,
            FACTORS.map(|f| format!("×{f}")).join(" | "),
            "---|".repeat(FACTORS.len())
        );
        for (param, row) in params {
            let cells: Vec<String> = row
                .iter()
                .map(|(_, m)| match m {
                    Some(m) => format!("{:.0} [{:.1}]", m.final_greedy, m.reaches_min),
                    None => "–".to_string(),
                })
                .collect();
            let _ = writeln!(s, "| {param} | {} |", cells.join(" | "));
        }
        let _ = writeln!(s);
    }
    let worst = sens.worst();
    let robust = worst
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or("–", |w| w.0.as_str());
    for (name, w, loss) in &worst {
        let _ = writeln!(
            s,
            "- {name}: worst final greedy return over all variations {w:.0}, {loss:.0} below its preset."
        );
    }
    let _ = writeln!(
        s,
        "\nMost robust (the better worst case over these variations): **{robust}**.\n"
    );
}
