//! `rig learn`: many independent learning experiments of one configuration, in parallel
//! on all cores, written as they finish.
//!
//! Outputs in the output directory:
//!
//! * `config.toml` — the fully resolved configuration (feed it back with `--config` to
//!   repeat the experiment), written first;
//! * `runs.csv` — `run,trial,sim_time_s,return,greedy_return`, one row per learning
//!   trial, in run order, each row as soon as every run before it has finished (the first
//!   unfinished run's rows as its trials end);
//!   `greedy_return` is blank except every `eval_every` trials;
//! * `curve.csv` — `trial,sim_time_s,mean,min,max,ci_low,ci_high` of `return` across
//!   runs (95 % confidence interval of the mean), `greedy_curve.csv` the same for the
//!   greedy evaluations;
//! * `curve.png`, `curve.svg` — the learning curve in the style of the thesis's figures;
//! * `responses.csv` — `run,t,x_0,...,u_0,...,reward`: each run's final greedy policy,
//!   one trial from the task's first start state (typical time responses, and their
//!   spread over runs);
//! * `observer.csv` — `run,x_0,...`: with a sensor or observer other than the default, how
//!   far the states each run's agent acted on in its learning trials were from the truth
//!   (RMSE per state component, [`crate::experiment::ActedOnError`]: the estimate `x̂_k`
//!   in direct timing, the one-step prediction `x̂_{k+1|k}` in predictive timing).
//!
//! Every file is a pure function of the configuration: the same seed gives byte-identical
//! files whatever the number of threads.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::ProgressBar;
use rayon::prelude::*;

use crate::config::ExperimentConfig;
use crate::error::{AtFile, FileError};
use crate::experiment::{Experiment, TrialRecord};
use crate::lock::LockError;
use crate::output::responses::{write_acted_on, write_responses};
use crate::output::runs::{OrderedWriter, RUNS_HEADER, curves};
use crate::output::{progress_bar, write_atomic};
use crate::report::{self, CurveError, CurvePoint, PlotError, Series, SeriesStyle};
use crate::response::ResponseSample;
use plant::config::ConfigError;

/// Why `rig learn` stopped.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    /// The configuration cannot be learned in one process.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The output folder is another command's.
    #[error(transparent)]
    Lock(#[from] LockError),
    /// An output file could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The worker threads could not be started.
    #[error("cannot start the worker threads")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// The learning curves could not be computed or written.
    #[error(transparent)]
    Curve(#[from] CurveError),
    /// The learning curves could not be plotted.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// How to run and where to write.
#[derive(Clone, Debug)]
pub struct LearnOptions {
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Where progress is shown.
    pub progress: Progress,
}

/// Where [`learn`] shows its progress.
#[derive(Clone, Debug)]
pub enum Progress {
    /// Nowhere.
    Hidden,
    /// A bar of its own on the terminal, cleared when done.
    Bar,
    /// Advances a caller's bar by one per trial (e.g. one bar per `rig reproduce`
    /// figure) and leaves it running.
    Shared(ProgressBar),
}

/// What a `learn` call produced.
#[derive(Clone, Debug)]
pub struct LearnSummary {
    /// Every learning trial of every run, in (run, trial) order.
    pub records: Vec<TrialRecord>,
    /// The learning curve (statistics of `return` across runs).
    pub curve: Vec<CurvePoint>,
    /// Statistics of the greedy evaluations across runs.
    pub greedy_curve: Vec<CurvePoint>,
    /// Wall-clock time of the experiments (excluding plots).
    pub wall: Duration,
    /// Each run's final greedy policy: one trial from the task's first start state (the
    /// time responses written to `responses.csv`), in run order.
    pub responses: Vec<Vec<ResponseSample>>,
    /// Each run's [`crate::experiment::ActedOnError`] RMSE per state component, in run
    /// order (empty for an experiment `rig reproduce` read back instead of running).
    pub acted_on_rmse: Vec<Vec<f64>>,
}

/// Runs every run of `cfg` and writes the outputs.
pub fn learn(cfg: &ExperimentConfig, opts: &LearnOptions) -> Result<LearnSummary, LearnError> {
    cfg.check_simulated()?;
    std::fs::create_dir_all(&opts.out).at("cannot create output directory", &opts.out)?;
    let _folder = crate::lock::FolderLock::acquire(&opts.out)?;
    write_atomic(&opts.out.join("config.toml"), &cfg.to_toml())?;
    let runs_path = opts.out.join("runs.csv");
    let mut out = BufWriter::new(File::create(&runs_path).at("cannot create", &runs_path)?);
    writeln!(out, "{RUNS_HEADER}").at("cannot write", &runs_path)?;
    let writer = Mutex::new(OrderedWriter::new(out));

    let (runs, trials) = (cfg.run().runs, cfg.run().trials);
    let bar = match &opts.progress {
        Progress::Shared(bar) => bar.clone(),
        own => progress_bar(
            u64::from(runs) * u64::from(trials),
            matches!(own, Progress::Bar),
            "learning",
        ),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads.unwrap_or(0))
        .build()?;
    let t0 = Instant::now();
    let x0 = cfg.task().initial_states[0].clone();
    let responses = Mutex::new(BTreeMap::new());
    let results: Result<Vec<Vec<TrialRecord>>, LearnError> = pool.install(|| {
        (0..runs)
            .into_par_iter()
            .map(|run| {
                let mut exp = Experiment::new(cfg, run);
                let mut records = Vec::with_capacity(trials as usize);
                while let Some(r) = exp.next_trial() {
                    bar.inc(1);
                    let mut w = writer.lock().expect("writer poisoned");
                    w.trial(run, &r).at("cannot write", &runs_path)?;
                    records.push(r);
                }
                let acted_on = exp.acted_on_error().rmse();
                let response = exp.greedy_trajectory(&x0);
                responses
                    .lock()
                    .expect("responses poisoned")
                    .insert(run, (response, acted_on));
                let mut w = writer.lock().expect("writer poisoned");
                w.finished(run).at("cannot write", &runs_path)?;
                Ok(records)
            })
            .collect()
    });
    let records: Vec<TrialRecord> = results?.into_iter().flatten().collect();
    let (responses, acted_on_rmse): (Vec<Vec<ResponseSample>>, Vec<Vec<f64>>) = responses
        .into_inner()
        .expect("responses poisoned")
        .into_values()
        .unzip();
    write_responses(&opts.out.join("responses.csv"), &responses)?;
    if !cfg.observer().is_default() {
        write_acted_on(&opts.out.join("observer.csv"), &acted_on_rmse)?;
    }
    let wall = t0.elapsed();
    if !matches!(opts.progress, Progress::Shared(_)) {
        bar.finish_and_clear();
    }
    drop(writer);

    let (curve, greedy_curve) = curves(&records, runs as usize, trials as usize)?;
    write_curves(cfg, &opts.out, &curve, &greedy_curve)?;
    Ok(LearnSummary {
        records,
        curve,
        greedy_curve,
        wall,
        responses,
        acted_on_rmse,
    })
}

/// Writes the learning curve (and the greedy one, if evaluated) as `curve.csv`,
/// `greedy_curve.csv` and the plot `curve.png`/`.svg` into `out`.
fn write_curves(
    cfg: &ExperimentConfig,
    out: &Path,
    curve: &[CurvePoint],
    greedy_curve: &[CurvePoint],
) -> Result<(), LearnError> {
    report::write_curve_csv(&out.join("curve.csv"), curve)?;
    let title = format!(
        "{} {}/{} — {} runs",
        cfg.task_name(),
        cfg.agent().algo.as_str().to_uppercase(),
        cfg.agent().approx.as_str().to_uppercase(),
        cfg.run().runs
    );
    let mut series = vec![Series {
        label: "learning (with exploration)".into(),
        points: curve,
        style: SeriesStyle::Band,
    }];
    if !greedy_curve.is_empty() {
        report::write_curve_csv(&out.join("greedy_curve.csv"), greedy_curve)?;
        series.push(Series {
            label: "greedy evaluation (mean)".into(),
            points: greedy_curve,
            style: SeriesStyle::Line,
        });
    }
    report::plot_curves(
        &out.join("curve.png"),
        &out.join("curve.svg"),
        &title,
        &series,
        None,
    )?;
    Ok(())
}
