//! `rig reproduce`: regenerates the thesis's learning-curve figures from the presets, with
//! the thesis's numbers of runs, and writes `REPORT.md` — per figure the plot, a table
//! "thesis says / we measured" and the figure's qualitative claims checked against the
//! regenerated data.
//!
//! Each figure is a set of experiments (`Figure::curves`), run with `rig learn`'s
//! machinery ([`runtime::learn::learn`]: all runs in parallel, a progress bar each) into
//! `DIR/<figure>/<curve>/`; an experiment that two figures share (3.23 gathers those of
//! 3.12, 3.17 and 3.22) runs once. Per figure: `figure.png`/`.svg` (the learning curves
//! over simulated minutes, as the thesis plots them; on the pendulum with the optimal
//! return of [`crate::optimal`] as a reference line) and `summary.csv`.
//!
//! Measures, per curve (from `runs.csv`):
//! * **final greedy return** — per run the mean of its last three greedy evaluations;
//!   mean and sample standard deviation over runs;
//! * **rise time t₉₀** — the simulated minutes until the learning curve (mean over runs
//!   of each trial's return, smoothed by a 10-trial moving mean) first covers 90 % of its
//!   improvement from the first trial (the untrained policy) to its final level (the
//!   mean over the last 10 % of trials) — the control engineer's 10–90 % rise time read
//!   on a learning curve, which is how the thesis reads "learns faster" off its plots;
//!   "a learns faster than b" compares the minutes until each curve first covers 90 % of
//!   the way from the lower of the two start levels to the lower of the two final levels;
//! * on the pendulum, the final greedy return as a percentage of the optimum
//!   (`optimum / final`, 100 % = optimal).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use agent::config::{Algo, ApproxKind, Component, HorizonKind};
use anyhow::{Context, Result, anyhow, bail};
use indicatif::ProgressBar;
use plant::SystemName;

use runtime::config::{ExperimentConfig, Overrides, resolve};
use runtime::experiment::TrialRecord;
use runtime::learn::{LearnOptions, LearnSummary, Progress, learn, progress_bar, write_atomic};
use runtime::report::{self, CurvePoint, Series, SeriesStyle};

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
    /// One sentence on agreement, or the reason for a difference, written for the run
    /// committed in `docs/reproduction` (seed 1; another seed may read differently).
    discussion: &'static str,
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
    fn minutes_to(&self, level: f64) -> f64 {
        self.smoothed
            .iter()
            .find(|p| p.1 >= level)
            .map_or(f64::INFINITY, |p| p.0)
    }
}

/// The level 90 % of the way from `start` to `end` (the target of a rise time t₉₀; `end`
/// itself if the curve did not improve).
fn rise_target(start: f64, end: f64) -> f64 {
    end - 0.1 * (end - start).max(0.0)
}

/// The common target of curves compared for speed: 90 % of the way from the lowest start
/// level to the lowest final level, so that a curve that stays low does not "converge"
/// at once to its own level.
fn common_target<'a>(curves: impl IntoIterator<Item = &'a Measured> + Clone) -> f64 {
    let low = |f: fn(&Measured) -> f64| {
        curves
            .clone()
            .into_iter()
            .map(f)
            .fold(f64::INFINITY, f64::min)
    };
    rise_target(low(|c| c.start_level), low(|c| c.final_level))
}

fn preset(
    system: SystemName,
    algo: Algo,
    approx: ApproxKind,
    horizon: HorizonKind,
) -> ExperimentConfig {
    ExperimentConfig::preset(system, algo, approx, horizon).expect("every figure's preset exists")
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

/// `a` learns faster than `b`: its smoothed learning curve reaches the common target
/// ([`common_target`]) first.
fn faster(m: &[Measured], a: &str, b: &str) -> std::result::Result<String, String> {
    let (x, y) = (find(m, a), find(m, b));
    let level = common_target([x, y]);
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
    let level = common_target([x, y]);
    let share = x.minutes_to(level) / y.minutes_to(level);
    let text = format!(
        "to the common level {level:.0}: SAC/LLR {:.1} min, SAC/RBF {:.1} min ({:.0} %)",
        x.minutes_to(level),
        y.minutes_to(level),
        100.0 * share
    );
    if share <= 0.5 { Ok(text) } else { Err(text) }
}

/// `a`'s final greedy return is higher than `b`'s by more than the 95 % margin of the
/// difference (Welch: 1.96 standard errors).
fn clearly_better(m: &[Measured], a: &str, b: &str) -> std::result::Result<String, String> {
    let (x, y) = (find(m, a), find(m, b));
    let se = (x.final_greedy_sd.powi(2) / x.runs as f64
        + y.final_greedy_sd.powi(2) / y.runs as f64)
        .sqrt();
    let diff = x.final_greedy - y.final_greedy;
    let text = format!(
        "final greedy return {a} {:.1} ± {:.1}, {b} {:.1} ± {:.1} (difference {diff:.1}, 95 % margin {:.1})",
        x.final_greedy,
        x.final_greedy_sd,
        y.final_greedy,
        y.final_greedy_sd,
        1.96 * se
    );
    if diff > 1.96 * se {
        Ok(text)
    } else {
        Err(text)
    }
}

/// The deepest fall of `c`'s smoothed learning curve below its running maximum between
/// simulated minutes `from` and `to` (the running maximum taken from `from` on).
fn dip(c: &Measured, from: f64, to: f64) -> f64 {
    let mut best = f64::NEG_INFINITY;
    let mut deepest: f64 = 0.0;
    for &(_, v) in c.smoothed.iter().filter(|p| p.0 >= from && p.0 <= to) {
        best = best.max(v);
        deepest = deepest.max(best - v);
    }
    deepest
}

/// §5.5: SAC/RBF's learning curve dips between 10 and 30 simulated minutes (the
/// optimistic initialisation of its RBFs), the LLR learners' less.
fn rbf_dip(m: &[Measured]) -> std::result::Result<String, String> {
    let d = |l: &str| dip(find(m, l), 10.0, 30.0);
    let (rbf, sac, mlac) = (d("SAC/RBF"), d("SAC/LLR"), d("MLAC/LLR"));
    let text = format!(
        "deepest fall below the running maximum between 10 and 30 min: SAC/RBF {rbf:.0}, SAC/LLR {sac:.0}, MLAC/LLR {mlac:.0}"
    );
    if rbf > sac && rbf > mlac {
        Ok(text)
    } else {
        Err(text)
    }
}

/// The opposite of a check.
fn not(r: std::result::Result<String, String>) -> std::result::Result<String, String> {
    match r {
        Ok(t) => Err(t),
        Err(t) => Ok(t),
    }
}

/// `a` reaches the common target ([`common_target`]) of all curves first.
fn fastest(m: &[Measured], a: &str) -> std::result::Result<String, String> {
    let level = common_target(m);
    let best = find(m, a).minutes_to(level);
    let text = format!(
        "to the common level {level:.0}: {}",
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
}

/// How many runs' final policies swing up with how many swings, e.g.
/// `2 swings: 12, 3 swings: 8, never upright: 0`.
fn swing_counts(c: &Measured) -> (BTreeMap<Option<usize>, usize>, String) {
    let mut counts = BTreeMap::new();
    for s in &c.swings {
        *counts.entry(*s).or_insert(0) += 1;
    }
    let text = counts
        .iter()
        .map(|(k, n)| match k {
            Some(1) => format!("1 swing: {n}"),
            Some(k) => format!("{k} swings: {n}"),
            None => format!("never upright: {n}"),
        })
        .collect::<Vec<_>>()
        .join(", ");
    (counts, format!("{} ({text})", c.label))
}

/// A curve with §3.7's input saturation ignored: the actor's outputs unbounded and
/// MLAC's `∇_u f̂` not cut at the bounds (the plant still saturates).
fn saturation_ignored(mut cfg: ExperimentConfig) -> ExperimentConfig {
    cfg.agent.learning.bounded_actor = false;
    cfg.agent.learning.saturation_margin = 0.0;
    cfg
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
            discussion: "Agrees on the final level (all three within a few per cent of each other) and on the learning dips of tile coding and RBFs in the first minute (Figure 3.10); SAC/LLR has no dip, leads for the first two minutes and its rise time matches the thesis's \"about 3 min\", but tile coding reaches the common level just as early, so LLR is \"on top\" only in the early phase.",
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
            discussion: "Agrees: MLAC/LLR converges in less than half MLAC/RBF's time and ends better; ignoring the input saturation ruins MLAC/LLR, as §3.7 warns, while MLAC/RBF is hardly affected (why was not investigated), so the claim holds for LLR only.",
            curves: vec![
                c("MLAC/RBF", preset(Pendulum, Mlac, Rbf, Infinite)),
                c("MLAC/LLR", preset(Pendulum, Mlac, Llr, Infinite)),
                c(
                    "MLAC/RBF, saturation ignored",
                    saturation_ignored(preset(Pendulum, Mlac, Rbf, Infinite)),
                ),
                c(
                    "MLAC/LLR, saturation ignored",
                    saturation_ignored(preset(Pendulum, Mlac, Llr, Infinite)),
                ),
            ],
            thesis: &[
                ("MLAC/RBF", "converges in over 10 min"),
                (
                    "MLAC/LLR",
                    "converges in just over 3 min; maximum after about 2–2.5 min",
                ),
            ],
            claims: vec![
                Claim {
                    says: "LLR is far superior to RBF in learning speed and performance (§3.6.2)",
                    check: |m| {
                        both(
                            faster(m, "MLAC/LLR", "MLAC/RBF"),
                            better(m, "MLAC/LLR", "MLAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "input saturation must be dealt with when learning a process model: simply ignoring it does not produce a well-performing policy (§3.7; ignored = actor outputs unbounded and ∇_u f̂ not cut at the bounds)",
                    check: |m| {
                        both(
                            clearly_better(m, "MLAC/RBF", "MLAC/RBF, saturation ignored"),
                            clearly_better(m, "MLAC/LLR", "MLAC/LLR, saturation ignored"),
                        )
                    },
                },
            ],
        },
        Figure {
            id: "3.22",
            title: "Figure 3.22: RMAC with RBF and LLR (pendulum)",
            discussion: "Agrees: RMAC/LLR is the faster of the two and ends worse, with a much larger spread (a few runs end in a poor policy), as §3.6.3 describes.",
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
            discussion: "Partly agrees: LLR speeds up every algorithm and MLAC/LLR learns fastest of all, but our RBF versions end as well as (SAC) or nearly as well as (MLAC) the LLR ones where the thesis found LLR clearly better at the end, and RMAC/LLR is not faster than SAC/LLR.",
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
                    check: |m| fastest(m, "MLAC/LLR"),
                },
                Claim {
                    says: "with RBFs, MLAC and RMAC do not learn faster than SAC (§3.7)",
                    check: |m| {
                        both(
                            not(faster(m, "MLAC/RBF", "SAC/RBF")),
                            not(faster(m, "RMAC/RBF", "SAC/RBF")),
                        )
                    },
                },
                Claim {
                    says: "the LLR versions of SAC and MLAC end much better than their RBF counterparts (§3.7)",
                    check: |m| {
                        both(
                            better(m, "SAC/LLR", "SAC/RBF"),
                            better(m, "MLAC/LLR", "MLAC/RBF"),
                        )
                    },
                },
                Claim {
                    says: "RMAC/LLR does not reach the best solution; RMAC is the only method that ends better with RBFs (§3.7)",
                    check: |m| {
                        let best = m
                            .iter()
                            .max_by(|a, b| a.final_greedy.total_cmp(&b.final_greedy))
                            .expect("curves");
                        let text = format!(
                            "best final greedy return: {} {:.1}",
                            best.label, best.final_greedy
                        );
                        both(
                            if best.label == "RMAC/LLR" {
                                Err(text)
                            } else {
                                Ok(text)
                            },
                            better(m, "RMAC/RBF", "RMAC/LLR"),
                        )
                    },
                },
            ],
        },
        Figure {
            id: "4.4",
            title: "Figure 4.4: SAC-FH, MLAC-FH and RMAC-FH (pendulum, finite horizon)",
            discussion: "The means are ordered as in Table 4.1 (SAC-FH worst) and MLAC-FH learns fastest, but our spread is larger: the medians are ordered as the thesis's means and close to them, while three or four runs per learner end in a poorer policy (see the worst runs) — runs the thesis's table does not show.",
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
            discussion: "Agrees on the order of learning speed; SAC/RBF ends best by the mean, as the thesis says, but only because one MLAC/LLR run degrades late (its worst run): MLAC/LLR's median run ends better than SAC/RBF's.",
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
                    says: "SAC/RBF's learning dips slightly between 10 and 30 minutes (optimistic initialisation); LLR overcomes this (§5.5)",
                    check: rbf_dip,
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
            discussion: "Agrees on the order of learning speed; in final return MLAC/LLR beats SAC/RBF too (the thesis has it slightly behind): within the 600 trials about half of the SAC/RBF runs have not yet learned to reach the reference (wide spread, poor median), while its best runs end ahead of MLAC/LLR's.",
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
                    says: "SAC/RBF's learning dips slightly between 10 and 30 minutes (optimistic initialisation); LLR overcomes this (§5.5)",
                    check: rbf_dip,
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
            discussion: "Agrees on speed (VGBP-LSTD fastest, VGBP-LLR ahead of MLAC, SARSA last); differs at the end: VGBP-LSTD ends best where the thesis has MLAC best, and every VGBP-LSTD final policy swings up with one swing where the thesis saw two or three — plausibly because our preset chooses the action by a search of Eq. 6.6 over V itself (README, Chapter 6) rather than by Eq. 6.21 alone, whose value gradient §6.5 blames for the variance.",
            curves: vec![
                c("MLAC/LLR", mlac_chapter6()),
                c("VGBP-LLR", preset(Pendulum, Vgbp, Llr, Infinite)),
                c("VGBP-LSTD", preset(Pendulum, Vgbp, Lstd, Infinite)),
                c("SARSA", preset(Pendulum, Sarsa, Rbf, Infinite)),
                c(
                    "VGBP-RBF (TD, per sample)",
                    preset(Pendulum, Vgbp, Rbf, Infinite),
                ),
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
                Claim {
                    says: "VGBP-LSTD achieved the highest learning speed (§6.5)",
                    check: |m| fastest(m, "VGBP-LSTD"),
                },
                Claim {
                    says: "VGBP's final policy is less stable: it needed two or three swings to get the pendulum upright, the other algorithms the same number each time (§6.5; swings of each run's final greedy policy)",
                    check: |m| {
                        let distinct = |label| swing_counts(find(m, label));
                        let (vgbp, v_text) = distinct("VGBP-LSTD");
                        let (mlac, m_text) = distinct("MLAC/LLR");
                        let (sarsa, s_text) = distinct("SARSA");
                        let text = format!("{v_text}; {m_text}; {s_text}");
                        if vgbp.len() > mlac.len().max(sarsa.len()) {
                            Ok(text)
                        } else {
                            Err(text)
                        }
                    },
                },
                Claim {
                    says: "updating the critic at the end of a trial performs better than updating it at each sample (§6.5; checked against VGBP with a per-sample TD(λ) critic on the same RBF grid — a per-sample LSTD was not run)",
                    check: |m| better(m, "VGBP-LSTD", "VGBP-RBF (TD, per sample)"),
                },
            ],
        },
        Figure {
            id: "6.5",
            title: "Figure 6.5: VGBP-LSTD on the 2-DOF manipulator (§6.4.2)",
            discussion: "Agrees qualitatively: VGBP-LSTD takes the extreme actions the thesis describes, leaves the operating range in many early trials and settles within minutes; the thesis gives no numbers to compare the final return with.",
            curves: vec![c("VGBP-LSTD", preset(Arm64, Vgbp, Lstd, Infinite))],
            thesis: &[(
                "VGBP-LSTD",
                "a proper policy in a short time; a low minimum bound from runs leaving the range",
            )],
            claims: vec![
                Claim {
                    says: "VGBP tends to explore unseen states, including bad terminal states (§6.4.2)",
                    check: |m| {
                        let v = &m[0];
                        let text = format!(
                            "{} of {} learning trials left the operating range",
                            v.ended_early,
                            v.runs * v.trials
                        );
                        if v.ended_early > 0 {
                            Ok(text)
                        } else {
                            Err(text)
                        }
                    },
                },
                Claim {
                    says: "where extreme actions are required for large parts of the state space, the maximum action is taken (§6.5; at least half the samples of the final policies at a bound)",
                    check: |m| {
                        let v = &m[0];
                        let text = format!(
                            "{:.0} % of the final greedy policies' samples at an action bound",
                            100.0 * v.at_bound
                        );
                        if v.at_bound >= 0.5 {
                            Ok(text)
                        } else {
                            Err(text)
                        }
                    },
                },
                Claim {
                    says: "VGBP finds a proper policy in a short amount of time (§6.4.2)",
                    check: |m| {
                        let v = &m[0];
                        let text = format!(
                            "final greedy return {:.0} ± {:.0}; rise time t₉₀ {:.1} min",
                            v.final_greedy, v.final_greedy_sd, v.reaches_min
                        );
                        if v.reaches_min < 10.0 {
                            Ok(text)
                        } else {
                            Err(text)
                        }
                    },
                },
            ],
        },
    ]
}

/// The measures of one experiment of `cfg`.
fn measure(label: &str, cfg: &ExperimentConfig, summary: &LearnSummary) -> Result<Measured> {
    let (records, runs, trials) = (
        &summary.records,
        cfg.run.runs as usize,
        cfg.run.trials as usize,
    );
    let task = plant::Task::new(cfg.system);
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
    let finals =
        runtime::learn::final_greedy(records, runs as u32).with_context(|| label.to_string())?;
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
        swings: if cfg.system == SystemName::Pendulum {
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
fn swings(response: &[runtime::experiment::Sample]) -> Option<usize> {
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
        bar: ProgressBar::hidden(),
    };
    let mut results = Vec::new();
    let wanted = |id: &str| opts.only.is_empty() || opts.only.iter().any(|o| o == id);
    for fig in figures() {
        if !wanted(fig.id) {
            continue;
        }
        let spent = runner.spent;
        runner.start(fig.id, fig.curves.iter().map(|c| &c.cfg), None);
        let dir = opts.out.join(fig.id);
        std::fs::create_dir_all(&dir)?;
        let mut measured = Vec::new();
        let mut curves: Vec<Vec<CurvePoint>> = Vec::new();
        let mut responses = Vec::new();
        for curve in &fig.curves {
            let (m, summary) = runner.run(&dir, fig.id, curve.label, &curve.cfg, None)?;
            measured.push(m);
            curves.push(summary.curve);
            responses.push(summary.responses);
        }
        let t_plots = Instant::now();
        let labelled: Vec<(&str, &[runtime::experiment::Sample])> = fig
            .curves
            .iter()
            .zip(&responses)
            .map(|(c, r)| (c.label, &r[0][..]))
            .collect();
        crate::response::plot_responses(
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
            && fig.curves[0].cfg.agent.horizon == HorizonKind::Infinite;
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
        runner.bar.finish_and_clear();
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
    /// The current figure's progress bar (trials of its experiments).
    bar: ProgressBar,
}

impl Runner<'_> {
    /// A progress line: above the bar on a terminal, on stderr otherwise (a log).
    fn say(&self, line: String) {
        match (self.opts.progress, self.bar.is_hidden()) {
            (false, _) => {}
            (true, true) => eprintln!("{line}"),
            (true, false) => self.bar.println(line),
        }
    }

    /// Starts the progress bar of a figure (or of the sensitivity analysis) whose
    /// experiments are `cfgs`, with runs overridden by `runs` if given.
    fn start<'c>(
        &mut self,
        id: &str,
        cfgs: impl IntoIterator<Item = &'c ExperimentConfig>,
        runs: Option<u32>,
    ) {
        let len = cfgs
            .into_iter()
            .map(|c| {
                let c = self.as_run(c, runs);
                u64::from(c.run.runs) * u64::from(c.run.trials)
            })
            .sum();
        self.bar.finish_and_clear();
        self.bar = progress_bar(len, self.opts.progress, id);
    }

    /// `cfg` as it is run: with the options' runs and trials, or `runs` if given.
    fn as_run(&self, cfg: &ExperimentConfig, runs: Option<u32>) -> ExperimentConfig {
        let mut cfg = cfg.clone();
        if let Some(r) = runs.or(self.opts.runs) {
            cfg.run.runs = r;
        }
        if let Some(t) = self.opts.trials {
            cfg.run.trials = t;
        }
        cfg
    }

    /// Runs `cfg` ([`Self::as_run`]) into `dir/<label>`, unless an identical experiment
    /// ran before; returns its measures.
    fn run(
        &mut self,
        dir: &Path,
        id: &str,
        label: &str,
        cfg: &ExperimentConfig,
        runs: Option<u32>,
    ) -> Result<(Measured, LearnSummary)> {
        let cfg = self.as_run(cfg, runs);
        let key = cfg.to_toml();
        let out = dir.join(slug(label));
        if !self.done.contains_key(&key)
            && let Some(s) = load_finished(&out, &cfg)
        {
            self.say(format!(
                "{id} {label}: reusing the finished experiment in {}",
                out.display()
            ));
            self.spent += s.wall;
            self.done.insert(key.clone(), s);
        }
        let summary = match self.done.get(&key) {
            Some(s) => {
                self.bar
                    .inc(u64::from(cfg.run.runs) * u64::from(cfg.run.trials));
                s.clone()
            }
            None => {
                self.say(format!(
                    "{id} {label}: {} runs × {} trials",
                    cfg.run.runs, cfg.run.trials
                ));
                let s = learn(
                    &cfg,
                    &LearnOptions {
                        out: out.clone(),
                        threads: None,
                        progress: Progress::Shared(self.bar.clone()),
                    },
                )?;
                write_atomic(
                    &out.join("wall_s.txt"),
                    &format!("{}\n", s.wall.as_secs_f64()),
                )?;
                write_atomic(&out.join("build.txt"), &format!("{}\n", build_id()))?;
                self.spent += s.wall;
                self.done.insert(key, s.clone());
                s
            }
        };
        let m = measure(label, &cfg, &summary)?;
        Ok((m, summary))
    }
}

/// The identity of this build of `rig`: a hash of its executable (the outputs of an
/// experiment depend on the code as much as on its configuration).
fn build_id() -> &'static str {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        use std::hash::{Hash, Hasher};
        let bytes = std::env::current_exe()
            .and_then(std::fs::read)
            .unwrap_or_default();
        let mut h = std::collections::hash_map::DefaultHasher::new();
        bytes.hash(&mut h);
        format!("{:016x}-{}", h.finish(), bytes.len())
    })
}

/// The outputs of a finished experiment of `cfg` in `dir` (written by an earlier
/// `rig reproduce` of this build: the same `config.toml` and `build.txt`, every row of
/// `runs.csv`, `responses.csv` and `wall_s.txt`), or `None`.
fn load_finished(dir: &Path, cfg: &ExperimentConfig) -> Option<LearnSummary> {
    if std::fs::read_to_string(dir.join("config.toml")).ok()? != cfg.to_toml()
        || std::fs::read_to_string(dir.join("build.txt")).ok()?.trim() != build_id()
    {
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
    let (curve, greedy_curve) = runtime::learn::curves(&records, runs, trials).ok()?;
    let responses = runtime::learn::read_responses(&dir.join("responses.csv"), runs)?;
    Some(LearnSummary {
        records,
        curve,
        greedy_curve,
        wall: Duration::from_secs_f64(wall),
        responses,
        // rig reproduce's experiments use the default sensor and observer (exact).
        acted_on_rmse: Vec::new(),
    })
}

/// The parameters the sensitivity analysis varies, and how.
/// Scales a parameter of a configuration by a factor.
type Scale = fn(&mut ExperimentConfig, f64);

/// `(name, short name for directories, how)` of each parameter.
const PARAMETERS: [(&str, &str, Scale); 5] = [
    ("α_a (actor rate)", "alpha_a", |c, f| {
        if let Some(Component::Llr(l)) = &mut c.agent.actor {
            l.alpha *= f;
        }
    }),
    ("α_c (critic rate)", "alpha_c", |c, f| {
        if let Component::Llr(l) = &mut c.agent.critic {
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
    ("σ (exploration)", "sigma", |c, f| {
        c.agent.learning.sigma *= f
    }),
];

/// Factors applied to each parameter (the preset is factor 1).
pub const FACTORS: [f64; 4] = [0.25, 0.5, 2.0, 4.0];

fn for_each_llr(c: &mut ExperimentConfig, mut f: impl FnMut(&mut agent::config::LlrConfig)) {
    let a = &mut c.agent;
    for comp in [a.actor.as_mut(), Some(&mut a.critic), a.model.as_mut()]
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

/// `base` with a parameter scaled by `f`; `None` where scaling changes nothing (e.g. a
/// rounded K) or makes an invalid configuration.
fn varied(base: &ExperimentConfig, apply: Scale, f: f64) -> Option<ExperimentConfig> {
    let mut cfg = base.clone();
    apply(&mut cfg, f);
    (cfg != *base && cfg.validate().is_ok()).then_some(cfg)
}

fn sensitivity(runner: &mut Runner) -> Result<Sensitivity> {
    use agent::config::{Algo::*, ApproxKind::Llr, HorizonKind::Infinite};
    let spent = runner.spent;
    let runs = runner.opts.runs.unwrap_or(10);
    let dir = runner.opts.out.join("sensitivity");
    let algorithms = [("SAC/LLR", Sac), ("MLAC/LLR", Mlac)];
    let bases = algorithms.map(|(_, algo)| preset(SystemName::Pendulum, algo, Llr, Infinite));
    let experiments: Vec<ExperimentConfig> = bases
        .iter()
        .flat_map(|base| {
            let varied = PARAMETERS
                .iter()
                .flat_map(|&(_, _, apply)| FACTORS.map(|f| varied(base, apply, f)));
            std::iter::once(base.clone()).chain(varied.flatten())
        })
        .collect();
    runner.start("sensitivity", &experiments, Some(runs));
    let mut algos = Vec::new();
    for ((name, _), base) in algorithms.into_iter().zip(&bases) {
        let (at_preset, _) = runner.run(
            &dir,
            "sensitivity",
            &format!("{name} preset"),
            base,
            Some(runs),
        )?;
        let mut params = Vec::new();
        for (param, key, apply) in PARAMETERS {
            let mut row = Vec::new();
            for f in FACTORS {
                let m = match varied(base, apply, f) {
                    Some(cfg) => {
                        let label = format!("{name} {key} x{f}");
                        Some(runner.run(&dir, "sensitivity", &label, &cfg, Some(runs))?.0)
                    }
                    None => None,
                };
                row.push((f, m));
            }
            params.push((param.to_string(), row));
        }
        algos.push((name.to_string(), at_preset, params));
    }
    let mut csv = String::from("algo,parameter,factor,final_greedy_mean,final_greedy_sd,t90_min\n");
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
    let sweeps: Vec<(&str, Vec<crate::sensitivity::Sweep>)> = algos
        .iter()
        .map(|(name, preset, params)| {
            let sweeps = params
                .iter()
                .map(|(param, row)| {
                    let mut points: Vec<(f64, f64, f64)> = row
                        .iter()
                        .filter_map(|(f, m)| {
                            m.as_ref().map(|m| (*f, m.final_greedy, m.reaches_min))
                        })
                        .chain([(1.0, preset.final_greedy, preset.reaches_min)])
                        .collect();
                    points.sort_by(|a, b| a.0.total_cmp(&b.0));
                    crate::sensitivity::Sweep {
                        // The symbol, without the explanation in brackets.
                        parameter: param.split(" (").next().unwrap_or(param),
                        points,
                    }
                })
                .collect();
            (name.as_str(), sweeps)
        })
        .collect();
    crate::sensitivity::plot_sensitivity(
        &dir.join("sensitivity.png"),
        &dir.join("sensitivity.svg"),
        &format!("Sensitivity: final greedy return and t₉₀ ({runs} runs per point)"),
        &sweeps,
    )?;
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
        "curve,runs,trials,final_greedy_mean,final_greedy_sd,final_greedy_median,final_greedy_worst,final_level,t90_min,percent_of_optimal,wall_s\n",
    );
    for c in m {
        let pct = optimum.map_or(String::new(), |o| {
            format!("{:.1}", 100.0 * o / c.final_greedy)
        });
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{:.1}",
            c.label,
            c.runs,
            c.trials,
            c.final_greedy,
            c.final_greedy_sd,
            c.final_greedy_median,
            c.final_greedy_worst,
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
         mean ± sample sd over runs; *median [worst]* = their median and the worst run's; *final level* = the learning curve's (mean over runs of \
         each trial's return, with exploration) mean over the last 10 % of trials; *t₉₀* \
         = rise time: simulated minutes until the learning curve (10-trial moving mean) first \
         covers 90 % of its improvement from the first trial to its final level; *% of \
         optimal* = optimum / final greedy. \"Faster\" in the claims compares the minutes \
         until each curve first covers 90 % of the way from the lowest start level to the \
         lowest final level of the curves compared (so that a curve that stays low does not \
         \"converge\" at once).\n",
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
            "| curve | runs × trials | final greedy | median [worst] | final level | t₉₀ [min] | % of optimal | thesis says |\n|---|---|---|---|---|---|---|---|"
        );
        let pendulum = fig.curves[0].cfg.system == SystemName::Pendulum
            && fig.curves[0].cfg.agent.horizon == HorizonKind::Infinite;
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
                "| {} | {} × {} | {:.1} ± {:.1} | {:.0} [{:.0}] | {:.0} | {:.1} | {} | {} |",
                m.label,
                m.runs,
                m.trials,
                m.final_greedy,
                m.final_greedy_sd,
                m.final_greedy_median,
                m.final_greedy_worst,
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
        let _ = writeln!(
            s,
            "\n*Discussion (written for the committed run, seed 1):* {}\n",
            fig.discussion
        );
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
         evaluations) and, in brackets, the rise time t₉₀ in simulated minutes. Wall time {:.0} s; data in `sensitivity/sensitivity.csv`.\n\n![sensitivity](sensitivity/sensitivity.png)\n",
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

#[cfg(test)]
mod tests {
    use super::*;
    use runtime::experiment::Sample;

    fn response(states: &[(f64, f64)]) -> Vec<Sample> {
        states
            .iter()
            .enumerate()
            .map(|(k, &(phi, omega))| Sample {
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
