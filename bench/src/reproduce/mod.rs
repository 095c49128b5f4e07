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
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use agent::config::HorizonKind;
use indicatif::ProgressBar;
use plant::SystemName;
use plant::config::ConfigError;
use runtime::error::AtFile;

use runtime::config::ExperimentConfig;
use runtime::experiment::TrialRecord;
use runtime::learn::{LearnOptions, LearnSummary, Progress, learn};
use runtime::output::{progress_bar, write_atomic};
use runtime::report::{CurvePoint, Series, SeriesStyle};

mod claims;
mod error;
mod figures;
mod measures;
mod report;
mod sensitivity;

pub use error::ReproduceError;
use figures::figures;
use measures::{Measured, measure};
use report::{write_report, write_summary};
pub use sensitivity::{AlgoSensitivity, FACTORS, Sensitivity};

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
pub fn reproduce(opts: &ReproduceOptions) -> Result<Vec<FigureResult>, ReproduceError> {
    for id in &opts.only {
        if !FIGURES.contains(&id.as_str()) {
            return Err(ReproduceError::NoFigure {
                id: id.clone(),
                figures: FIGURES.join(", "),
            });
        }
    }
    std::fs::create_dir_all(&opts.out).at("cannot create output directory", &opts.out)?;
    let optimum = crate::optimal::pendulum_optimum(&crate::optimal::OptimumOptions {
        grid: 201,
        actions: 61,
    })?
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
        let labelled: Vec<(&str, &[runtime::response::ResponseSample])> = fig
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
            match fig.curves[0].cfg.system() {
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
        let pendulum = fig.curves[0].cfg.system() == SystemName::Pendulum
            && fig.curves[0].cfg.agent().horizon == HorizonKind::Infinite;
        runtime::report::plot_curves(
            &dir.join("figure.png"),
            &dir.join("figure.svg"),
            fig.title,
            &series,
            pendulum.then_some(("optimal (DP)", optimum)),
        )?;
        let claims: Vec<(String, bool, String)> = fig
            .claims
            .iter()
            .map(|c| {
                let v = (c.check)(&measured);
                (c.says.to_string(), v.confirmed, v.why)
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
        let s = sensitivity::sensitivity(&mut runner)?;
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
            // One that cannot be run is refused when it is to run.
            .filter_map(|c| self.as_run(c, runs).ok())
            .map(|c| u64::from(c.run().runs) * u64::from(c.run().trials))
            .sum();
        self.bar.finish_and_clear();
        self.bar = progress_bar(len, self.opts.progress, id);
    }

    /// `cfg` as it is run: with the options' runs and trials, or `runs` if given.
    fn as_run(
        &self,
        cfg: &ExperimentConfig,
        runs: Option<u32>,
    ) -> Result<ExperimentConfig, ConfigError> {
        let mut cfg = cfg.clone();
        cfg.change_run(|run| {
            if let Some(r) = runs.or(self.opts.runs) {
                run.runs = r;
            }
            if let Some(t) = self.opts.trials {
                run.trials = t;
            }
        })?;
        Ok(cfg)
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
    ) -> Result<(Measured, LearnSummary), ReproduceError> {
        let cfg = self.as_run(cfg, runs)?;
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
                    .inc(u64::from(cfg.run().runs) * u64::from(cfg.run().trials));
                s.clone()
            }
            None => {
                self.say(format!(
                    "{id} {label}: {} runs × {} trials",
                    cfg.run().runs,
                    cfg.run().trials
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
    let (runs, trials) = (cfg.run().runs as usize, cfg.run().trials as usize);
    if records.len() != runs * trials {
        return None;
    }
    let (curve, greedy_curve) = runtime::output::runs::curves(&records, runs, trials).ok()?;
    let responses = runtime::output::responses::read_responses(&dir.join("responses.csv"), runs)?;
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
