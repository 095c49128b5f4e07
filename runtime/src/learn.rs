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

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;

use crate::config::ExperimentConfig;
use crate::experiment::{Experiment, Sample, TrialRecord};
use crate::report::{self, CurvePoint, Series, SeriesStyle};

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
    pub responses: Vec<Vec<Sample>>,
    /// Each run's [`crate::experiment::ActedOnError`] RMSE per state component, in run
    /// order (empty for an experiment `rig reproduce` read back instead of running).
    pub acted_on_rmse: Vec<Vec<f64>>,
}

/// Writes `runs.csv` in run order, each row as soon as it can be: the rows of the first
/// unfinished run as its trials end (a study can follow a run trial by trial), those of
/// later runs once every run before them has finished.
struct OrderedWriter<W: Write> {
    /// The run whose rows are written as they come.
    next: u32,
    /// Rows of later runs, and whether each has finished.
    pending: BTreeMap<u32, (Vec<TrialRecord>, bool)>,
    out: W,
}

impl<W: Write> OrderedWriter<W> {
    /// One trial of `run` has ended.
    fn trial(&mut self, run: u32, r: &TrialRecord) -> Result<()> {
        if run == self.next {
            write_row(&mut self.out, r)?;
            self.out.flush()?;
        } else {
            self.pending.entry(run).or_default().0.push(r.clone());
        }
        Ok(())
    }

    /// Every trial of `run` has ended.
    fn finished(&mut self, run: u32) -> Result<()> {
        self.pending.entry(run).or_default().1 = true;
        while self.pending.get(&self.next).is_some_and(|(_, done)| *done) {
            self.pending.remove(&self.next);
            self.next += 1;
            if let Some((rows, _)) = self.pending.get_mut(&self.next) {
                for r in rows.drain(..) {
                    write_row(&mut self.out, &r)?;
                }
            }
        }
        self.out.flush()?;
        Ok(())
    }
}

/// A progress bar of `len` trials on stderr (hidden when `enabled` is false, or when
/// stderr is not a terminal).
pub fn progress_bar(len: u64, enabled: bool, label: &str) -> ProgressBar {
    let target = if enabled {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(len), target);
    let template = format!(
        "{{spinner}} {label} [{{bar:40}}] {{pos}}/{{len}} trials, {{per_sec}}, eta {{eta}}"
    );
    bar.set_style(
        ProgressStyle::with_template(&template)
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar
}

/// The header of `runs.csv`.
pub const RUNS_HEADER: &str = "run,trial,sim_time_s,return,greedy_return";

/// One `runs.csv` row (numbers in Rust's shortest round-trip form).
pub fn write_row(out: &mut impl Write, r: &TrialRecord) -> std::io::Result<()> {
    match r.greedy {
        Some(g) => writeln!(
            out,
            "{},{},{},{},{}",
            r.run, r.trial, r.sim_time_s, r.ret, g
        ),
        None => writeln!(out, "{},{},{},{},", r.run, r.trial, r.sim_time_s, r.ret),
    }
}

/// Writes `text` to `path` atomically (temporary file, then rename).
pub fn write_atomic(path: &Path, text: &str) -> Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path)
        .with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display()))
}

/// Runs every run of `cfg` and writes the outputs.
pub fn learn(cfg: &ExperimentConfig, opts: &LearnOptions) -> Result<LearnSummary> {
    cfg.check_simulated()?;
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create output directory {}", opts.out.display()))?;
    let _folder = crate::lock::FolderLock::acquire(&opts.out)?;
    write_atomic(&opts.out.join("config.toml"), &cfg.to_toml())?;
    let runs_path = opts.out.join("runs.csv");
    let mut out = BufWriter::new(
        File::create(&runs_path)
            .with_context(|| format!("cannot create {}", runs_path.display()))?,
    );
    writeln!(out, "{RUNS_HEADER}")?;
    let writer = Mutex::new(OrderedWriter {
        next: 0,
        pending: BTreeMap::new(),
        out,
    });

    let (runs, trials) = (cfg.run.runs, cfg.run.trials);
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
    let results: Result<Vec<Vec<TrialRecord>>> = pool.install(|| {
        (0..runs)
            .into_par_iter()
            .map(|run| {
                let mut exp = Experiment::new(cfg, run)?;
                let mut records = Vec::with_capacity(trials as usize);
                while let Some(r) = exp.next_trial() {
                    bar.inc(1);
                    writer.lock().expect("writer poisoned").trial(run, &r)?;
                    records.push(r);
                }
                let acted_on = exp.acted_on_error().rmse();
                let response = exp.greedy_trajectory(&x0);
                responses
                    .lock()
                    .expect("responses poisoned")
                    .insert(run, (response, acted_on));
                writer.lock().expect("writer poisoned").finished(run)?;
                Ok(records)
            })
            .collect()
    });
    let records: Vec<TrialRecord> = results?.into_iter().flatten().collect();
    let (responses, acted_on_rmse): (Vec<Vec<Sample>>, Vec<Vec<f64>>) = responses
        .into_inner()
        .expect("responses poisoned")
        .into_values()
        .unzip();
    write_responses(&opts.out.join("responses.csv"), &responses)?;
    if !cfg.observer.is_default() {
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
) -> Result<()> {
    report::write_curve_csv(&out.join("curve.csv"), curve)?;
    let title = format!(
        "{} {}/{} — {} runs",
        cfg.task_name(),
        cfg.agent.algo.as_str().to_uppercase(),
        cfg.agent.approx.as_str().to_uppercase(),
        cfg.run.runs
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
    )
}

/// Writes each run's acted-on error as `run,x_0,...` (shortest round-trip numbers).
fn write_acted_on(path: &Path, rmse: &[Vec<f64>]) -> Result<()> {
    let n = rmse.first().map_or(0, Vec::len);
    let mut text = String::from("run");
    for i in 0..n {
        text += &format!(",x_{i}");
    }
    for (run, r) in rmse.iter().enumerate() {
        text += &format!("\n{run}");
        for v in r {
            text += &format!(",{v}");
        }
    }
    text.push('\n');
    write_atomic(path, &text)
}

/// Writes each run's time response as `run,t,x_0,...,u_0,...,reward` (shortest
/// round-trip numbers).
fn write_responses(path: &Path, responses: &[Vec<Sample>]) -> Result<()> {
    let mut s = String::new();
    if let Some(first) = responses.iter().flatten().next() {
        let cols: Vec<String> = (0..first.x.len())
            .map(|i| format!("x_{i}"))
            .chain((0..first.u.len()).map(|i| format!("u_{i}")))
            .collect();
        s.push_str(&format!("run,t,{},reward\n", cols.join(",")));
    }
    for (run, samples) in responses.iter().enumerate() {
        for p in samples {
            let v: Vec<String> = std::iter::once(p.t)
                .chain(p.x.iter().copied())
                .chain(p.u.iter().copied())
                .chain(std::iter::once(p.reward))
                .map(|v| v.to_string())
                .collect();
            s.push_str(&format!("{run},{}\n", v.join(",")));
        }
    }
    write_atomic(path, &s)
}

/// Reads what `write_responses` wrote for `runs` runs; `None` if the file is missing,
/// malformed or incomplete.
pub fn read_responses(path: &Path, runs: usize) -> Option<Vec<Vec<Sample>>> {
    let mut reader = csv::Reader::from_path(path).ok()?;
    let n = reader
        .headers()
        .ok()?
        .iter()
        .filter(|h| h.starts_with("x_"))
        .count();
    let mut out = vec![Vec::new(); runs];
    for row in reader.records() {
        let row = row.ok()?;
        let run: usize = row.get(0)?.parse().ok()?;
        let v: Vec<f64> = row
            .iter()
            .skip(1)
            .map(|f| f.parse().ok())
            .collect::<Option<_>>()?;
        let last = v.len().checked_sub(1)?;
        out.get_mut(run)?.push(Sample {
            t: v[0],
            x: v.get(1..1 + n)?.to_vec(),
            u: v.get(1 + n..last)?.to_vec(),
            reward: v[last],
        });
    }
    out.iter().all(|r| !r.is_empty()).then_some(out)
}

/// The greedy evaluations a run's final policy is judged by (the thesis's figures end on
/// them): the mean of the last this many.
pub const LAST_EVALUATIONS: usize = 3;

/// Per run, the mean of its last [`LAST_EVALUATIONS`] greedy evaluations.
pub fn final_greedy(records: &[TrialRecord], runs: u32) -> Result<Vec<f64>> {
    (0..runs)
        .map(|run| {
            let g: Vec<f64> = records
                .iter()
                .filter(|r| r.run == run)
                .filter_map(|r| r.greedy)
                .collect();
            let last = &g[g.len().saturating_sub(LAST_EVALUATIONS)..];
            if last.is_empty() {
                return Err(anyhow::anyhow!(
                    "run {run} has no greedy evaluation (more trials than run.eval_every needed)"
                ));
            }
            Ok(last.iter().sum::<f64>() / last.len() as f64)
        })
        .collect()
}

/// Learning and greedy curves from the records of `runs` runs of `trials` trials.
pub fn curves(
    records: &[TrialRecord],
    runs: usize,
    trials: usize,
) -> Result<(Vec<CurvePoint>, Vec<CurvePoint>)> {
    let mut ret = vec![Vec::with_capacity(runs); trials];
    let mut time = vec![0.0; trials];
    let mut greedy: BTreeMap<u32, (f64, Vec<f64>)> = BTreeMap::new();
    for r in records {
        let i = r.trial as usize - 1;
        ret[i].push(r.ret);
        time[i] = r.sim_time_s;
        if let Some(g) = r.greedy {
            greedy
                .entry(r.trial)
                .or_insert_with(|| (r.sim_time_s, Vec::new()))
                .1
                .push(g);
        }
    }
    let trial_numbers: Vec<u32> = (1..=trials as u32).collect();
    let curve = report::curve(&trial_numbers, &time, &ret)?;
    let greedy_curve = if greedy.is_empty() {
        Vec::new()
    } else {
        let t: Vec<u32> = greedy.keys().copied().collect();
        let s: Vec<f64> = greedy.values().map(|v| v.0).collect();
        let v: Vec<Vec<f64>> = greedy.into_values().map(|v| v.1).collect();
        report::curve(&t, &s, &v)?
    };
    Ok((curve, greedy_curve))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(run: u32, trial: u32) -> TrialRecord {
        TrialRecord {
            run,
            trial,
            sim_time_s: f64::from(trial),
            ret: -1.0,
            greedy: None,
        }
    }

    fn rows(w: &OrderedWriter<Vec<u8>>) -> Vec<String> {
        String::from_utf8(w.out.clone())
            .unwrap()
            .lines()
            .map(|l| l[..3].to_string())
            .collect()
    }

    #[test]
    fn the_first_unfinished_run_is_written_as_its_trials_end_and_later_runs_wait() {
        let mut w = OrderedWriter {
            next: 0,
            pending: BTreeMap::new(),
            out: Vec::new(),
        };
        w.trial(1, &record(1, 1)).unwrap();
        w.trial(0, &record(0, 1)).unwrap();
        assert_eq!(rows(&w), ["0,1"], "run 0's row at once, run 1's held back");
        w.trial(2, &record(2, 1)).unwrap();
        w.trial(2, &record(2, 2)).unwrap();
        w.finished(2).unwrap();
        w.trial(0, &record(0, 2)).unwrap();
        assert_eq!(rows(&w), ["0,1", "0,2"]);
        w.finished(0).unwrap();
        assert_eq!(
            rows(&w),
            ["0,1", "0,2", "1,1"],
            "run 1 is now written as it goes"
        );
        w.trial(1, &record(1, 2)).unwrap();
        assert_eq!(rows(&w), ["0,1", "0,2", "1,1", "1,2"]);
        w.finished(1).unwrap();
        assert_eq!(
            rows(&w),
            ["0,1", "0,2", "1,1", "1,2", "2,1", "2,2"],
            "the finished run 2 follows at once, in run order"
        );
        assert!(w.pending.is_empty());
    }
}
